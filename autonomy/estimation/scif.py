"""Square-root cubature information filter (SCIF) of paper 000 (Hu et al. 2018), square-root form end to end.

The filter carries the square root ``S_h`` of the information matrix ``Y = P⁻¹ = S_h S_hᵀ`` and the information vector
``ĥ = Y x̂``. With 2n cubature points ``ξ_i = ±√n e_i`` and ``tria(A)`` = lower factor of ``A Aᵀ`` (by QR):

Predict::

    S_x = S_h⁻ᵀ,  x̂ = S_x S_xᵀ ĥ,  X_i = S_x ξ_i + x̂,  X*_i = f(X_i),  x̂⁻ = mean X*_i
    S_x⁻ = tria([(X*_1 − x̂⁻)/√2n, …, (X*_2n − x̂⁻)/√2n, S_Q]),  S_h⁻ = (S_x⁻)⁻ᵀ,  ĥ⁻ = S_h⁻ S_h⁻ᵀ x̂⁻

Measurement information (``S_R S_Rᵀ = R``; χ, Z_c the centred, 1/√2n-scaled point deviations)::

    X_i = S_x⁻ ξ_i + x̂⁻,  Z_i = h(X_i),  ẑ = mean Z_i,  P_xz = χ Z_cᵀ
    S_I = Y⁻ P_xz S_R⁻ᵀ,  i = S_I S_R⁻¹ (z − ẑ + P_xzᵀ ĥ⁻)

Local update: ``ĥ = ĥ⁻ + i``, ``S_h = tria([S_h⁻, S_I])``. In a team, HCMCI consensus replaces the local update
(see ``autonomy.fusion.consensus``): use :meth:`SCIF.information` and :meth:`SCIF.set_information`.

The motion and measurement models are called from Python (any model works); the dense algebra between them (moments,
triangularisation, inverses, the information contribution) runs in compiled (numba) functions, one call per step,
because on 6-state filters the per-call overhead of a dozen numpy/LAPACK calls exceeded the arithmetic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from autonomy.estimation.base import GaussianFilter, Innovation
from autonomy.estimation.linalg import psd_sqrt, tria, tria_jit
from autonomy.estimation.measurements import MeasurementLike, MeasurementModel, measurement_model
from autonomy.estimation.sigma_point import angle_mean, cubature_points

__all__ = ["SqrtInformation", "SCIF", "add_information"]


@dataclass(frozen=True, eq=False)
class SqrtInformation:
    """Square-root information pair: ``S`` with ``S Sᵀ`` the information (inverse covariance) and vector ``h``.

    For a prior or posterior ``h = Y x̂``; for a measurement contribution ``S Sᵀ = I`` and ``h = i``.
    """

    S: np.ndarray
    h: np.ndarray

    @property
    def Y(self) -> np.ndarray:
        """Information matrix ``S Sᵀ``."""
        return self.S @ self.S.T


def add_information(*parts: SqrtInformation) -> SqrtInformation:
    """The sum of information pairs: ``S = tria([S_1, S_2, …])`` (so ``S Sᵀ = Σ S_k S_kᵀ``) and ``h = Σ h_k`` — e.g. a
    prior plus a measurement contribution (the local update), or the contributions of several scans."""
    return SqrtInformation(tria(np.hstack([p.S for p in parts])), np.sum([p.h for p in parts], axis=0))


@numba.njit(cache=True)
def _information_pair(S_x: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``S_h = S_x⁻ᵀ`` and ``ĥ = S_h S_hᵀ x̂``."""
    S_h = np.ascontiguousarray(np.linalg.inv(S_x).T)
    return S_h, S_h @ (np.ascontiguousarray(S_h.T) @ x)


