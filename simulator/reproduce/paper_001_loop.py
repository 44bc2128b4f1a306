"""Paper 001's kinematic closed loop with the estimation inside it: the planner flies on the UAVs' own estimates.

Each step k (T_s = 1 s), as the paper's section 4.3 orders it:

1. every UAV plans (:class:`TeamInfoPlanner`, sequential search in the MST hierarchy) from its **own** local estimate
   of the target (the paper's UAVs run local EIFs and receive no fused estimate back), and flies its first heading rate
   for one step (exact arcs);
2. the target moves by the paper's model (eq. 4): constant velocity plus white acceleration noise of std
   :data:`TARGET_ACCEL_STD` per axis (δx = δy = 0.1 m/s², section 5.1) for a moving target; a static target (scenarios 2
   and 4, "a single static target") stays where it is;
3. the minimum spanning tree (or the fixed chain) over the new positions gives each UAV's route probability β;
   every UAV measures range and azimuth (δr = 2 m, δθ = 0.05 rad), updates its local filter (an EKF on the CV model,
   the EIF's covariance form) and sends its measurement information ``(i, I)``, linearised at its own prediction; each
   packet arrives with probability β and the base adds those that do to its own prediction (eqs. 23–24).

Random streams (common random numbers): one run seed drives four streams spawned by component — the initial cue, the
target's acceleration noise, the radar noise and the packet draws — never by variant, so the variants of a scenario
meet the same target noise, the same radar noise draws and the same packet uniforms, step for step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from autonomy.estimation.factory import make_filter
from autonomy.estimation.measurements import Measurement
from autonomy.estimation.models import ConstantVelocity
from autonomy.fusion.base_station import BaseStationFusion, information_contribution
from autonomy.guidance.infoplan.config import InfoPlannerConfig
from autonomy.guidance.infoplan.information import (cv_process_noise, cv_transition, predict_information,
                                                    radar_information)
from autonomy.guidance.infoplan.planner import TeamInfoPlanner, arc_paths
from autonomy.guidance.infoplan.routing import (chain_route_probabilities, link_probabilities,
                                                mst_route_probabilities, planning_hierarchy)

__all__ = ["Flight", "LoopResult", "TARGET_ACCEL_STD", "fly", "STREAMS", "static_bound"]

TARGET_ACCEL_STD = 0.1
"""m/s² per axis: the paper's target noise δx = δy (section 5.1), the same as the filters' model."""
STREAMS = {"cue": 0, "target": 1, "radar": 2, "packets": 3}
"""Spawn keys of a run's random streams (by component, never by variant)."""


@dataclass(frozen=True, kw_only=True)
class Flight:
    """Start of a run: target (position, velocity, static or not) and UAVs (positions, courses), for ``steps``."""

    steps: int
    target_p0: tuple[float, float]
    target_v: tuple[float, float]
    uav_p0: tuple[tuple[float, float], ...]
    uav_course0: tuple[float, ...]

    @property
    def static(self) -> bool:
        """A target without velocity is the paper's static target: no acceleration noise either."""
        return not any(self.target_v)


@dataclass(frozen=True, kw_only=True)
class LoopResult:
    """One run (S steps, N UAVs): paths, routes and the estimation's time-averaged figures.

    ``base_err`` / ``uav_err``: mean ‖p̂ − p‖ over the steps (m); ``base_sigma``: mean over the steps of the base
    filter's own √(tr P_pos) (m); ``*_trace``: mean tr(P⁻¹) (the whole 4 × 4 information); ``beta``: mean route
    probability per UAV; ``direct_beta``: mean probability of the direct link to the base along the flown path.
    """

    p_W: np.ndarray
    target_p_W: np.ndarray
    parent: np.ndarray
    base_err: float
    base_err_late: float
    base_sigma: float
    uav_err: np.ndarray
    beta: np.ndarray
    direct_beta: np.ndarray
    base_trace: float
    uav_trace: np.ndarray


def _rng(seed: int, stream: str) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(STREAMS[stream],)))


