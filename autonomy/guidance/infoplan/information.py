"""Fisher information of range/azimuth radar measurements of a constant-velocity target, and its prediction.

Target state layout ``TARGET_CV = ("x", "y", "vx", "vy")`` (m, m, m/s, m/s), the layout of
:class:`~interfaces.state.TargetEstimate` ``P``. Constant-velocity model over a step T (Liu, Fu & Gao 2018,
eq. 4, with the corrupt printed G repaired)::

    F = [[I, T I], [0, I]],   G Q Gᵀ = [[T⁴/4 S, T³/2 S], [T³/2 S, T² S]],   S = diag(δx², δy²)

A radar at horizontal offset d = p_T − p_U (range r = ‖d‖) measuring range and azimuth with noise (δr, δθ) contributes
the information (eq. 29)::

    I = Hᵀ R⁻¹ H = (1/δr²) u uᵀ + (1/(δθ² r²)) n nᵀ   in the position block,   u = d/r,  n ⊥ u

so ``tr I = 1/δr² + 1/(δθ r)²``. The predicted information (eq. 28) follows the information-filter recursion
``Y_{l} = (F Y_{l−1}⁻¹ Fᵀ + G Q Gᵀ)⁻¹ + Σ_i β_i I_i``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["TARGET_CV", "cv_transition", "cv_process_noise", "radar_information", "predict_information"]

TARGET_CV = ("x", "y", "vx", "vy")


def cv_transition(T: float) -> np.ndarray:
    """F (4 × 4) of the constant-velocity model over ``T`` (s), layout ``TARGET_CV``."""
    F = np.eye(4)
    F[0, 2] = F[1, 3] = T
    return F


def cv_process_noise(T: float, accel_std: float) -> np.ndarray:
    """G Q Gᵀ (4 × 4) for white acceleration noise of std ``accel_std`` (m/s²) per axis over ``T`` (s)."""
    q = accel_std**2
    Q = np.zeros((4, 4))
    Q[0, 0] = Q[1, 1] = q * T**4 / 4.0
    Q[2, 2] = Q[3, 3] = q * T**2
    Q[0, 2] = Q[2, 0] = Q[1, 3] = Q[3, 1] = q * T**3 / 2.0
    return Q


def radar_information(d_W: np.ndarray, sigma_range: float, sigma_bearing: float,
                      min_range: float = 1.0) -> np.ndarray:
    """Position-block information (..., 2, 2) (1/m²) of range/azimuth measurements at offsets ``d_W`` (..., 2) (m).

    ``d_W`` is the horizontal vector UAV → target; ranges below ``min_range`` (m) are clipped.
    """
    d = np.asarray(d_W, dtype=float)
    r = np.maximum(np.linalg.norm(d, axis=-1), min_range)
    u = d / r[..., None]
    n = np.stack([-u[..., 1], u[..., 0]], axis=-1)
    a = 1.0 / sigma_range**2
    b = 1.0 / (sigma_bearing * r) ** 2
    return a * u[..., :, None] * u[..., None, :] + b[..., None, None] * n[..., :, None] * n[..., None, :]


def predict_information(Y: np.ndarray, F: np.ndarray, GQG: np.ndarray) -> np.ndarray:
    """Prior information one step ahead, (F Y⁻¹ Fᵀ + G Q Gᵀ)⁻¹, for Y of shape (..., 4, 4)."""
    P = np.linalg.inv(Y)
    return np.linalg.inv(F @ P @ F.T + GQG)
