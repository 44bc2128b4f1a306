"""Closed loop of paper 003 on kinematic agents: bearings-only IMM tracking of a manoeuvring target by a team in an
FIM-optimal formation (or, as the baseline the paper never ran, a formation held fixed).

Each step of ``dt`` seconds

1. the target moves along its scripted manoeuvre (:func:`manoeuvre_truth`: CV, constant acceleration, coordinated
   turns — the paper's cases 1–4);
2. every agent measures the bearing to the target with Gaussian noise σ; the bearings are stacked into one measurement
   for the IMM (the paper's centralised augmented-measurement EKF per mode, :class:`~autonomy.estimation.imm.IMM`);
3. the team decides around the IMM's estimate: Algorithm 1 plus the Jacobi PD law
   (:func:`~autonomy.guidance.formation.guidance.formation_step`); the baselines use the same PD law towards a geometry
   that is not optimised: ``formation="fixed"`` holds the start geometry translated with the estimate, and
   ``formation="trail"`` flies the agents in a narrow fan behind the target (the formation law's ``geometry="trail"``:
   bearings ±``trail_fan`` around the direction opposite to its velocity, at the agents' mean start range), a natural
   follow-the-car formation whose nearly parallel bearing lines are the poor geometry Algorithm 1 avoids. With
   ``ranges`` set, every formation flies those ranges (Algorithm 1 keeps each agent's current range otherwise), so
   formations differ only in their bearings; ``fixed_bearings`` gives the fixed formation other directions than the
   start's (a random geometry, say);
4. each agent flies its commanded velocity for one step (a velocity-tracking plant, as
   :class:`~autonomy.guidance.formation.guidance.FormationGuidance` assumes).

The filter is initialised from the first bearings: the least-squares intersection of the bearing lines for the
position, the target's true initial velocity for the velocity (the paper's agents start with the target's velocity,
so it is known), with a 30 m / 5 m/s standard deviation.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from autonomy.estimation.imm import IMM, cv_ct_imm
from autonomy.estimation.measurements import Measurement, StackedMeasurement
from autonomy.guidance.formation.guidance import FormationConfig, formation_step
from autonomy.guidance.formation.jacobi import jacobi_pd_acceleration
from autonomy.metrics.fim import bearing_fim
from interfaces.state import TargetEstimate

__all__ = ["Segment", "CASES", "FormationLoopConfig", "FormationLoopResult", "manoeuvre_truth", "run_formation_loop"]


@dataclass(frozen=True)
class Segment:
    """A piece of the target's motion: ``duration`` s of turn rate ``omega`` rad/s and acceleration ``accel`` m/s²."""

    duration: float
    omega: float = 0.0
    accel: tuple[float, float] = (0.0, 0.0)


CASES: dict[int, tuple[Segment, ...]] = {
    1: (Segment(30.0),),
    2: (Segment(30.0, accel=(0.25, 0.2)),),
    3: (Segment(30.0, omega=0.25),),
    4: (Segment(3.0), Segment(10.5, omega=0.35), Segment(3.0), Segment(10.5, omega=-0.35), Segment(3.0)),
}
"""The paper's four cases with a car's speeds (module docstring of :mod:`simulator.reproduce.paper_003`)."""


def manoeuvre_truth(segments: tuple[Segment, ...], p0: np.ndarray, v0: np.ndarray, dt: float) -> np.ndarray:
    """(K + 1, 4) states ``(x, vx, y, vy)`` every ``dt`` s, exact per segment (turns by rotation, accelerations
    by the constant-acceleration formulas)."""
    x = np.array([p0[0], v0[0], p0[1], v0[1]], dtype=float)
    out = [x.copy()]
    for seg in segments:
        c, s = np.cos(seg.omega * dt), np.sin(seg.omega * dt)
        for _ in range(int(round(seg.duration / dt))):
            v = np.array([x[1], x[3]])
            if seg.omega != 0.0:
                dp = np.array([s * v[0] - (1 - c) * v[1], (1 - c) * v[0] + s * v[1]]) / seg.omega
                v = np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])
            else:
                a = np.asarray(seg.accel, dtype=float)
                dp = v * dt + 0.5 * a * dt**2
                v = v + a * dt
            x = np.array([x[0] + dp[0], v[0], x[2] + dp[1], v[1]])
            out.append(x.copy())
    return np.array(out)


