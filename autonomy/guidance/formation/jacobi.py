"""Jacobi coordinates of a formation and the PD law that drives shape and centre separately (Yang & Wang 2019, §V).

For N agents at p_1 … p_N the Jacobi transform Φ (N × N) maps positions to shape vectors and the centre::

    [ρ_1, …, ρ_{N−1}, q_c]ᵀ = Φ [p_1, …, p_N]ᵀ
    ρ_k = √(k / (k+1)) · (p_{N−k} − mean(p_{N−k+1}, …, p_N)),   q_c = mean(p_1, …, p_N)

which for N = 3 is the paper's ρ_1 = (p_2 − p_3)/√2, ρ_2 = (2p_1 − p_2 − p_3)/√6 (eq. 39). The shape rows are
orthonormal and orthogonal to the centre row, so a common translation leaves every ρ_k unchanged. The agents are
double integrators p̈_i = u_i, hence ρ̈_k and q̈_c are driven independently by::

    ü_ρk = −k_p^ρ (ρ_k − ρ_k^d) − k_d^ρ (ρ̇_k − ρ̇_k^d)
    ü_c  = a_T − k_p^c (q_c − q_c^d) − k_d^c (q̇_c − q̇_c^d)

and mapped back with the *inverse* transform u = Φ⁻¹ [ü_ρ1, …, ü_c] (the paper prints Φ in eq. 42, which is wrong;
it also damps on q̇_cd instead of the velocity error in eq. 41). a_T is the target's estimated acceleration
(feed-forward; zero for a constant-velocity estimate).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = ["JacobiGains", "jacobi_matrix", "jacobi_pd_acceleration"]


@dataclass(frozen=True, kw_only=True)
class JacobiGains:
    """PD gains of the formation controller.

    Attributes
    ----------
    kp_shape : float
        Stiffness on the Jacobi shape vectors (1/s²), > 0.
    kd_shape : float
        Damping on the shape-vector rates (1/s), > 0.
    kp_center : float
        Stiffness on the formation centre (1/s²), > 0.
    kd_center : float
        Damping on the centre velocity error (1/s), > 0.
    """

    kp_shape: float = 0.25
    kd_shape: float = 1.0
    kp_center: float = 0.25
    kd_center: float = 1.0

    def __post_init__(self) -> None:
        for name in ("kp_shape", "kd_shape", "kp_center", "kd_center"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"JacobiGains.{name} must be > 0, got {v}")


@lru_cache(maxsize=16)
def _jacobi(n: int) -> tuple[np.ndarray, np.ndarray]:
    phi = np.zeros((n, n))
    for k in range(1, n):
        row = phi[k - 1]
        row[n - k - 1] = 1.0
        row[n - k:] = -1.0 / k
        row *= np.sqrt(k / (k + 1.0))
    phi[n - 1] = 1.0 / n
    phi.setflags(write=False)
    inv = np.linalg.inv(phi)
    inv.setflags(write=False)
    return phi, inv


def jacobi_matrix(n: int) -> np.ndarray:
    """Jacobi transform Φ (N × N) for N >= 2 agents: rows ρ_1 … ρ_{N−1} then q_c (module docstring)."""
    if int(n) != n or n < 2:
        raise ValueError(f"a formation needs n >= 2 agents, got {n}")
    return _jacobi(int(n))[0]


def jacobi_pd_acceleration(p_W: np.ndarray, v_W: np.ndarray, p_d_W: np.ndarray, v_d_W: np.ndarray,
                           gains: JacobiGains, a_ff_W: np.ndarray | None = None) -> np.ndarray:
    """Accelerations (N, 2) (m/s²) of the Jacobi PD law.

    Parameters
    ----------
    p_W, v_W : np.ndarray
        (N, 2) agent positions (m) and velocities (m/s).
    p_d_W, v_d_W : np.ndarray
        (N, 2) desired positions (m) and velocities (m/s) (for a formation riding on the target, v_d = v_T for all).
    gains : JacobiGains
        PD gains.
    a_ff_W : np.ndarray | None
        (2,) feed-forward acceleration of the centre (m/s²), e.g. the target's estimated acceleration.
    """
    p, v = np.asarray(p_W, float), np.asarray(v_W, float)
    n = p.shape[0]
    phi, inv = _jacobi(n)
    e = phi @ (p - np.asarray(p_d_W, float))
    de = phi @ (v - np.asarray(v_d_W, float))
    u = np.empty_like(e)
    u[:-1] = -gains.kp_shape * e[:-1] - gains.kd_shape * de[:-1]
    u[-1] = -gains.kp_center * e[-1] - gains.kd_center * de[-1]
    if a_ff_W is not None:
        u[-1] += np.asarray(a_ff_W, float)[:2]
    return inv @ u
