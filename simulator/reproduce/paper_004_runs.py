"""Paper 004's kinematic missions: the configurations flown, one run of each, and its summary.

Every configuration flies the same evaluation seeds (:meth:`ReproContext.run_seeds`). A run's seed is split into four
streams — the world (obstacles, targets' and decoys' starts and cones, UAV starts), the movers' motion, the sensors'
noise and the random turns — so the targets and decoys follow the same paths in every configuration, whatever the UAVs
do, and no configuration enters a run's random stream (common random numbers). The UAV starts are drawn until their
±45° loiters clear the obstacles in every configuration (``MissionConfig.start_turn`` pinned), so a configuration with
another turn bound starts from the same states.

The paper's configuration (:data:`PRIMARY`) reads the sensor's π/4 opening as the full angle of the field of view
(82.8 m footprint at 100 m, the paper's own reading: see the report's deviations) and flies the paper's planner: its
cost (19)–(22) with its weights, no safe-loiter constraint. The others (:data:`VARIANTS`) change one thing each and
fly the first :data:`SENS_RUNS` seeds.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from autonomy.guidance.search.planner import SearchConfig
from autonomy.sensing.box_sensor import BoxSensorConfig
from simulator.kinematic.search_mission import MissionConfig, SearchMission
from simulator.reproduce.paper_004_decoys import DecoyEpisodes, DecoyProvenance

__all__ = ["D_COL", "PRIMARY", "QUICK", "RunSummary", "SENS_RUNS", "VARIANTS", "Variant", "footprint_side",
           "mission_config", "run_one"]

D_COL = 5.0  # m, the paper's collision distance
QUICK = {"steps": 20, "n_uavs": 2}
SENS_RUNS = 10
"""Runs of each configuration other than the paper's (its first seeds): the paper ran 100 missions of its own
configuration only; these are sensitivity studies, paired with the paper's configuration on the same seeds."""
START_TURN = np.pi / 4  # rad, the loiter turn of the safe-start check, the same in every configuration
REGROW_EVERY = 20  # steps between samples of X̄'s regrowth


@dataclass(frozen=True, kw_only=True)
class Variant:
    """One configuration of the mission: what differs from the paper's."""

    name: str
    label: str
    control: str = "mpc"
    opening: float = np.pi / 4
    max_turn: float = np.pi / 4
    n_controls: int = 7
    component_choice: str = "near_large"
    loiter_safety: bool = False


PRIMARY = Variant(name="paper", label="paper's configuration (full angle π/4, 82.8 m)")
VARIANTS: tuple[Variant, ...] = (
    PRIMARY,
    Variant(name="random", label="random turns (baseline)", control="random"),
    Variant(name="half", label="half-angle reading π/4 (200 m footprint)", opening=np.pi / 2),
    Variant(name="safe", label="+ safe-loiter constraint (ours)", loiter_safety=True),
    Variant(name="turn90", label="turn bound ±90° (7 turns, 30° apart)", max_turn=np.pi / 2),
    Variant(name="turn180", label="turn unbounded ±180° (13 turns, 30° apart)", max_turn=np.pi, n_controls=13),
    Variant(name="fine", label="finer grid (15 turns in ±45°)", n_controls=15),
    Variant(name="jd_paper", label="J_d on argmin φ·d (the paper's formula)", component_choice="paper"),
)


def mission_config(v: Variant, quick: bool) -> MissionConfig:
    """The mission of configuration ``v`` (the paper's section V; quick: 20 steps, 2 UAVs)."""
    search = replace(SearchConfig(), max_turn=v.max_turn, n_controls=v.n_controls,
                     component_choice=v.component_choice, loiter_safety=v.loiter_safety)
    return MissionConfig(control=v.control, search=search, sensor=BoxSensorConfig(opening_angle=v.opening),
                         start_turn=START_TURN, **(QUICK if quick else {}))


