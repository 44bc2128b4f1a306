"""Base-station information fusion with lost packets (paper 001).

Each UAV runs a local extended information filter and sends its measurement information, linearised at its own
prediction ``x̂⁻``: ``I = Hᵀ R⁻¹ H`` and ``i = Hᵀ R⁻¹ (z − h(x̂⁻) + H x̂⁻)`` (angles wrapped). A packet reaches the base
with probability β (the product of its route's hop probabilities). The base predicts with the same motion model,
``Y⁻ = (F Y⁻¹ Fᵀ + Q)⁻¹``, ``ŷ⁻ = Y⁻ F Y⁻¹ ŷ``, then adds ``Σ ξ_k I_k`` and ``Σ ξ_k i_k`` over the packets that
arrived (ξ_k ∈ {0, 1}). Measurement information is fused, not local posteriors (that would count the prior twice).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from autonomy.estimation.base import TIME_TOLERANCE
from autonomy.estimation.measurements import MeasurementLike, MeasurementModel, measurement_model
from autonomy.estimation.models import MotionModel

__all__ = ["InformationContribution", "information_contribution", "sample_received", "BaseStationFusion"]


@dataclass(frozen=True, kw_only=True, eq=False)
class InformationContribution:
    """One UAV's measurement information packet.

    Attributes
    ----------
    info_matrix : ndarray (n, n)
        Information matrix ``I = Hᵀ R⁻¹ H``, in inverse state units squared.
    info_vector : ndarray (n,)
        Information vector ``i = Hᵀ R⁻¹ (ν + H x̂⁻)``.
    t_meas : float
        Time of the measurement, s.
    sensor_id : int or str
        Sender.
    """

    info_matrix: np.ndarray
    info_vector: np.ndarray
    t_meas: float
    sensor_id: int | str = 0


def information_contribution(x_pred: np.ndarray, measurement: MeasurementLike, layout: tuple[str, ...],
                             model: MeasurementModel | None = None, target_height: float = 0.0
                             ) -> InformationContribution:
    """Measurement information of ``measurement`` linearised at the sender's prediction ``x_pred`` (EIF form)."""
    mm = model if model is not None else measurement_model(measurement, layout, target_height)
    x_pred = np.asarray(x_pred, dtype=float)
    H = mm.jacobian(x_pred)
    nu = mm.residual(np.asarray(measurement.z, dtype=float), mm.h(x_pred))
    HtRinv = np.linalg.solve(np.asarray(measurement.R, dtype=float), H).T
    return InformationContribution(info_matrix=HtRinv @ H, info_vector=HtRinv @ (nu + H @ x_pred),
                                   t_meas=float(measurement.t_meas), sensor_id=measurement.sensor_id)


def sample_received(beta: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Bernoulli packet arrivals ``ξ_k ~ B(β_k)`` (bool array)."""
    beta = np.asarray(beta, dtype=float)
    if np.any((beta < 0) | (beta > 1)):
        raise ValueError(f"beta must lie in [0, 1], got {beta}")
    return rng.random(beta.shape) < beta


def _time(c: object) -> float:
    t = getattr(c, "t_meas", None)
    return float(t if t is not None else c.t_info)  # type: ignore[attr-defined]


class BaseStationFusion:
    """Information filter at the base station fusing the packets that arrive.

    Parameters
    ----------
    model : MotionModel
        Target motion model (linear or not; nonlinear models are linearised at the current estimate).
    x0, P0 : ndarray
        Initial estimate and covariance.
    t0 : float
        Time of ``x0``, s.
    """

    def __init__(self, model: MotionModel, x0: np.ndarray, P0: np.ndarray, t0: float = 0.0) -> None:
        self.model = model
        self.layout = model.layout
        self.t = float(t0)
        self.Y = np.linalg.inv(np.asarray(P0, dtype=float))
        self.y = self.Y @ np.asarray(x0, dtype=float)
        self.n_received = 0
        self.n_lost = 0

    @property
    def x(self) -> np.ndarray:
        """State estimate ``Y⁻¹ y``."""
        return np.linalg.solve(self.Y, self.y)

    @property
    def P(self) -> np.ndarray:
        """Covariance ``Y⁻¹``."""
        P = np.linalg.inv(self.Y)
        return 0.5 * (P + P.T)

    def predict(self, t: float) -> None:
        """Information prediction to absolute time ``t`` (s)."""
        dt = float(t) - self.t
        if dt < -TIME_TOLERANCE:
            raise ValueError(f"cannot predict backwards: t={t} < base time {self.t}")
        if dt <= TIME_TOLERANCE:
            return
        x, P = self.x, self.P
        F = self.model.jacobian(x, dt)
        x = self.model.propagate(x, dt)
        P = F @ P @ F.T + self.model.process_noise(dt, x)
        self.Y = np.linalg.inv(0.5 * (P + P.T))
        self.Y = 0.5 * (self.Y + self.Y.T)
        self.y = self.Y @ x
        self.t = float(t)

    def fuse(self, contributions: Sequence[InformationContribution], received: Sequence[bool] | None = None) -> int:
        """Predict to the packets' time and add the information of those received; returns how many were fused.

        Any object with ``info_matrix``, ``info_vector`` and a time ``t_meas`` (or ``t_info``, as the radio's
        ``InformationMessage`` has) is accepted.
        """
        if received is None:
            received = [True] * len(contributions)
        if len(received) != len(contributions):
            raise ValueError(f"received must have one flag per contribution ({len(contributions)}), "
                             f"got {len(received)}")
        if contributions:
            self.predict(max(_time(c) for c in contributions))
        k = 0
        for c, ok in zip(contributions, received, strict=True):
            if ok:
                self.Y = self.Y + c.info_matrix
                self.y = self.y + c.info_vector
                k += 1
        self.n_received += k
        self.n_lost += len(contributions) - k
        return k