@dataclass(frozen=True, kw_only=True)
class FormationLoopConfig:
    """A closed-loop run.

    Attributes
    ----------
    case : int
        Target manoeuvre, a key of :data:`CASES`.
    formation : {"optimal", "fixed", "trail"}
        Algorithm 1 around the estimate, the start geometry held (translated with the estimate), or a fan behind
        the target.
    trail_fan : float
        Half-angle of the ``trail`` fan, rad, > 0.
    ranges : tuple of float | None
        Desired range of each agent to the estimate, m, > 0, for every formation (None: ``optimal`` keeps each
        agent's current range, ``fixed`` the start offsets, ``trail`` the mean start range).
    fixed_bearings : tuple of float | None
        Directions target → agent of the ``fixed`` formation, rad (None: the start's); needs ``ranges``.
    max_duration : float | None
        Stop after this many seconds of the case (None: the whole case), s.
    dt : float
        Step, s (bearings, filter and guidance), > 0.
    sigma_bearing : float
        Bearing noise standard deviation, rad, > 0.
    target_p0, target_v0 : tuple of float
        Target start position (m) and velocity (m/s).
    agents_p0 : tuple of (float, float)
        Agent start positions (m); the agents start with the target's velocity.
    q_cv, q_ct : float
        Spectral densities of the IMM's CV and CT models, m²/s³.
    turn_rate : float
        Turn rate of the IMM's two CT models (±), rad/s.
    p_stay : float
        Diagonal of the IMM's mode-transition matrix (the rest spread evenly), in (0, 1).
    guidance : FormationConfig
        Formation law settings (team size, gains, speed limit, ...).
    """

    case: int = 1
    formation: Literal["optimal", "fixed", "trail"] = "optimal"
    trail_fan: float = float(np.deg2rad(15.0))
    ranges: tuple[float, ...] | None = None
    fixed_bearings: tuple[float, ...] | None = None
    max_duration: float | None = None
    dt: float = 0.1
    sigma_bearing: float = 0.1
    target_p0: tuple[float, float] = (75.0, 75.0)
    target_v0: tuple[float, float] = (12.0 * np.cos(np.pi / 4), 12.0 * np.sin(np.pi / 4))
    agents_p0: tuple[tuple[float, float], ...] = ((0.0, 75.0), (75.0, -30.0), (0.0, 0.0))
    q_cv: float = 0.05
    q_ct: float = 0.05
    turn_rate: float = 0.3
    p_stay: float = 0.95
    guidance: FormationConfig = field(default_factory=lambda: FormationConfig(team_size=3, sigma_bearing=0.1,
                                                                               dt=0.1, max_speed=30.0))

    def __post_init__(self) -> None:
        if self.case not in CASES:
            raise ValueError(f"FormationLoopConfig.case must be one of {sorted(CASES)}, got {self.case}")
        if self.formation not in ("optimal", "fixed", "trail"):
            raise ValueError(f"FormationLoopConfig.formation must be optimal|fixed|trail, got {self.formation!r}")
        for name in ("dt", "sigma_bearing", "turn_rate", "trail_fan"):
            if not getattr(self, name) > 0:
                raise ValueError(f"FormationLoopConfig.{name} must be > 0, got {getattr(self, name)}")
        if not 0.0 < self.p_stay < 1.0:
            raise ValueError(f"FormationLoopConfig.p_stay must be in (0, 1), got {self.p_stay}")
        n = self.guidance.team_size
        if self.ranges is not None and (len(self.ranges) != n or not all(np.isfinite(r) and r > 0
                                                                         for r in self.ranges)):
            raise ValueError(f"FormationLoopConfig.ranges must be {n} values > 0 m, got {self.ranges}")
        if self.fixed_bearings is not None and (self.ranges is None or len(self.fixed_bearings) != n):
            raise ValueError(f"FormationLoopConfig.fixed_bearings needs ranges and {n} angles, got "
                             f"{self.fixed_bearings}")
        if len(self.agents_p0) != self.guidance.team_size:
            raise ValueError(f"FormationLoopConfig: {len(self.agents_p0)} agents for a team of "
                             f"{self.guidance.team_size}")


@dataclass(frozen=True, kw_only=True)
class FormationLoopResult:
    """Time series of a run (K steps, N agents).

    Attributes
    ----------
    t : np.ndarray
        (K,) times of the bearings, s.
    truth : np.ndarray
        (K, 4) true target ``(x, vx, y, vy)``.
    estimate : np.ndarray
        (K, 4) IMM estimate after each update.
    error : np.ndarray
        (K,) position error ‖p̂ − p‖, m.
    mode_probability : np.ndarray
        (K, 3) IMM mode probabilities (CV, CT+, CT−).
    agents : np.ndarray
        (K, N, 2) agent positions when measuring, m.
    log_det_fim : np.ndarray
        (K,) ln det F of the bearing FIM of the true geometry (F in m⁻²).
    max_log_det_fim : np.ndarray
        (K,) its upper bound ln (½ Σ c_i²)² for the same ranges.
    """

    t: np.ndarray
    truth: np.ndarray
    estimate: np.ndarray
    error: np.ndarray
    mode_probability: np.ndarray
    agents: np.ndarray
    log_det_fim: np.ndarray
    max_log_det_fim: np.ndarray