def _routes(cfg: InfoPlannerConfig, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    base = np.asarray(cfg.base_p_W, float)
    _, parent = planning_hierarchy(base, p, cfg.channel)
    P = link_probabilities(np.vstack([base, p])[None], cfg.channel)
    beta = chain_route_probabilities(P)[0, 1:] if cfg.routing == "chain" else mst_route_probabilities(P)[0][0, 1:]
    return beta, np.asarray(parent)


def fly(cfg: InfoPlannerConfig, flight: Flight, seed: int, settle_s: float = 10.0) -> LoopResult:
    """Fly and estimate one run (module docstring); errors over t ≥ ``settle_s`` go to ``base_err_late``."""
    planner = TeamInfoPlanner(cfg)
    cue, tgt_rng, radar, packets = (_rng(seed, s) for s in ("cue", "target", "radar", "packets"))
    model = ConstantVelocity(q=cfg.target_accel_std**2)
    F, GQG = cv_transition(cfg.dt), cv_process_noise(cfg.dt, cfg.target_accel_std)
    R = np.diag([cfg.sigma_range**2, cfg.sigma_bearing**2])
    sd = np.sqrt(np.diag(R))
    n = len(flight.uav_p0)
    p, chi = np.array(flight.uav_p0, float), np.array(flight.uav_course0, float)
    xt = np.array([*flight.target_p0, *flight.target_v], float)  # layout x, y, vx, vy (the planner's TARGET_CV)
    P0 = np.diag([cfg.prior_position_std**2, cfg.prior_velocity_std**2] * 2)  # the filters' layout x, vx, y, vy
    x0 = np.array([xt[0], xt[2], xt[1], xt[3]]) + np.sqrt(np.diag(P0)) * cue.normal(size=4)
    filters = [make_filter("ekf", model, x0.copy(), P0.copy()) for _ in range(n)]
    base = BaseStationFusion(model, x0.copy(), P0.copy())
    Y_exp = cfg.default_prior_information()
    ps, tps, betas, parents = [p.copy()], [xt[:2].copy()], [], []
    base_err, base_sig, uav_err, base_tr, uav_tr = [], [], [], [], []
    for k in range(flight.steps):
        est_p = np.array([[f.x[0], f.x[2]] for f in filters])
        est_v = np.array([[f.x[1], f.x[3]] for f in filters])
        plan = planner.plan(p, chi, est_p, est_v, Y_exp)
        for i in range(n):
            pi, ci = arc_paths(p[i], chi[i], plan.heading_rates[i:i + 1, :1], cfg.speed, cfg.dt)
            p[i], chi[i] = pi[0, 0], ci[0, 0]
        w = tgt_rng.normal(size=2) * TARGET_ACCEL_STD  # drawn for every flight, so the stream stays aligned
        xt[:2] += xt[2:] * cfg.dt
        if not flight.static:
            xt[:2] += 0.5 * cfg.dt**2 * w
            xt[2:] += cfg.dt * w
        beta, parent = _routes(cfg, p)
        t = (k + 1) * cfg.dt
        noise = radar.normal(size=(n, 2)) * sd
        contributions = []
        for i, f in enumerate(filters):
            d = xt[:2] - p[i]
            z = np.array([np.hypot(d[0], d[1]), np.arctan2(d[1], d[0])]) + noise[i]
            m = Measurement(z=z, R=R, t_meas=t, sensor_id=i, p_sensor_W=np.array([*p[i], 0.0]))
            f.predict(t)
            contributions.append(information_contribution(f.x, m, model.layout))
            f.update(m)
        delivered = packets.uniform(size=n) < beta
        base.fuse(contributions, delivered)
        info = radar_information(xt[:2] - p, cfg.sigma_range, cfg.sigma_bearing)
        Y_exp = predict_information(Y_exp, F, GQG)
        Y_exp[:2, :2] += np.einsum("i,ijk->jk", beta, info)
        Pb = base.P
        base_err.append(np.hypot(base.x[0] - xt[0], base.x[2] - xt[1]))
        base_sig.append(np.sqrt(Pb[0, 0] + Pb[2, 2]))
        base_tr.append(np.trace(base.Y))
        uav_err.append([np.hypot(f.x[0] - xt[0], f.x[2] - xt[1]) for f in filters])
        uav_tr.append([np.trace(np.linalg.inv(f.P)) for f in filters])
        ps.append(p.copy())
        tps.append(xt[:2].copy())
        betas.append(beta)
        parents.append(parent)
    p_W, times = np.array(ps), cfg.dt * np.arange(1, flight.steps + 1)
    late = times >= settle_s
    d = np.linalg.norm(p_W[1:] - np.asarray(cfg.base_p_W, float), axis=-1)
    return LoopResult(p_W=p_W, target_p_W=np.array(tps), parent=np.array(parents),
                      base_err=float(np.mean(base_err)),
                      base_err_late=float(np.mean(np.asarray(base_err)[late])) if late.any() else float("nan"),
                      base_sigma=float(np.mean(base_sig)), uav_err=np.mean(uav_err, axis=0),
                      beta=np.mean(betas, axis=0),
                      direct_beta=np.asarray(cfg.channel.delivery_probability(d), float).mean(axis=0),
                      base_trace=float(np.mean(base_tr)), uav_trace=np.mean(uav_tr, axis=0))


def static_bound(cfg: InfoPlannerConfig, accel_std: float, velocity_known: bool = False, steps: int = 100) -> float:
    """The best a filter of the paper's model can do on a static target: the time-mean of ``√(π/4 · tr P_pos)`` (the
    mean ‖p̂ − p‖ of a circular Gaussian, m) when two UAVs circle the target in quadrature at their smallest turn
    radius v/ω_max, every packet reaches the base and the filter assumes acceleration noise ``accel_std`` (m/s²; 0: a
    filter that does not let it move). Same prior as the runs; ``velocity_known``: the filter also knows the velocity
    is zero (a position-only filter of a static target)."""
    F = cv_transition(cfg.dt)
    GQG = cv_process_noise(cfg.dt, accel_std) if accel_std > 0 else np.zeros((4, 4))
    radius = cfg.speed / cfg.max_heading_rate
    Y = cfg.default_prior_information()
    if velocity_known:
        Y[2:, 2:] = np.eye(2) * 1e12
    out = []
    for k in range(steps):
        Y = predict_information(Y, F, GQG)
        a = (k + 1) * cfg.max_heading_rate * cfg.dt + np.array([0.0, np.pi / 2])
        d = radius * np.column_stack([np.cos(a), np.sin(a)])
        Y[:2, :2] += radar_information(d, cfg.sigma_range, cfg.sigma_bearing).sum(axis=0)
        P = np.linalg.inv(Y)
        out.append(np.sqrt(np.pi / 4.0 * (P[0, 0] + P[1, 1])))
    return float(np.mean(out))