def footprint_side(cfg: MissionConfig) -> float:
    """Side (m) of the box sensor's square ground footprint at the mission's altitude."""
    return 2.0 * (cfg.search.altitude - cfg.sensor.ground_z) * np.tan(cfg.sensor.opening_angle / 2.0)


@dataclass(frozen=True, kw_only=True)
class RunSummary:
    """What the findings need of one mission.

    Attributes
    ----------
    xbar, x : np.ndarray
        (steps,) team-mean ``φ(X̄)/φ(X_s)`` and ``φ(X)/φ(X_s)`` after each step.
    guarantee : float
        Fraction of (step, UAV, target) checks with the true target inside ``X ∪ X̄``.
    min_obs : float
        Closest approach of a flown chord to an obstacle (m).
    close_steps : int
        UAV-steps whose chord passes within ``D_COL`` of an obstacle.
    unsafe : int
        MPC decisions without a safe candidate (safe-loiter configuration only).
    cpu_s : float
        Process CPU time of the mission (s).
    decoys : DecoyEpisodes
        Decoy-born subsets of ``X`` and their erasure (:mod:`simulator.reproduce.paper_004_decoys`).
    decoy_steps : int
        Steps with a decoy's position inside some UAV's ``X`` (for the table only: chance membership counts too).
    regrowth : float
        Mean growth of UAV 0's ``X̄`` by one prediction, ``φ((X̄ ⊕ B(v_max T)) ∩ X_s) − φ(X̄)`` per step (m²/s),
        sampled every :data:`REGROW_EVERY` steps while ``X̄`` is not empty.
    """

    xbar: np.ndarray
    x: np.ndarray
    guarantee: float
    min_obs: float
    close_steps: int
    unsafe: int
    cpu_s: float
    decoys: DecoyEpisodes
    decoy_steps: int = 0
    regrowth: float = float("nan")

    def at(self, what: str, step: int) -> float:
        """``xbar`` or ``x`` after step ``step`` (1-based); NaN when the mission is shorter."""
        a = getattr(self, what)
        return float(a[step - 1]) if len(a) >= step else float("nan")


def _streams(seed: int) -> list[np.random.Generator]:
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(4)]


def run_one(args: tuple[str, int, bool]) -> RunSummary:
    """One mission of the configuration named ``args[0]`` from seed ``args[1]`` (quick: ``args[2]``)."""
    name, seed, quick = args
    v = next(v for v in VARIANTS if v.name == name)
    cfg = mission_config(v, quick)
    t0 = time.process_time()
    world, motion, noise, control = _streams(seed)
    mission = SearchMission(cfg, world, motion_rng=motion, noise_rng=noise, control_rng=control)
    r = cfg.estimator.max_target_speed * cfg.search.dt
    tracker = DecoyProvenance(steps=cfg.steps, radius=r)
    regrowth: list[float] = []

    def on_step(m: SearchMission) -> None:
        tracker.observe(m)
        if m.k % REGROW_EVERY == 0:
            from autonomy.estimation.setmem import polygons as pg

            est = m.estimators[0]
            Xb = est.estimate.Xbar
            if not Xb.is_empty:
                grown = pg.intersection_all([pg.dilate(Xb, r, cfg.estimator.quad_segs), est.free_area])
                regrowth.append((pg.area(grown) - pg.area(Xb)) / cfg.search.dt)

    res = mission.run(on_step=on_step)
    return RunSummary(
        xbar=res.area_Xbar.mean(axis=1), x=res.area_X.mean(axis=1), guarantee=res.guarantee_rate,
        min_obs=float(res.min_obstacle_distance.min()), close_steps=res.collisions(D_COL),
        unsafe=int(res.unsafe_decisions.sum()), cpu_s=time.process_time() - t0, decoys=tracker.result(),
        decoy_steps=int(res.decoy_in_X.any(axis=1).sum()) if res.decoy_in_X.size else 0,
        regrowth=float(np.mean(regrowth)) if regrowth else float("nan"))
