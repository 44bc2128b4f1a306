"""Extended Kalman filter (the exact Kalman filter on linear models)."""

from __future__ import annotations

import numpy as np

from autonomy.estimation.base import GaussianFilter, Innovation
from autonomy.estimation.linalg import small_inv
from autonomy.estimation.measurements import MeasurementModel

__all__ = ["EKF"]


class EKF(GaussianFilter):
    """Extended Kalman filter.

    Predict: ``x⁻ = f(x)``, ``P⁻ = F P Fᵀ + Q`` with ``F = ∂f/∂x``.
    Update: ``S = H P⁻ Hᵀ + R``, ``K = P⁻ Hᵀ S⁻¹``, ``x = x⁻ + K ν`` (ν with angles wrapped) and the Joseph form
    ``P = (I − K H) P⁻ (I − K H)ᵀ + K R Kᵀ``, which keeps ``P`` symmetric positive definite under round-off.

    With ``iterations = n > 1`` the update is the iterated EKF (Gauss–Newton on the posterior's mode, Bell & Cathey
    1993): relinearised at each iterate ``xᵢ`` (``x₀ = x⁻``), ``xᵢ₊₁ = x⁻ + Kᵢ (z − h(xᵢ) − Hᵢ (x⁻ − xᵢ))`` with
    ``Kᵢ`` from ``Hᵢ = ∂h/∂x (xᵢ)``, stopping after ``n`` steps or once a step moves the state by less than 1 mm
    (mm/s); the covariance is the Joseph form at the last linearisation. A bearing seen from close by (a camera's
    elevation from 60 m above a car 80 m away) is strongly curved over a prior tens of metres wide: one
    linearisation there can land metres off with a covariance of centimetres, which the iterations avoid. The
    innovation returned (for gating and NIS) is the prior's, as with one iteration.

    Parameters
    ----------
    iterations : int
        Linearisations per update, >= 1 (1: the plain EKF).
    """

    def __init__(self, *args, iterations: int = 1, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        if int(iterations) != iterations or iterations < 1:
            raise ValueError(f"EKF.iterations must be an integer >= 1, got {iterations!r}")
        self.iterations = int(iterations)

    _dt_cached: float = -1.0
    _FQ: tuple[np.ndarray, np.ndarray]

    def set_state(self, x: np.ndarray, P: np.ndarray, t: float | None = None) -> None:
        if getattr(self, "_eye", None) is None or self._eye.shape[0] != len(x):
            self._eye = np.eye(len(x))
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

    def _predict(self, dt: float) -> None:
        m = self.model
        if m.is_linear:
            if dt != self._dt_cached:
                self._FQ = m.matrices(dt)  # type: ignore[attr-defined]
                self._dt_cached = dt
            F, Q = self._FQ
            self._x = F @ self._x
        else:
            F = m.jacobian(self._x, dt)
            self._x = m.propagate(self._x, dt)
            Q = m.process_noise(dt, self._x)
        self._P = F @ self._P @ F.T + Q  # symmetric up to round-off; the update symmetrises

    def update_with(self, model: MeasurementModel, z: np.ndarray, R: np.ndarray) -> Innovation:
        x, P = self._x, self._P
        z_pred, H = model.linearise(x)
        nu = model.residual(z, z_pred)
        PHt = P @ H.T
        S = H @ PHt + R
        S_inv, det_S = small_inv(S)
        K = PHt @ S_inv
        x_new = x + K @ nu
        innovation = Innovation(nu, S, S_inv, det_S)
        x_i = x
        for _ in range(self.iterations - 1):
            if np.max(np.abs(x_new - x_i)) < 1e-3:
                break
            x_i = x_new
            z_i, H = model.linearise(x_i)
            PHt = P @ H.T
            K = PHt @ small_inv(H @ PHt + R)[0]
            x_new = x + K @ (model.residual(z, z_i) - H @ (x - x_i))
        self._x = x_new
        IKH = self._eye - K @ H
        P = IKH @ P @ IKH.T + K @ R @ K.T
        self._P = 0.5 * (P + P.T)
        return innovation
