"""det(FIM)-optimal bearing geometry around a target, with the free rotation, reflection and per-sensor flips chosen
so that the agents are not asked to fly backwards.

Bearings-only sensors at ranges ``r_i`` with noise σ (rad) give the 2-D position Fisher information (Yang & Wang 2019,
eq. 24)::

    F = Σ c_i² (I − M_i M_iᵀ),   c_i = 1 / (σ r_i),   M_i = [cos θ_i, sin θ_i]  (unit vector target → sensor i)

Algorithm 1 (as corrected in :func:`autonomy.metrics.fim.optimal_bearing_geometry`, which is reused here) gives one set
of directions θ_i reaching ``det F = (½ Σ c_i²)²``. ``F`` depends on the θ_i only through 2θ_i, so every

    θ'_i = s θ_i + ψ + π f_i,   s ∈ {+1, −1},  ψ ∈ [0, 2π),  f_i ∈ {0, 1}

is optimal too: a common rotation ψ about the target, a reflection s about a line through it, and a reflection f_i of
single sensors through the target (paper, Proposition 2 and Section IV). Among these the one with the least cost

    J = Σ_i ‖p_i^d − p_i‖² + w_b Σ_i max(0, −(p_i^d − p_i) · v̂_T)²

is chosen, ``p_i^d = p_T + r_i M'_i``: short moves, and a penalty (weight ``w_b``) on moves against the target's
direction of travel, which an agent following a moving target could only make by flying backwards.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from autonomy.metrics.fim import bearing_fim_from_directions, max_det_bearing_fim, optimal_bearing_geometry

__all__ = ["OptimalFormation", "optimal_formation"]


@dataclass(frozen=True, kw_only=True)
class OptimalFormation:
    """Desired geometry of a team around a target.

    Attributes
    ----------
    theta : np.ndarray
        (N,) directions target → agent (rad).
    p_W : np.ndarray
        (N, 2) desired horizontal positions (m).
    ranges : np.ndarray
        (N,) ranges used (m).
    det_fim : float
        ``det F`` of the geometry (1/m⁴).
    det_bound : float
        Largest ``det F`` reachable at these ranges (1/m⁴).
    cost : float
        Selection cost ``J`` of the chosen rotation / reflection (m²).
    """

    theta: np.ndarray
    p_W: np.ndarray
    ranges: np.ndarray
    det_fim: float
    det_bound: float
    cost: float


@lru_cache(maxsize=16)
def _flip_table(n: int) -> np.ndarray:
    """(2**n, n) all 0/1 patterns of per-sensor reflections through the target."""
    table = np.array(list(itertools.product((0.0, 1.0), repeat=n)))
    table.setflags(write=False)
    return table


def optimal_formation(p_target: np.ndarray, v_target: np.ndarray, p_agents: np.ndarray, ranges: np.ndarray,
                      sigma: float, *, backward_weight: float = 10.0, n_rotations: int = 72,
                      min_speed: float = 1e-3) -> OptimalFormation:
    """Optimal directions (Algorithm 1) placed to suit the agents' current positions; see the module docstring.

    Parameters
    ----------
    p_target : np.ndarray
        (2,) target position (m).
    v_target : np.ndarray
        (2,) target velocity (m/s); below ``min_speed`` no direction counts as backwards.
    p_agents : np.ndarray
        (N, 2) current agent positions (m), N >= 2.
    ranges : np.ndarray
        (N,) desired ranges (m), > 0.
    sigma : float
        Bearing noise standard deviation (rad), > 0.
    backward_weight : float
        ``w_b`` (dimensionless), >= 0.
    n_rotations : int
        Number of common rotations ψ tried on a uniform grid over [0, 2π); the best is then refined on a grid
        40 times finer within one coarse step.
    min_speed : float
        Target speed (m/s) under which the backward penalty is off.
    """
    p_t = np.asarray(p_target, dtype=float)[:2]
    v_t = np.asarray(v_target, dtype=float)[:2]
    p = np.asarray(p_agents, dtype=float)[:, :2]
    r = np.asarray(ranges, dtype=float).reshape(-1)
    n = p.shape[0]
    if n < 2 or r.shape != (n,):
        raise ValueError(f"need N >= 2 agents and N ranges, got {p.shape} positions and {r.shape} ranges")
    if not np.all(r > 0):
        raise ValueError(f"ranges must be > 0 m, got {r}")
    if not sigma > 0:
        raise ValueError(f"sigma must be > 0 rad, got {sigma}")
    theta0 = np.arctan2(*optimal_bearing_geometry(p_t, r, sigma).directions.T[::-1])
    speed = float(np.hypot(*v_t))
    u_t = v_t / speed if speed > min_speed else np.zeros(2)
    flips = _flip_table(n)
    signs = np.array([1.0, -1.0])

    def costs(psi: np.ndarray, sign: np.ndarray, flip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # candidate angles (S, R, F, N): reflection × rotation × flip pattern × agent
        th = (sign[:, None, None, None] * theta0 + psi[None, :, None, None] + np.pi * flip[None, None, :, :])
        d = p_t + r[:, None] * np.stack([np.cos(th), np.sin(th)], axis=-1) - p
        back = np.maximum(0.0, -(d @ u_t))
        return np.sum(d**2, axis=(-1, -2)) + backward_weight * np.sum(back**2, axis=-1), th

    step = 2.0 * np.pi / n_rotations
    cost, _ = costs(step * np.arange(n_rotations), signs, flips)
    k_s, k_r, k_f = np.unravel_index(int(np.argmin(cost)), cost.shape)
    # refine the rotation within one coarse step around the best, keeping reflection and flips
    fine = step * k_r + np.linspace(-step, step, 41)
    cost_f, th_f = costs(fine, signs[k_s:k_s + 1], flips[k_f:k_f + 1])
    k = int(np.argmin(cost_f[0, :, 0]))
    best = (float(cost_f[0, k, 0]), th_f[0, k, 0])
    theta = np.mod(best[1], 2.0 * np.pi)
    c2 = 1.0 / (sigma * r) ** 2
    p_d = p_t + r[:, None] * np.stack([np.cos(theta), np.sin(theta)], axis=1)
    return OptimalFormation(theta=theta, p_W=p_d, ranges=r, det_fim=float(np.linalg.det(
        bearing_fim_from_directions(c2, theta))), det_bound=max_det_bearing_fim(c2), cost=best[0])