def _triangulate(p_agents: np.ndarray, bearings: np.ndarray) -> np.ndarray:
    """Least-squares intersection (2,) m of the bearing lines through ``p_agents`` (N, 2)."""
    n = np.c_[-np.sin(bearings), np.cos(bearings)]  # line normals
    return np.linalg.lstsq(n, np.sum(n * p_agents, axis=1), rcond=None)[0]


def _imm(cfg: FormationLoopConfig, x0: np.ndarray, P0: np.ndarray, t0: float) -> IMM:
    return cv_ct_imm(x0, P0, t0, q_cv=cfg.q_cv, q_ct=cfg.q_ct, turn_rate=cfg.turn_rate, p_stay=cfg.p_stay)


def run_formation_loop(cfg: FormationLoopConfig, rng: np.random.Generator) -> FormationLoopResult:
    """Run ``cfg`` with bearing noise from ``rng``."""
    truth = manoeuvre_truth(CASES[cfg.case], np.array(cfg.target_p0), np.array(cfg.target_v0), cfg.dt)
    if cfg.max_duration is not None:
        truth = truth[:max(2, int(round(cfg.max_duration / cfg.dt)) + 1)]
    n = cfg.guidance.team_size
    p = np.array(cfg.agents_p0, dtype=float)
    v = np.tile(np.array(cfg.target_v0, dtype=float), (n, 1))
    offsets = p - np.array(cfg.target_p0)  # the fixed formation's geometry
    trail_range = float(np.mean(np.linalg.norm(offsets, axis=1)))
    guidance = cfg.guidance if cfg.formation != "trail" else replace(
        cfg.guidance, geometry="trail", ranges=(trail_range,) * n, trail_fan=cfg.trail_fan)
    if cfg.ranges is not None:
        guidance = replace(guidance, ranges=cfg.ranges)
        theta = (np.arctan2(offsets[:, 1], offsets[:, 0]) if cfg.fixed_bearings is None
                 else np.asarray(cfg.fixed_bearings, dtype=float))
        offsets = np.asarray(cfg.ranges)[:, None] * np.c_[np.cos(theta), np.sin(theta)]
    sig = cfg.sigma_bearing
    imm: IMM | None = None
    rows = {k: [] for k in ("t", "x", "err", "mu", "p", "ld", "ldmax")}
    for k in range(1, len(truth)):
        t = k * cfg.dt
        xt = truth[k]
        pt = np.array([xt[0], xt[2]])
        rel = pt - p
        bearings = np.arctan2(rel[:, 1], rel[:, 0]) + sig * rng.normal(size=n)
        if imm is None:
            x0 = np.array([0.0, cfg.target_v0[0], 0.0, cfg.target_v0[1]])
            x0[[0, 2]] = _triangulate(p, bearings)
            imm = _imm(cfg, x0, np.diag([30.0**2, 5.0**2, 30.0**2, 5.0**2]), t)
        else:
            parts = tuple(Measurement(z=np.array([bearings[i]]), R=np.array([[sig**2]]), t_meas=t, kind="bearing",
                                      sensor_id=i, p_sensor_W=np.array([p[i, 0], p[i, 1], 0.0])) for i in range(n))
            imm.update(StackedMeasurement(parts=parts))
        x = imm.x
        F = bearing_fim(pt, p, sig)
        c2 = 1.0 / (sig**2 * np.sum(rel**2, axis=1))
        for key, val in (("t", t), ("x", x.copy()), ("err", float(np.hypot(x[0] - pt[0], x[2] - pt[1]))),
                         ("mu", imm.mu.copy()), ("p", p.copy()), ("ld", float(np.log(np.linalg.det(F)))),
                         ("ldmax", float(2.0 * np.log(0.5 * c2.sum())))):
            rows[key].append(val)
        # the team decides around the estimate and flies one step
        est = TargetEstimate(t=t, p_W=np.array([x[0], x[2]]), v_W=np.array([x[1], x[3]]))
        if cfg.formation != "fixed":
            v_cmd = formation_step(p, v, est, guidance).v_cmd_W
        else:
            g = cfg.guidance
            p_d = est.p_W + offsets
            a = jacobi_pd_acceleration(p, v, p_d, np.broadcast_to(est.v_W, p.shape), g.gains)
            v_cmd = v + a * g.dt
            speed = np.linalg.norm(v_cmd, axis=1, keepdims=True)
            v_cmd = np.where(speed > g.max_speed, v_cmd * (g.max_speed / np.maximum(speed, 1e-12)), v_cmd)
        p = p + v_cmd * cfg.dt
        v = v_cmd
    return FormationLoopResult(t=np.array(rows["t"]), truth=truth[1:], estimate=np.array(rows["x"]),
                               error=np.array(rows["err"]), mode_probability=np.array(rows["mu"]),
                               agents=np.array(rows["p"]), log_det_fim=np.array(rows["ld"]),
                               max_log_det_fim=np.array(rows["ldmax"]))
