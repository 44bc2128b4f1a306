"""The χ² validation gate and the distance it gates: the NIS of a detection against a track predicted to its time.

A detection ``z`` with innovation ``ν = z − h(x̂⁻)`` and innovation covariance ``S = H P⁻ Hᵀ + R`` lies in the gate
of probability ``p`` when ``νᵀ S⁻¹ ν ≤ χ²_m(p)``, the ``p``-quantile of the χ² distribution with ``m = len(z)``
degrees of freedom: for a consistent track, the true target's detection falls inside with probability ``p``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.special import gammaincinv

from autonomy.estimation.base import Filter
from autonomy.estimation.measurements import MeasurementLike
from autonomy.estimation.models import MotionModel

__all__ = ["ChiSquareGate", "PredictedNis"]


class ChiSquareGate:
    """The χ² validation gate of probability ``probability`` in (0, 1) (module docstring)."""

    def __init__(self, probability: float) -> None:
        if not 0 < probability < 1:
            raise ValueError(f"ChiSquareGate.probability must be in (0, 1), got {probability!r}")
        self.probability = float(probability)
        self._thresholds: dict[int, float] = {}

    def threshold(self, dof: int) -> float:
        """``χ²_dof(probability)``: the largest NIS inside the gate for a measurement of ``dof`` components."""
        if dof not in self._thresholds:
            self._thresholds[dof] = float(2.0 * gammaincinv(dof / 2.0, self.probability))  # χ² quantile
        return self._thresholds[dof]

    def accepts(self, nis: float, dof: int) -> bool:
        """Whether a detection of ``dof`` components at NIS ``nis`` lies inside the gate."""
        return nis <= self.threshold(dof)


def _same(f: Filter) -> Filter:
    return f


class PredictedNis:
    """The NIS ``νᵀ S⁻¹ ν`` of a detection against a track's filter predicted to the detection's time, with the EKF
    linearisation of ``motion`` and of the detection's own model; the filter is not changed.

    Parameters
    ----------
    motion : MotionModel
        The motion model of the prediction (and the state layout the detection's model is bound to).
    target_height : float
        Ground plane of planar states (m).
    gating_filter : callable, optional
        The filter whose estimate is gated against, given the track's filter (default: that filter itself); e.g. a
        road-network filter's unconstrained fallback, so a car leaving the road is not gated out by the estimate
        that is tight across the road.
    """

    def __init__(self, motion: MotionModel, target_height: float,
                 gating_filter: Callable[[Filter], Filter] | None = None) -> None:
        self.motion = motion
        self.layout = motion.layout
        self.target_height = float(target_height)
        self.gating_filter = _same if gating_filter is None else gating_filter

    def __call__(self, filter: Filter, det: MeasurementLike) -> float:
        """NIS of ``det`` against ``filter`` (dimensionless, χ² with ``len(det.z)`` degrees of freedom)."""
        f = self.gating_filter(filter)
        model = self.motion
        F = model.jacobian(f.x, det.t_meas - f.t)
        x = model.propagate(f.x, det.t_meas - f.t)
        P = F @ f.P @ F.T + model.process_noise(det.t_meas - f.t, f.x)
        h = det.model.bind(det, self.layout, self.target_height)
        H = h.jacobian(x)
        nu = h.residual(np.asarray(det.z, dtype=float), h.h(x))
        S = H @ P @ H.T + np.asarray(det.R, dtype=float)
        return float(nu @ np.linalg.solve(S, nu))
