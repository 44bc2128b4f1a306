"""Sigma-point filters: the unscented (UKF) and the cubature (CKF) Kalman filters.

Both propagate a deterministic point set ``X_i = x + S ξ_i`` (``S Sᵀ = P``) through the models and recover moments
with weights ``W^m``, ``W^c``. Angle components of the predicted measurement are averaged on the circle (deviations
from a reference point are wrapped before averaging) and their deviations wrapped.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from autonomy.estimation.base import GaussianFilter, Innovation
from autonomy.estimation.linalg import psd_sqrt, small_inv
from autonomy.estimation.measurements import MeasurementModel, wrap_angle
from autonomy.estimation.models import MotionModel

__all__ = ["UKFParams", "SigmaPointFilter", "UKF", "CKF", "cubature_points", "unscented_points", "angle_mean"]


@dataclass(frozen=True, kw_only=True)
class UKFParams:
    """Scaled unscented transform parameters (Wan & van der Merwe): ``λ = α²(n + κ) − n``.

    The defaults (α = 1, β = 2, κ = 0) keep every covariance weight non-negative, so predicted covariances stay
    positive semi-definite for any state dimension.
    """

    alpha: float = field(default=1.0, metadata={"doc": "spread of the points, dimensionless, > 0"})
    beta: float = field(default=2.0, metadata={"doc": "prior-distribution term (2 for Gaussian), dimensionless"})
    kappa: float = field(default=0.0, metadata={"doc": "secondary scaling, dimensionless"})

    def __post_init__(self) -> None:
        if not (np.isfinite(self.alpha) and self.alpha > 0):
            raise ValueError(f"alpha must be finite and > 0, got {self.alpha!r}")
        if not np.isfinite(self.beta):
            raise ValueError(f"beta must be finite, got {self.beta!r}")
        if not np.isfinite(self.kappa):
            raise ValueError(f"kappa must be finite, got {self.kappa!r}")


def unscented_points(n: int, params: UKFParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit points ``ξ`` (n × (2n+1)) and weights ``(W^m, W^c)`` of the scaled unscented transform."""
    lam = params.alpha**2 * (n + params.kappa) - n
    if n + lam <= 0:
        raise ValueError(f"alpha={params.alpha}, kappa={params.kappa} give n + λ = {n + lam} <= 0 for n={n}")
    c = np.sqrt(n + lam)
    xi = np.hstack([np.zeros((n, 1)), c * np.eye(n), -c * np.eye(n)])
    Wm = np.full(2 * n + 1, 0.5 / (n + lam))
    Wc = Wm.copy()
    Wm[0] = lam / (n + lam)
    Wc[0] = Wm[0] + 1.0 - params.alpha**2 + params.beta
    return xi, Wm, Wc


def cubature_points(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Third-degree spherical-radial cubature: ``ξ = √n [I, −I]``, weights ``1/(2n)``."""
    xi = np.sqrt(n) * np.hstack([np.eye(n), -np.eye(n)])
    W = np.full(2 * n, 0.5 / n)
    return xi, W, W.copy()


def angle_mean(Z: np.ndarray, Wm: np.ndarray, angle_mask: np.ndarray) -> np.ndarray:
    """Weighted mean of the columns of ``Z``; angle rows averaged as wrapped deviations from the first column."""
    if not angle_mask.any():
        return Z @ Wm
    ref = Z[:, 0]
    D = np.where(angle_mask[:, None], wrap_angle(Z - ref[:, None]), Z - ref[:, None])
    zm = ref + D @ Wm
    return np.where(angle_mask, wrap_angle(zm), zm)


class SigmaPointFilter(GaussianFilter):
    """Gaussian filter with a fixed unit point set ``ξ`` and weights ``W^m``, ``W^c`` (set by subclasses)."""

    _xi: np.ndarray
    _Wm: np.ndarray
    _Wc: np.ndarray

    def set_state(self, x: np.ndarray, P: np.ndarray, t: float | None = None) -> None:
        self._x = np.array(x, dtype=float)
        self._P = np.array(P, dtype=float)
        if t is not None:
            self.t = float(t)

    @property
    def x(self) -> np.ndarray:
        return self._x

    @property
    def P(self) -> np.ndarray:
        return self._P

    def _points(self) -> np.ndarray:
        return self._x[:, None] + psd_sqrt(self._P) @ self._xi

    def _predict(self, dt: float) -> None:
        m = self.model
        X = m.propagate(self._points(), dt)
        x = X @ self._Wm
        D = X - x[:, None]
        P = (D * self._Wc) @ D.T + m.process_noise(dt, x)
        self._x = x
        self._P = 0.5 * (P + P.T)

    def update_with(self, model: MeasurementModel, z: np.ndarray, R: np.ndarray) -> Innovation:
        X = self._points()
        Z = model.h(X)
        zm = angle_mean(Z, self._Wm, model.angle_mask)
        DZ = model.residual(Z, zm[:, None])
        DX = X - self._x[:, None]
        DZw = DZ * self._Wc
        S = DZw @ DZ.T + R
        Pxz = DX @ DZw.T
        S_inv, det_S = small_inv(S)
        K = Pxz @ S_inv
        nu = model.residual(z, zm)
        self._x = self._x + K @ nu
        P = self._P - K @ S @ K.T
        self._P = 0.5 * (P + P.T)
        return Innovation(nu, S, S_inv, det_S)


class UKF(SigmaPointFilter):
    """Unscented Kalman filter (2n + 1 scaled sigma points; see :class:`UKFParams`)."""

    def __init__(self, model: MotionModel, x0: np.ndarray, P0: np.ndarray, t0: float = 0.0,
                 target_height: float = 0.0, params: UKFParams | None = None) -> None:
        self.params = params if params is not None else UKFParams()
        self._xi, self._Wm, self._Wc = unscented_points(len(model.layout), self.params)
        super().__init__(model, x0, P0, t0, target_height)


class CKF(SigmaPointFilter):
    """Cubature Kalman filter (Arasaratnam & Haykin 2009): 2n points ``±√n e_i``, equal weights ``1/(2n)``."""

    def __init__(self, model: MotionModel, x0: np.ndarray, P0: np.ndarray, t0: float = 0.0,
                 target_height: float = 0.0) -> None:
        self._xi, self._Wm, self._Wc = cubature_points(len(model.layout))
        super().__init__(model, x0, P0, t0, target_height)