@numba.njit(cache=True)
def _moments(Xs: np.ndarray, W: np.ndarray, scale: float, S_Q: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Predicted ``x̂⁻ = Σ W_i X*_i``, ``S_x⁻ = tria([(X* − x̂⁻) scale, S_Q])``, ``S_h⁻``, ``ĥ⁻`` (module docstring)."""
    n, p = Xs.shape
    x = Xs @ W
    A = np.empty((n, p + S_Q.shape[1]))
    for i in range(n):
        for j in range(p):
            A[i, j] = (Xs[i, j] - x[i]) * scale
        for j in range(S_Q.shape[1]):
            A[i, p + j] = S_Q[i, j]
    S_x = tria_jit(A)
    S_h, h = _information_pair(S_x, x)
    return x, S_x, S_h, h


@numba.njit(cache=True)
def _measurement_information(chi: np.ndarray, Zc: np.ndarray, S_h: np.ndarray, h: np.ndarray, R: np.ndarray,
                             nu: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(S_I, i, S)`` from the scaled point deviations ``χ``, ``Z_c`` (module docstring); ``S = Z_c Z_cᵀ + R``."""
    Pxz = chi @ np.ascontiguousarray(Zc.T)
    S_R_inv_T = np.ascontiguousarray(np.linalg.inv(np.linalg.cholesky(R)).T)
    S_I = (S_h @ np.ascontiguousarray(S_h.T)) @ Pxz @ S_R_inv_T
    i = S_I @ (np.ascontiguousarray(S_R_inv_T.T) @ (nu + np.ascontiguousarray(Pxz.T) @ h))
    return S_I, i, Zc @ np.ascontiguousarray(Zc.T) + R


class SCIF(GaussianFilter):
    """Square-root cubature information filter (see the module docstring for the equations)."""

    def __init__(self, model, x0: np.ndarray, P0: np.ndarray, t0: float = 0.0, target_height: float = 0.0) -> None:
        n = len(model.layout)
        self._xi, self._W, _ = cubature_points(n)
        self._scale = 1.0 / np.sqrt(2.0 * n)
        self._eye = np.eye(n)
        self._sq_cache: dict[float, np.ndarray] = {}
        super().__init__(model, x0, P0, t0, target_height)

    # --- state access -------------------------------------------------------------------------------------------
    def set_state(self, x: np.ndarray, P: np.ndarray, t: float | None = None) -> None:
        self._S_x = np.linalg.cholesky(np.asarray(P, dtype=float))
        self._x = np.array(x, dtype=float)
        self._S_h, self._h = _information_pair(self._S_x, self._x)
        if t is not None:
            self.t = float(t)

    def set_information(self, info: SqrtInformation) -> None:
        """Replace the estimate by an information pair (e.g. the HCMCI result)."""
        self._S_h = np.array(info.S, dtype=float, order="C")
        self._h = np.array(info.h, dtype=float)
        self._S_x, self._x = _information_pair(self._S_h, self._h)

    @property
    def information_state(self) -> SqrtInformation:
        """Current ``(S_h, ĥ)``."""
        return SqrtInformation(self._S_h, self._h)

    @property
    def x(self) -> np.ndarray:
        return self._x

    @property
    def P(self) -> np.ndarray:
        return self._S_x @ self._S_x.T

    # --- filter steps --------------------------------------------------------------------------------------------
    def _sqrt_Q(self, dt: float, x: np.ndarray) -> np.ndarray:
        if not self.model.is_linear:
            return psd_sqrt(self.model.process_noise(dt, x))
        S_Q = self._sq_cache.get(dt)
        if S_Q is None:
            if len(self._sq_cache) > 64:
                self._sq_cache.clear()
            S_Q = self._sq_cache[dt] = psd_sqrt(self.model.process_noise(dt))
        return S_Q

    def _predict(self, dt: float) -> None:
        X = self._x[:, None] + self._S_x @ self._xi
        Xs = np.ascontiguousarray(self.model.propagate(X, dt), dtype=float)
        S_Q = np.ascontiguousarray(self._sqrt_Q(dt, Xs @ self._W), dtype=float)  # Q(x̂⁻) for state-dependent noise
        self._x, self._S_x, self._S_h, self._h = _moments(Xs, self._W, self._scale, S_Q)

    def information(self, measurement: MeasurementLike, model: MeasurementModel | None = None
                    ) -> tuple[SqrtInformation, Innovation]:
        """Predict to ``measurement.t_meas``; return its information contribution ``(S_I, i)`` without applying it."""
        self.predict(measurement.t_meas)
        mm = model if model is not None else measurement_model(measurement, self.layout, self.target_height)
        return self._contribution(mm, np.asarray(measurement.z, dtype=float), np.asarray(measurement.R, dtype=float))

    def _contribution(self, model: MeasurementModel, z: np.ndarray, R: np.ndarray
                      ) -> tuple[SqrtInformation, Innovation]:
        chi = self._S_x @ self._xi
        Z = model.h(self._x[:, None] + chi)
        zm = angle_mean(Z, self._W, model.angle_mask)
        Zc = model.residual(Z, zm[:, None]) * self._scale
        nu = model.residual(z, zm)
        S_I, i, S = _measurement_information(chi * self._scale, np.ascontiguousarray(Zc, dtype=float), self._S_h,
                                             self._h, np.ascontiguousarray(R, dtype=float),
                                             np.asarray(nu, dtype=float))
        return SqrtInformation(S_I, i), Innovation(nu, S)

    def update_with(self, model: MeasurementModel, z: np.ndarray, R: np.ndarray) -> Innovation:
        info, innov = self._contribution(model, z, R)
        self.set_information(add_information(self.information_state, info))
        return innov
