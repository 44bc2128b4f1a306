"""IMM of extended Kalman filters on linear motion models sharing one state layout, computed as batched arrays.

Same estimator as :class:`~autonomy.estimation.imm.IMM` over :class:`~autonomy.estimation.ekf.EKF` modes
(interaction, mode-matched EKF predict and update, Gaussian-likelihood mode probabilities, combination; the covariance
update is the short form ``P − K S Kᵀ``, symmetrised, where the EKF uses the Joseph form), but the r mode estimates
are stacked as ``X`` (r × n) and ``P`` (r × n × n) so each step is a few batched numpy operations instead of r
separate filter calls. Use it for the common CV / CT(±ω) / Singer mode sets; use ``IMM`` for mixed layouts, nonlinear
motion models or other filters.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from autonomy.estimation.base import TIME_TOLERANCE, Filter, Innovation
from autonomy.estimation.measurements import MeasurementLike, MeasurementModel, measurement_model
from autonomy.estimation.models import LinearMotionModel

__all__ = ["BatchedEKFIMM"]

_LOG_2PI = math.log(2.0 * math.pi)


class BatchedEKFIMM(Filter):
    """IMM with one EKF per linear motion model, batched over modes.

    Parameters
    ----------
    models : sequence of LinearMotionModel
        One model per mode, all with the same ``layout``.
    x0, P0 : ndarray
        Initial state and covariance, shared by every mode.
    transition : ndarray
        Mode-transition matrix ``Π`` (r × r, rows sum to 1), applied once per prediction.
    t0 : float
        Time of ``x0``, s.
    mu0 : ndarray, optional
        Initial mode probabilities (uniform by default).
    target_height : float
        Height (m) of targets whose state has no ``z``.
    """

    def __init__(self, models: Sequence[LinearMotionModel], x0: np.ndarray, P0: np.ndarray, transition: np.ndarray,
                 t0: float = 0.0, mu0: np.ndarray | None = None, target_height: float = 0.0) -> None:
        if len(models) == 0:
            raise ValueError("models must hold at least one model, got none")
        self.models = tuple(models)
        self.layout = self.models[0].layout
        if any(m.layout != self.layout or not m.is_linear for m in self.models):
            raise ValueError("models must all be linear and share one layout")
        r = len(self.models)
        self._Pi = np.array(transition, dtype=float)
        if self._Pi.shape != (r, r) or np.any(self._Pi < 0) or not np.allclose(self._Pi.sum(axis=1), 1.0):
            raise ValueError(f"transition must be a {r}×{r} row-stochastic matrix, got {transition!r}")
        mu = np.full(r, 1.0 / r) if mu0 is None else np.asarray(mu0, dtype=float)
        if mu.shape != (r,) or np.any(mu < 0) or not np.isclose(mu.sum(), 1.0):
            raise ValueError(f"mu0 must be {r} non-negative probabilities summing to 1, got {mu0!r}")
        self.mu = mu
        self.X = np.tile(np.asarray(x0, dtype=float), (r, 1))
        self.Ps = np.tile(np.asarray(P0, dtype=float), (r, 1, 1))
        self.t = float(t0)
        self.target_height = float(target_height)
        self._dt_cached = -1.0
        self._F = self._Q = self._FT = np.empty(0)
        self._last: tuple | None = None

    # --- combined estimate ---------------------------------------------------------------------------------------
    @property
    def x(self) -> np.ndarray:
        return self.mu @ self.X

    @property
    def P(self) -> np.ndarray:
        x = self.mu @ self.X
        D = self.X - x
        P = np.tensordot(self.mu, self.Ps, axes=1) + (D * self.mu[:, None]).T @ D
        return 0.5 * (P + P.T)

    def set_state(self, x: np.ndarray, P: np.ndarray, t: float | None = None) -> None:
        r = len(self.models)
        self.X = np.tile(np.asarray(x, dtype=float), (r, 1))
        self.Ps = np.tile(np.asarray(P, dtype=float), (r, 1, 1))
        if t is not None:
            self.t = float(t)

    # --- cycle ---------------------------------------------------------------------------------------------------
    def _matrices(self, dt: float) -> None:
        if dt != self._dt_cached:
            FQ = [m.matrices(dt) for m in self.models]
            self._F = np.array([f for f, _ in FQ])
            self._FT = self._F.transpose(0, 2, 1).copy()
            self._Q = np.array([q for _, q in FQ])
            self._dt_cached = dt

    def predict(self, t: float) -> None:
        dt = float(t) - self.t
        if dt < -TIME_TOLERANCE:
            raise ValueError(f"cannot predict backwards: t={t} < filter time {self.t} (out-of-sequence measurement)")
        if dt <= TIME_TOLERANCE:
            return
        r, n = self.X.shape
        # interaction: P⁰_j = Σ_i μ_{i|j}(P_i + d_i d_iᵀ) − d⁰_j d⁰_jᵀ, deviations d from mode 0's estimate
        cbar = self.mu @ self._Pi
        w = (self._Pi * self.mu[:, None]) / np.where(cbar > 0, cbar, 1.0)
        wT = w.T
        ref = self.X[0]
        Dc = self.X - ref
        M = (self.Ps + Dc[:, :, None] * Dc[:, None, :]).reshape(r, n * n)
        D0 = wT @ Dc
        P0 = (wT @ M).reshape(r, n, n) - D0[:, :, None] * D0[:, None, :]
        self.mu = cbar
        # mode-matched prediction
        self._matrices(dt)
        self.X = np.matmul(self._F, (D0 + ref)[:, :, None])[:, :, 0]
        self.Ps = self._F @ P0 @ self._FT + self._Q
        self.t = float(t)

    def update(self, measurement: MeasurementLike, model: MeasurementModel | None = None) -> Innovation:
        """Predict to ``measurement.t_meas`` and update every mode; returns the most probable mode's innovation."""
        self.predict(measurement.t_meas)
        mm = model if model is not None else measurement_model(measurement, self.layout, self.target_height)
        z = np.asarray(measurement.z, dtype=float)
        R = np.asarray(measurement.R, dtype=float)
        X, Ps = self.X, self.Ps
        lin = [mm.linearise(x) for x in X]
        H = np.array([h for _, h in lin])  # (r, m, n)
        nu = mm.residual(z[:, None], np.array([zp for zp, _ in lin]).T).T  # (r, m)
        PHt = Ps @ H.transpose(0, 2, 1)
        S = H @ PHt + R
        S_inv = np.linalg.inv(S)
        K = PHt @ S_inv
        self.X = X + np.matmul(K, nu[:, :, None])[:, :, 0]
        P = Ps - K @ PHt.transpose(0, 2, 1)  # P − K S Kᵀ; the symmetrisation below removes round-off asymmetry
        self.Ps = 0.5 * (P + P.transpose(0, 2, 1))
        nis = (nu[:, None, :] @ S_inv @ nu[:, :, None]).ravel().tolist()
        det = np.linalg.det(S).tolist()
        c = z.size * _LOG_2PI
        logw = [-0.5 * (q + math.log(d) + c) + math.log(mu) if d > 0.0 and mu > 0.0 else -math.inf
                for q, d, mu in zip(nis, det, self.mu.tolist(), strict=True)]
        top = max(logw)
        if math.isfinite(top):  # log-sum-exp normalisation; all-impossible updates leave μ unchanged
            wts = [math.exp(lw - top) for lw in logw]
            total = sum(wts)
            self.mu = np.array([v / total for v in wts])
        self._last = (nu, S, S_inv, det)
        j = int(np.argmax(self.mu))
        return Innovation(nu[j], S[j], S_inv[j], det[j])

    @property
    def last_innovations(self) -> list[Innovation] | None:
        """Every mode's innovation at the last update."""
        if self._last is None:
            return None
        nu, S, S_inv, det = self._last
        return [Innovation(nu[j], S[j], S_inv[j], det[j]) for j in range(len(det))]
