"""Closed loop of the information planner on kinematic UAVs with a lossy relay network to a base station.

Each step k (T_s apart): the team plans from the UAVs' states, the target estimate (the true constant-velocity target,
so that the comparison isolates the guidance) and the base station's current information; every UAV flies its first
heading rate for one step (exact arcs); then every UAV measures the target and sends its information along its route
(the minimum spanning tree over the new positions; the fixed chain for the ``"chain"`` routing). The base station
keeps two information matrices (layout ``TARGET_CV``)::

    expected:  Y⁺ = (F Y⁻¹ Fᵀ + G Q Gᵀ)⁻¹ + Σ_i β_i I_i
    realised:  Y⁺ = (F Y⁻¹ Fᵀ + G Q Gᵀ)⁻¹ + Σ_i ξ_i I_i,   ξ_i ~ Bernoulli(β_i) drawn from the injected generator

(Liu, Fu & Gao 2018, eq. 28 and the base-station fusion of §3).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from autonomy.guidance.infoplan.config import InfoPlannerConfig
from autonomy.guidance.infoplan.information import (cv_process_noise, cv_transition, predict_information,
                                                    radar_information)
from autonomy.guidance.infoplan.planner import TeamInfoPlanner, arc_paths
from autonomy.guidance.infoplan.routing import (chain_route_probabilities, link_probabilities,
                                                mst_route_probabilities, planning_hierarchy)

__all__ = ["InfoLoopConfig", "InfoLoopResult", "run_info_loop", "fuse_at_base"]


@dataclass(frozen=True, kw_only=True)
class InfoLoopConfig:
    """Scenario of a closed-loop run (defaults: scenario 1 of the paper).

    Attributes
    ----------
    steps : int
        Number of planning steps, >= 1.
    target_p0 : tuple[float, float]
        Target position at t = 0 (m).
    target_v : tuple[float, float]
        Constant target velocity (m/s).
    uav_p0 : tuple[tuple[float, float], ...]
        Initial UAV positions (m).
    uav_course0 : tuple[float, ...]
        Initial UAV courses (rad).
    """

    steps: int = 100
    target_p0: tuple[float, float] = (-800.0, 0.0)
    target_v: tuple[float, float] = (10.0 * np.cos(np.deg2rad(-20.0)), 10.0 * np.sin(np.deg2rad(-20.0)))
    uav_p0: tuple[tuple[float, float], ...] = ((-400.0, -700.0), (-800.0, 200.0))
    uav_course0: tuple[float, ...] = (float(np.deg2rad(45.0)), 0.0)

    def __post_init__(self) -> None:
        if int(self.steps) != self.steps or self.steps < 1:
            raise ValueError(f"InfoLoopConfig.steps must be an integer >= 1, got {self.steps}")
        if len(self.uav_p0) != len(self.uav_course0) or len(self.uav_p0) < 1:
            raise ValueError(f"InfoLoopConfig needs one course per UAV, got {len(self.uav_p0)} positions and "
                             f"{len(self.uav_course0)} courses")


@dataclass(frozen=True, kw_only=True)
class InfoLoopResult:
    """Time series of a run (S steps, N UAVs).

    Attributes
    ----------
    t : np.ndarray
        (S+1,) times (s).
    p_W : np.ndarray
        (S+1, N, 2) UAV positions (m).
    target_p_W : np.ndarray
        (S+1, 2) target positions (m).
    beta : np.ndarray
        (S, N) route probabilities of the packets sent after each step.
    parent : np.ndarray
        (S, N) next hop of each UAV in the minimum spanning tree after each step (UAV index, -1 base, -2 cut off).
    delivered : np.ndarray
        (S, N) whether each packet reached the base.
    information : np.ndarray
        (S, N, 2, 2) position-block information of each UAV's measurement after each step (1/m²).
    trace_expected : np.ndarray
        (S,) tr Y of the base's expected information after each step.
    trace_realised : np.ndarray
        (S,) tr Y of the base's realised information.
    position_std_realised : np.ndarray
        (S,) √(tr of the position block of Y⁻¹) of the realised information (m).
    """

    t: np.ndarray
    p_W: np.ndarray
    target_p_W: np.ndarray
    beta: np.ndarray
    parent: np.ndarray
    delivered: np.ndarray
    information: np.ndarray
    trace_expected: np.ndarray
    trace_realised: np.ndarray
    position_std_realised: np.ndarray


def run_info_loop(planner_config: InfoPlannerConfig, loop: InfoLoopConfig, rng: np.random.Generator) -> InfoLoopResult:
    """Fly the team of ``loop`` with :class:`TeamInfoPlanner` for ``loop.steps`` steps (module docstring)."""
    cfg = planner_config
    planner = TeamInfoPlanner(cfg)
    F, GQG = cv_transition(cfg.dt), cv_process_noise(cfg.dt, cfg.target_accel_std)
    base = np.asarray(cfg.base_p_W, float)
    p = np.array(loop.uav_p0, float)
    chi = np.array(loop.uav_course0, float)
    n = p.shape[0]
    p0, vt = np.asarray(loop.target_p0, float), np.asarray(loop.target_v, float)
    Y_exp = cfg.default_prior_information()
    ps, tps = [p.copy()], [p0.copy()]
    betas, parents, infos = [], [], []
    for k in range(loop.steps):
        p_t = p0 + vt * k * cfg.dt
        plan = planner.plan(p, chi, p_t, vt, Y_exp)
        new_p, new_c = [], []
        for i in range(n):
            pi, ci = arc_paths(p[i], chi[i], plan.heading_rates[i:i + 1, :1], cfg.speed, cfg.dt)
            new_p.append(pi[0, 0])
            new_c.append(ci[0, 0])
        p, chi = np.array(new_p), np.array(new_c)
        p_t1 = p0 + vt * (k + 1) * cfg.dt
        _, parent = planning_hierarchy(base, p, cfg.channel)
        P = link_probabilities(np.vstack([base, p])[None], cfg.channel)
        if cfg.routing == "chain":
            beta = chain_route_probabilities(P)[0, 1:]
        else:
            beta = mst_route_probabilities(P)[0][0, 1:]
        info = radar_information(p_t1 - p, cfg.sigma_range, cfg.sigma_bearing)
        Y_exp = predict_information(Y_exp, F, GQG)
        Y_exp[:2, :2] += np.einsum("i,ijk->jk", beta, info)
        ps.append(p.copy())
        tps.append(p_t1)
        betas.append(beta)
        parents.append(parent)
        infos.append(info)
    beta, info = np.array(betas), np.array(infos)
    delivered = rng.uniform(size=beta.shape) < beta
    Y_e = fuse_at_base(info, beta, cfg)
    Y_r = fuse_at_base(info, delivered.astype(float), cfg)
    return InfoLoopResult(t=cfg.dt * np.arange(loop.steps + 1), p_W=np.array(ps), target_p_W=np.array(tps),
                          beta=beta, parent=np.array(parents), delivered=delivered, information=info,
                          trace_expected=np.trace(Y_e, axis1=1, axis2=2),
                          trace_realised=np.trace(Y_r, axis1=1, axis2=2),
                          position_std_realised=np.sqrt(np.trace(np.linalg.inv(Y_r)[:, :2, :2], axis1=1, axis2=2)))


def fuse_at_base(information: np.ndarray, weights: np.ndarray, config: InfoPlannerConfig,
                 Y0: np.ndarray | None = None) -> np.ndarray:
    """Base-station information (S, 4, 4) from the UAVs' information (S, N, 2, 2) weighted by ``weights`` (S, N).

    Weights β give the expected recursion, 0/1 delivery indicators the realised one; the prior ``Y0`` defaults to
    ``config.default_prior_information()``. Leading batch axes of ``weights`` (..., S, N) give (..., S, 4, 4).
    """
    F, GQG = cv_transition(config.dt), cv_process_noise(config.dt, config.target_accel_std)
    w = np.asarray(weights, float)
    Y = np.broadcast_to(config.default_prior_information() if Y0 is None else Y0, w.shape[:-2] + (4, 4))
    out = np.empty(w.shape[:-1] + (4, 4))
    for k in range(w.shape[-2]):
        Y = predict_information(Y, F, GQG).copy()
        Y[..., :2, :2] += np.einsum("...i,ijk->...jk", w[..., k, :], information[k])
        out[..., k, :, :] = Y
    return out
