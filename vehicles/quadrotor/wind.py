"""Wind: a constant mean plus Dryden turbulence (MIL-F-8785C spectra), one independent realisation per UAV."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import cholesky, expm, solve_continuous_lyapunov

__all__ = ["WindConfig", "DrydenWind"]


def _vec3(name: str, value: object, positive: bool) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=float).reshape(-1)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)) or (positive and np.any(arr <= 0)):
        raise ValueError(f"WindConfig.{name} must be 3 finite {'positive ' if positive else ''}numbers, got {value!r}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


@dataclass(frozen=True, kw_only=True)
class WindConfig:
    """Wind acting on every UAV through its body drag (air-relative velocity ``v - w``).

    Attributes
    ----------
    mean_W : tuple[float, float, float]
        Constant wind velocity, world ENU (m/s).
    sigma : tuple[float, float, float]
        Turbulence intensities ``(sigma_u, sigma_v, sigma_w)``: longitudinal (along the mean horizontal wind, +x if
        it is calm), lateral, vertical (m/s), >= 0; all zero disables turbulence.
    length_scale : tuple[float, float, float]
        Dryden scale lengths ``(L_u, L_v, L_w)`` (m), > 0.
    airspeed : float
        Airspeed ``V`` that converts the spatial spectra to time (frozen turbulence, Taylor's hypothesis) (m/s), > 0.
    """

    mean_W: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sigma: tuple[float, float, float] = (1.0, 1.0, 0.5)
    length_scale: tuple[float, float, float] = (200.0, 200.0, 50.0)
    airspeed: float = 10.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean_W", _vec3("mean_W", self.mean_W, positive=False))
        sig = np.asarray(self.sigma, dtype=float).reshape(-1)
        if sig.shape != (3,) or not np.all(np.isfinite(sig)) or np.any(sig < 0):
            raise ValueError(f"WindConfig.sigma must be 3 finite numbers >= 0 m/s, got {self.sigma!r}")
        object.__setattr__(self, "sigma", tuple(float(v) for v in sig))
        object.__setattr__(self, "length_scale", _vec3("length_scale", self.length_scale, positive=True))
        if not (math.isfinite(self.airspeed) and self.airspeed > 0):
            raise ValueError(f"WindConfig.airspeed must be > 0 m/s, got {self.airspeed!r}")


def _dryden_axis(sigma: float, L: float, V: float, second_order: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Continuous state-space ``(A, B, C)`` driven by unit white noise whose output has variance ``sigma^2``.

    Longitudinal: ``H_u(s) ∝ 1 / (1 + T s)``; lateral and vertical: ``H(s) ∝ (1 + sqrt(3) T s) / (1 + T s)^2``,
    ``T = L / V`` (MIL-F-8785C shapes); the gain is set from the stationary covariance ``P``
    (``A P + P A^T + B B^T = 0``).
    """
    T = L / V
    if second_order:
        A = np.array([[0.0, 1.0], [-1.0 / T**2, -2.0 / T]])
        B = np.array([[0.0], [1.0]])
        C = np.array([[1.0 / T**2, math.sqrt(3.0) / T]])
    else:
        A = np.array([[-1.0 / T]])
        B = np.array([[1.0]])
        C = np.array([[1.0 / T]])
    P = solve_continuous_lyapunov(A, -B @ B.T)
    var = float((C @ P @ C.T)[0, 0])
    return A, B, C * (sigma / math.sqrt(var))


class DrydenWind:
    """Mean wind plus Dryden turbulence for N UAVs, advanced once per physics step.

    Each axis' shaping filter is discretised exactly (Van Loan): ``x_{k+1} = A_d x_k + L n_k``, ``n_k ~ N(0, I)`` with
    ``L L^T = int_0^dt e^{A s} B B^T e^{A^T s} ds``; the stationary output variance is ``sigma^2`` by construction and
    the filter starts in its stationary distribution.

    Parameters
    ----------
    config : WindConfig
        Mean wind and turbulence.
    n : int
        Number of UAVs.
    dt : float
        Physics step (s).
    rng : np.random.Generator
        Source of the turbulence.
    """

    def __init__(self, config: WindConfig, n: int, dt: float, rng: np.random.Generator) -> None:
        self._rng = rng
        self._mean = np.asarray(config.mean_W, dtype=float)
        mh = math.hypot(config.mean_W[0], config.mean_W[1])
        c, s = (config.mean_W[0] / mh, config.mean_W[1] / mh) if mh > 0 else (1.0, 0.0)
        self._R_WT = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])  # turbulence axes (u, v, w) -> world
        blocks = [_dryden_axis(sig, L, config.airspeed, second_order=k > 0)
                  for k, (sig, L) in enumerate(zip(config.sigma, config.length_scale, strict=True))]
        nx = sum(b[0].shape[0] for b in blocks)
        A, B, C = np.zeros((nx, nx)), np.zeros((nx, 3)), np.zeros((3, nx))
        i = 0
        for k, (Ak, Bk, Ck) in enumerate(blocks):
            m = Ak.shape[0]
            A[i:i + m, i:i + m], B[i:i + m, k:k + 1], C[k:k + 1, i:i + m] = Ak, Bk, Ck
            i += m
        van_loan = expm(np.block([[-A, B @ B.T], [np.zeros_like(A), A.T]]) * dt)
        Ad = van_loan[nx:, nx:].T
        Qd = Ad @ van_loan[:nx, nx:]
        self._Ad_T = Ad.T
        self._Lq_T = cholesky(Qd, lower=True).T
        self._C_T = (self._R_WT @ C).T
        P = solve_continuous_lyapunov(A, -B @ B.T)
        self._x = rng.standard_normal((n, nx)) @ cholesky(P, lower=True).T
        self._turbulent = any(sig > 0 for sig in config.sigma)

    def step(self) -> np.ndarray:
        """Advance one physics step; return the wind velocity (N, 3) at every UAV, world frame (m/s)."""
        if self._turbulent:
            self._x = self._x.dot(self._Ad_T) + self._rng.standard_normal(self._x.shape).dot(self._Lq_T)
        return self._mean + self._x.dot(self._C_T)
