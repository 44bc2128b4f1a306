"""The filter interface: ``predict(t)`` to an absolute time, ``update(measurement)``; state ``x``, covariance ``P``,
time ``t``.

A filter predicts to each measurement's own time stamp ``t_meas`` before updating, so asynchronous and delayed
sensors are handled by construction (measurements older than the filter's time are rejected: no out-of-sequence
processing). Constrained filters (e.g. road constraints as pseudo-measurements) subclass a filter and call
:meth:`GaussianFilter.update_with` with their own measurement model after the sensor update.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from autonomy.estimation.linalg import log_gaussian
from autonomy.estimation.measurements import MeasurementLike, MeasurementModel, measurement_model
from autonomy.estimation.models import MotionModel

__all__ = ["Innovation", "Filter", "GaussianFilter", "TIME_TOLERANCE"]

TIME_TOLERANCE = 1e-9  # s; time stamps closer than this count as equal
_LOG_2PI = math.log(2.0 * math.pi)


@dataclass(frozen=True, eq=False)
class Innovation:
    """Result of one update; ``nis`` (``νᵀ S⁻¹ ν``, χ² with ``len(ν)`` degrees of freedom for a consistent filter)
    and ``log_likelihood`` are computed on first use.

    Attributes
    ----------
    nu : ndarray
        Innovation ``z − ẑ`` (angles wrapped), measurement units.
    S : ndarray
        Innovation covariance, measurement units squared.
    S_inv : ndarray or None
        ``S⁻¹`` when the filter computed it anyway.
    det_S : float or None
        ``det S`` when the filter computed it anyway (saves a factorisation in the likelihood).
    """

    nu: np.ndarray
    S: np.ndarray
    S_inv: np.ndarray | None = None
    det_S: float | None = None

    @property
    def nis(self) -> float:
        """Normalised innovation squared ``νᵀ S⁻¹ ν``."""
        if self.S_inv is not None:
            return float(self.nu @ self.S_inv @ self.nu)
        return float(self.nu @ np.linalg.solve(self.S, self.nu))

    @property
    def log_likelihood(self) -> float:
        """``log N(ν; 0, S)`` = ``−½(nis + log det(2π S))``, used for IMM mode probabilities."""
        if self.det_S is None:
            return log_gaussian(self.nis, self.S)
        if self.det_S <= 0.0:
            return -np.inf
        return -0.5 * (self.nis + math.log(self.det_S) + self.S.shape[0] * _LOG_2PI)


class Filter(ABC):
    """Base class of state estimators.

    Attributes
    ----------
    layout : tuple of str
        Names of the state components.
    t : float
        Time of the current estimate, s.
    """

    layout: tuple[str, ...]
    t: float

    @property
    @abstractmethod
    def x(self) -> np.ndarray:
        """State estimate, shape ``(n,)``."""

    @property
    @abstractmethod
    def P(self) -> np.ndarray:
        """Error covariance, shape ``(n, n)``."""

    @abstractmethod
    def predict(self, t: float) -> None:
        """Predict the estimate to absolute time ``t`` (s), ``t >= self.t``."""

    @abstractmethod
    def update(self, measurement: MeasurementLike, model: MeasurementModel | None = None) -> Innovation:
        """Predict to ``measurement.t_meas`` then correct with it; ``model`` overrides the kind-based model."""

    @abstractmethod
    def set_state(self, x: np.ndarray, P: np.ndarray, t: float | None = None) -> None:
        """Overwrite the estimate (e.g. IMM mixing, fusion feedback)."""


class GaussianFilter(Filter):
    """A single-model Gaussian filter (EKF, UKF, CKF, SCIF share this skeleton).

    Parameters
    ----------
    model : MotionModel
        Target motion model.
    x0 : ndarray
        Initial state, layout ``model.layout``.
    P0 : ndarray
        Initial covariance (symmetric positive definite).
    t0 : float
        Time of ``x0``, s.
    target_height : float
        Height (m) of targets whose state has no ``z`` (measurement models place them on this plane).
    """

    def __init__(self, model: MotionModel, x0: np.ndarray, P0: np.ndarray, t0: float = 0.0,
                 target_height: float = 0.0) -> None:
        self.model = model
        self.layout = model.layout
        self.target_height = float(target_height)
        n = len(self.layout)
        x0 = np.asarray(x0, dtype=float).reshape(-1)
        P0 = np.asarray(P0, dtype=float)
        if x0.shape != (n,):
            raise ValueError(f"x0 must have shape ({n},) for layout {self.layout}, got {x0.shape}")
        if P0.shape != (n, n):
            raise ValueError(f"P0 must have shape ({n}, {n}), got {P0.shape}")
        if not np.allclose(P0, P0.T):
            raise ValueError("P0 must be symmetric")
        self.t = float(t0)
        self.set_state(x0, P0, t0)

    def predict(self, t: float) -> None:
        dt = float(t) - self.t
        if dt < -TIME_TOLERANCE:
            raise ValueError(f"cannot predict backwards: t={t} < filter time {self.t} (out-of-sequence measurement)")
        if dt <= TIME_TOLERANCE:
            return
        self._predict(dt)
        self.t = float(t)

    def update(self, measurement: MeasurementLike, model: MeasurementModel | None = None) -> Innovation:
        self.predict(measurement.t_meas)
        mm = model if model is not None else measurement_model(measurement, self.layout, self.target_height)
        return self.update_with(mm, np.asarray(measurement.z, dtype=float), np.asarray(measurement.R, dtype=float))

    @abstractmethod
    def _predict(self, dt: float) -> None:
        """Predict over ``dt > 0`` s (``t`` is advanced by the caller)."""

    @abstractmethod
    def update_with(self, model: MeasurementModel, z: np.ndarray, R: np.ndarray) -> Innovation:
        """Correct the current estimate (no prediction) with ``z`` under ``model`` and noise ``R``."""
