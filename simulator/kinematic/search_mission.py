"""Kinematic closed loop of set-membership search: unicycle UAVs, box sensors, estimators, fusion, search MPC.

No physics engine: each step of ``T`` seconds

1. every UAV turns by its control ``u`` (search MPC, or a random turn when ``control="random"``) and advances
   ``V T`` at constant altitude;
2. targets and decoys move (:class:`~autonomy.guidance.search.scenario.GroundMovers`);
3. every UAV scans with its :class:`~autonomy.sensing.box_sensor.BoxSensor` on a
   :class:`~autonomy.sensing.fake_scene.FakeScene` of the obstacles, then predicts and corrects its sets;
4. UAVs linked by an unobstructed line of sight (obstacles are at least as tall as the UAVs fly, so a 2-D
   segment test) fuse their post-correction sets;
5. the guarantee (every true target inside ``X U Xbar`` of every UAV), the areas, the decoys inside ``X`` and the
   distance from each UAV's flown chord to the obstacles are recorded.

UAV starts are uniform free points ``alpha_s1 + 2 alpha_s2`` inside the free area with uniform headings; with
``MissionConfig.safe_starts`` (the default) each start whose state is not safe in the sense of
:mod:`~autonomy.guidance.search.safety` is redrawn (position and heading, from the same generator), so the
planner's safe-loiter constraint (``SearchConfig.loiter_safety``) holds from the first step and no flown chord
comes within ``d_col`` of an obstacle. ``safe_starts=False`` keeps the first draw.

The mission is the harness of the search tests and benchmarks; :class:`MissionResult` carries every figure the
paper reports except run time, which benchmarks measure.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import shapely

from autonomy.estimation.setmem import polygons as pg
from autonomy.estimation.setmem.estimator import SetMembershipConfig, SetMembershipEstimator, free_search_area
from autonomy.fusion.set_team import fuse_team_sets
from autonomy.guidance.search.planner import SearchConfig, SearchPlanner, yaw_quaternion
from autonomy.guidance.search.regions import PrismViewRegion
from autonomy.guidance.search.safety import LoiterSafety
from autonomy.guidance.search.scenario import MoverConfig, random_cuboids, random_free_points, random_movers
from autonomy.sensing.box_sensor import BoxSensor, BoxSensorConfig
from autonomy.sensing.fake_scene import FakeScene
from autonomy.sensing.scene import SensorPose

__all__ = ["MissionConfig", "MissionResult", "SearchMission", "line_of_sight_graph"]


@dataclass(frozen=True, kw_only=True)
class MissionConfig:
    """A search mission (defaults: the paper's section V).

    Attributes
    ----------
    area_size : tuple[float, float]
        Side lengths of the square-ish search area, anchored at the origin (m), > 0.
    n_uavs, n_targets, n_decoys, n_obstacles : int
        Team size (>= 1), true targets, decoys and cuboid obstacles (>= 0).
    obstacle_sides : tuple[float, float]
        Range of the obstacles' side lengths (m).
    obstacle_height : float
        Obstacle height (m), > 0.
    steps : int
        Number of steps, >= 1.
    control : {"mpc", "random"}
        Search MPC, or uniformly random turns in ``[-max_turn, max_turn]`` with a turn back towards the area's
        centre when outside it (for estimator tests and as a baseline).
    search : SearchConfig
        UAV motion and MPC parameters (``dt`` is the mission step).
    estimator : SetMembershipConfig
        Estimator parameters; its ``max_target_speed`` must bound ``movers.speed``.
    movers : MoverConfig
        Target and decoy motion; its ``dt`` must equal ``search.dt``.
    sensor : BoxSensorConfig
        The nadir bounded-error sensor.
    safe_starts : bool
        Redraw UAV starts until their maximum-turn loiters keep ``search.d_col + search.clearance_margin`` from
        the obstacles (module docstring); needed by the planner's safe-loiter induction.
    start_turn : float | None
        Turn bound (rad) of the loiters the safe-start check tests; ``None``: ``search.max_turn``. Pinning it keeps
        the starts of missions that differ only in their planner's turn bound the same.
    """

    area_size: tuple[float, float] = (500.0, 500.0)
    n_uavs: int = 4
    n_targets: int = 2
    n_decoys: int = 2
    n_obstacles: int = 5
    obstacle_sides: tuple[float, float] = (30.0, 70.0)
    obstacle_height: float = 100.0
    steps: int = 400
    control: Literal["mpc", "random"] = "mpc"
    search: SearchConfig = field(default_factory=SearchConfig)
    estimator: SetMembershipConfig = field(default_factory=SetMembershipConfig)
    movers: MoverConfig = field(default_factory=MoverConfig)
    sensor: BoxSensorConfig = field(default_factory=BoxSensorConfig)
    safe_starts: bool = True
    start_turn: float | None = None

    def __post_init__(self) -> None:
        if not all(s > 0 for s in self.area_size):
            raise ValueError(f"MissionConfig.area_size must be positive, got {self.area_size}")
        if self.n_uavs < 1:
            raise ValueError(f"MissionConfig.n_uavs must be >= 1, got {self.n_uavs}")
        for name in ("n_targets", "n_decoys", "n_obstacles"):
            if getattr(self, name) < 0:
                raise ValueError(f"MissionConfig.{name} must be >= 0, got {getattr(self, name)}")
        if self.steps < 1:
            raise ValueError(f"MissionConfig.steps must be >= 1, got {self.steps}")
        if self.control not in ("mpc", "random"):
            raise ValueError(f"MissionConfig.control must be mpc|random, got {self.control!r}")
        if self.movers.speed > self.estimator.max_target_speed:
            raise ValueError(
                f"MissionConfig: movers.speed {self.movers.speed} m/s exceeds the estimator's bound "
                f"{self.estimator.max_target_speed} m/s"
            )
        if self.start_turn is not None and not (0 < self.start_turn <= np.pi):
            raise ValueError(f"MissionConfig.start_turn must be in (0, pi] rad, got {self.start_turn}")
        if abs(self.movers.dt - self.search.dt) > 1e-12:
            raise ValueError(f"MissionConfig: movers.dt {self.movers.dt} s must equal search.dt {self.search.dt} s")


@dataclass(frozen=True, kw_only=True)
class MissionResult:
    """Time series of a mission (row ``k`` is after step ``k + 1``).

    Attributes
    ----------
    area_X, area_Xbar : np.ndarray
        (steps, n_uavs) ``phi(X_i) / phi(X_s)`` and ``phi(Xbar_i) / phi(X_s)`` after fusion (dimensionless).
    guarantee : np.ndarray
        (steps, n_uavs, n_targets) bool: true target ``j`` lies in ``X_i U Xbar_i``.
    decoy_in_X : np.ndarray
        (steps, n_decoys) bool: the decoy lies in the ``X`` of at least one UAV.
    uav_xy : np.ndarray
        (steps + 1, n_uavs, 2) UAV positions (m).
    mover_xy : np.ndarray
        (steps + 1, n_targets + n_decoys, 2) target then decoy positions (m).
    min_obstacle_distance : np.ndarray
        (steps, n_uavs) horizontal distance from the chord each UAV flew during the step (from its previous to its
        new position) to the nearest obstacle (m); ``inf`` without obstacles.
    links : np.ndarray
        (steps,) number of line-of-sight links.
    unsafe_decisions : np.ndarray
        (steps, n_uavs) bool: the search MPC found no candidate with a safe next state and took the one of largest
        clearance (never from a safe start; always False for random turns or without ``loiter_safety``).
    """

    area_X: np.ndarray
    area_Xbar: np.ndarray
    guarantee: np.ndarray
    decoy_in_X: np.ndarray
    uav_xy: np.ndarray
    mover_xy: np.ndarray
    min_obstacle_distance: np.ndarray
    links: np.ndarray
    unsafe_decisions: np.ndarray

    @property
    def guarantee_rate(self) -> float:
        """Fraction of (step, UAV, target) checks where the true target was inside ``X U Xbar``."""
        return float(np.mean(self.guarantee)) if self.guarantee.size else 1.0

    def collisions(self, d_col: float = 0.0) -> int:
        """UAV-steps closer than ``d_col`` m to an obstacle (0: inside a footprint)."""
        return int(np.sum(self.min_obstacle_distance <= d_col))

    def xbar_empty_step(self, threshold: float = 1e-3) -> int | None:
        """First step (1-based) at which the team-mean ``phi(Xbar) / phi(X_s)`` falls below ``threshold``."""
        idx = np.flatnonzero(self.area_Xbar.mean(axis=1) < threshold)
        return int(idx[0]) + 1 if idx.size else None


def line_of_sight_graph(p_xy: np.ndarray, obstacles: shapely.Geometry | None) -> np.ndarray:
    """(N, N) bool adjacency: UAVs ``i != j`` linked when the segment between them crosses no obstacle."""
    P = np.asarray(p_xy, dtype=float).reshape(-1, 2)
    n = len(P)
    A = ~np.eye(n, dtype=bool)
    if obstacles is None or obstacles.is_empty:
        return A
    for i in range(n):
        for j in range(i + 1, n):
            blocked = bool(shapely.intersects(obstacles, shapely.LineString([P[i], P[j]])))
            A[i, j] = A[j, i] = not blocked
    return A


class SearchMission:
    """A random mission built from a seed (module docstring).

    Parameters
    ----------
    config : MissionConfig
        Mission parameters.
    rng : np.random.Generator
        Source of all randomness (scenario, motion, sensor noise, random control) unless one of the three below is
        given.
    motion_rng, noise_rng, control_rng : np.random.Generator | None
        Separate sources of the targets' and decoys' motion, the sensors' noise and the random turns (``None``:
        ``rng``). With its own motion stream the movers follow the same paths whatever the UAVs do, so missions
        that differ only in their control see the same targets (common random numbers).
    """

    def __init__(self, config: MissionConfig, rng: np.random.Generator, *,
                 motion_rng: np.random.Generator | None = None, noise_rng: np.random.Generator | None = None,
                 control_rng: np.random.Generator | None = None):
        self.config = config
        self.rng = rng
        self.motion_rng = rng if motion_rng is None else motion_rng
        self.noise_rng = rng if noise_rng is None else noise_rng
        self.control_rng = rng if control_rng is None else control_rng
        self.last_scans: list = []
        W, H = config.area_size
        self.area = shapely.box(0.0, 0.0, W, H)
        self.buildings = random_cuboids(rng, (0.0, 0.0, W, H), config.n_obstacles, config.obstacle_sides,
                                        config.obstacle_height) if config.n_obstacles else []
        self.free_area = free_search_area(self.area, self.buildings)
        self.obstacles = pg.union_all([shapely.Polygon(b.footprint) for b in self.buildings])
        self.scene = FakeScene(self.buildings)
        self.sensor = BoxSensor(config.sensor, self.buildings)
        self.movers = random_movers(rng, config.movers, self.free_area, config.n_targets, config.n_decoys)
        s = config.search
        margin = min(s.alpha_s1 + 2 * s.alpha_s2, 0.2 * min(W, H))
        self.uav_xy = random_free_points(rng, self.free_area, config.n_uavs, margin=margin)
        self.uav_heading = rng.uniform(-np.pi, np.pi, size=config.n_uavs)
        self.estimators = [SetMembershipEstimator(config.estimator, self.free_area, 0.0, owner=i)
                           for i in range(config.n_uavs)]
        a = (s.altitude - config.sensor.ground_z) * np.tan(config.sensor.opening_angle / 2)
        self.planner = SearchPlanner(s, PrismViewRegion(config.sensor, self.buildings), self.free_area,
                                     self.buildings, footprint_radius=np.sqrt(2) * a)
        if config.safe_starts:
            self._redraw_unsafe_starts(margin)
        self.unsafe = np.zeros(config.n_uavs, dtype=bool)
        self.k = 0

    def _redraw_unsafe_starts(self, margin: float, max_tries: int = 10000) -> None:
        """Redraw each UAV start (position, heading) whose state is not safe (module docstring)."""
        s = self.config.search
        turn = s.max_turn if self.config.start_turn is None else self.config.start_turn
        safety = LoiterSafety(speed=s.speed, dt=s.dt, max_turn=turn, required=s.d_col + s.clearance_margin,
                              obstacles=self.obstacles)
        if not safety.active:
            return
        for i in np.flatnonzero(~safety.is_safe(self.uav_xy, self.uav_heading)):
            for _ in range(max_tries):
                self.uav_xy[i] = random_free_points(self.rng, self.free_area, 1, margin=margin)[0]
                self.uav_heading[i] = self.rng.uniform(-np.pi, np.pi)
                if safety.is_safe(self.uav_xy[i], self.uav_heading[i])[0]:
                    break
            else:
                raise ValueError(f"SearchMission: no safe start for UAV {i} in {max_tries} draws")

    def _controls(self, adjacency: np.ndarray) -> np.ndarray:
        cfg = self.config
        if cfg.control == "random":
            s = cfg.search
            u = self.control_rng.uniform(-s.max_turn, s.max_turn, size=cfg.n_uavs)
            # outside the area, turn back towards its centre as fast as allowed
            centre = np.asarray(self.area.centroid.coords[0])
            outside = ~shapely.contains_xy(self.area, self.uav_xy[:, 0], self.uav_xy[:, 1])
            to_c = centre - self.uav_xy
            err = np.angle(np.exp(1j * (np.arctan2(to_c[:, 1], to_c[:, 0]) - self.uav_heading)))
            return np.where(outside, np.clip(err, -s.max_turn, s.max_turn), u)
        decisions = self.planner.plan_team(self.uav_xy, self.uav_heading, [e.estimate for e in self.estimators],
                                           adjacency)
        self.unsafe = np.array([not d.safe for d in decisions])
        return np.array([d.u for d in decisions])

    def step(self, adjacency: np.ndarray) -> np.ndarray:
        """Run one step with the links of the previous step; returns the new links."""
        s = self.config.search
        u = self._controls(adjacency)
        self.uav_heading = self.uav_heading + u
        self.uav_xy = self.uav_xy + s.speed * s.dt * np.column_stack([np.cos(self.uav_heading),
                                                                       np.sin(self.uav_heading)])
        self.movers.step(self.motion_rng)
        self.k += 1
        t = self.k * s.dt
        truth = self.movers.truth()
        self.last_scans = []
        for i, est in enumerate(self.estimators):
            pose = SensorPose(p_W=np.array([*self.uav_xy[i], s.altitude]), q_WB=yaw_quaternion(self.uav_heading[i]))
            out = self.sensor.measure(t, pose, truth, self.scene, self.noise_rng)
            self.last_scans.append(out)
            est.predict(t)
            est.update(out.extras["observed_region"], out.detections)
        links = line_of_sight_graph(self.uav_xy, self.obstacles)
        fuse_team_sets(self.estimators, links)
        return links

    def run(self, on_step: Callable[[SearchMission], None] | None = None) -> MissionResult:
        """Run all steps and collect the result; ``on_step(self)``, when given, is called after each step (after
        fusion), when ``last_scans`` holds the step's sensor outputs, one per UAV (an observer: it must not change
        the mission)."""
        cfg = self.config
        n, steps = cfg.n_uavs, cfg.steps
        is_target = self.movers.is_target
        aX = np.zeros((steps, n))
        aXb = np.zeros((steps, n))
        guarantee = np.zeros((steps, n, int(is_target.sum())), dtype=bool)
        decoy_in_X = np.zeros((steps, int((~is_target).sum())), dtype=bool)
        uav_xy = [self.uav_xy.copy()]
        mover_xy = [self.movers.p_xy.copy()]
        d_obs = np.full((steps, n), np.inf)
        unsafe = np.zeros((steps, n), dtype=bool)
        links_n = np.zeros(steps, dtype=int)
        links = line_of_sight_graph(self.uav_xy, self.obstacles)
        for k in range(steps):
            before = self.uav_xy.copy()
            links = self.step(links)
            if on_step is not None:
                on_step(self)
            unsafe[k] = self.unsafe
            links_n[k] = int(np.sum(np.triu(links, 1)))
            p = self.movers.p_xy
            for i, est in enumerate(self.estimators):
                e = est.estimate
                aX[k, i], aXb[k, i] = est.normalized_areas()
                guarantee[k, i] = e.contains(p[is_target], cfg.estimator.containment_tol)
                decoy_in_X[k] |= e.in_X(p[~is_target])
            if not self.obstacles.is_empty:
                d_obs[k] = shapely.distance(self.obstacles, shapely.linestrings(np.stack([before, self.uav_xy], 1)))
            uav_xy.append(self.uav_xy.copy())
            mover_xy.append(p.copy())
        return MissionResult(area_X=aX, area_Xbar=aXb, guarantee=guarantee, decoy_in_X=decoy_in_X,
                             uav_xy=np.array(uav_xy), mover_xy=np.array(mover_xy), min_obstacle_distance=d_obs,
                             links=links_n, unsafe_decisions=unsafe)
