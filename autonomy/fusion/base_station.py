"""Base-station information fusion with lost packets (paper 001).

Each UAV runs a local extended information filter and sends its measurement information, linearised at its own
prediction ``x̂⁻``: ``I = Hᵀ R⁻¹ H`` and ``i = Hᵀ R⁻¹ (z − h(x̂⁻) + H x̂⁻)`` (angles wrapped). A packet reaches the base
with probability β (the product of its route's hop probabilities). The base predicts with the same motion model,
``Y⁻ = (F Y⁻¹ Fᵀ + Q)⁻¹``, ``ŷ⁻ = Y⁻ F Y⁻¹ ŷ``, then adds ``Σ ξ_k I_k`` and ``Σ ξ_k i_k`` over the packets that
arrived (ξ_k ∈ {0, 1}). Measurement information is fused, not local posteriors (that would count the prior twice).

A base may also start knowing nothing (``Y = 0``: no prior), as a base station does before the first packets arrive.
For a linear motion model the prediction is then made in information form, which needs no inverse of ``Y``::

    M = F⁻ᵀ Y F⁻¹,   Y⁻ = (I + M Q)⁻¹ M,   ŷ⁻ = (I + M Q)⁻¹ F⁻ᵀ ŷ

(the same as the covariance form when ``Y`` is invertible: ``(M⁻¹ + Q)⁻¹ = (I + M Q)⁻¹ M``); the estimate exists once
the packets have made ``Y`` positive definite (for the CV model, position information from two scan times).

On a UAV, :class:`InformationReporter` is the estimator of that scheme: its tracker (the ``scif`` information filter)
takes each scan at the step time as an information contribution (:meth:`SingleTargetTracker.step_information`),
adds it to its own prior (the local EIF update) and keeps it to send to the base.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from autonomy.estimation.base import TIME_TOLERANCE
from autonomy.estimation.measurements import MeasurementLike, MeasurementModel, measurement_model
from autonomy.estimation.models import MotionModel
from autonomy.estimation.scif import add_information
from autonomy.estimation.tracker import SingleTargetTracker
from interfaces.state import TargetEstimate

__all__ = ["InformationContribution", "information_contribution", "sample_received", "BaseStationFusion",
           "InformationReporter"]

VALID_CONDITION = 1e12
"""Largest condition number of ``Y`` for which the base holds an estimate (a singular ``Y`` leaves some direction
of the state without information)."""


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
        Target motion model (linear or not; nonlinear models are linearised at the current estimate and need a prior).
    x0, P0 : ndarray | None
        Initial estimate and covariance; both None for no prior (``Y = 0``, a linear model only).
    t0 : float
        Time of ``x0``, s.
    """

    def __init__(self, model: MotionModel, x0: np.ndarray | None = None, P0: np.ndarray | None = None,
                 t0: float = 0.0) -> None:
        self.model = model
        self.layout = model.layout
        self.t = float(t0)
        if (x0 is None) != (P0 is None):
            raise ValueError("BaseStationFusion needs both x0 and P0, or neither (no prior)")
        if x0 is None:
            if not model.is_linear:
                raise ValueError(f"BaseStationFusion without a prior needs a linear motion model, got "
                                 f"{type(model).__name__}")
            self.Y = np.zeros((model.n, model.n))
            self.y = np.zeros(model.n)
        else:
            self.Y = np.linalg.inv(np.asarray(P0, dtype=float))
            self.y = self.Y @ np.asarray(x0, dtype=float)
        self.n_received = 0
        self.n_lost = 0

    @property
    def valid(self) -> bool:
        """Whether ``Y`` is positive definite (condition number below :data:`VALID_CONDITION`): an estimate exists."""
        w = np.linalg.eigvalsh(0.5 * (self.Y + self.Y.T))
        return bool(w[0] > 0 and w[-1] < VALID_CONDITION * w[0])

    @property
    def x(self) -> np.ndarray:
        """State estimate ``Y⁻¹ y``."""
        return np.linalg.solve(self.Y, self.y)

    @property
    def P(self) -> np.ndarray:
        """Covariance ``Y⁻¹``."""
        P = np.linalg.inv(self.Y)
        return 0.5 * (P + P.T)

    def _predicted(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """``(Y⁻, ŷ⁻)`` at ``t`` (s) without changing the filter."""
        dt = float(t) - self.t
        if dt < -TIME_TOLERANCE:
            raise ValueError(f"cannot predict backwards: t={t} < base time {self.t}")
        if dt <= TIME_TOLERANCE:
            return self.Y, self.y
        if self.model.is_linear:  # information form (module docstring): valid for any Y, also singular
            F = self.model.jacobian(self.y, dt)
            Q = self.model.process_noise(dt)
            F_inv_T = np.linalg.inv(F).T
            M = F_inv_T @ self.Y @ F_inv_T.T
            A = np.eye(self.model.n) + M @ Q
            Y, y = np.linalg.solve(A, M), np.linalg.solve(A, F_inv_T @ self.y)
        else:
            x, P = self.x, self.P
            F = self.model.jacobian(x, dt)
            x = self.model.propagate(x, dt)
            P = F @ P @ F.T + self.model.process_noise(dt, x)
            Y = np.linalg.inv(0.5 * (P + P.T))
            y = Y @ x
        return 0.5 * (Y + Y.T), y

    def predict(self, t: float) -> None:
        """Information prediction to absolute time ``t`` (s)."""
        self.Y, self.y = self._predicted(t)
        self.t = max(self.t, float(t))

    def estimate(self, t: float) -> TargetEstimate | None:
        """The estimate predicted to ``t`` (s) (the filter is not changed), or None while ``Y`` is singular.

        The layout must name ``x``, ``y``, ``vx``, ``vy``.
        """
        if not self.valid:
            return None
        Y, y = self._predicted(t)
        P = np.linalg.inv(Y)
        x = P @ y
        idx = [self.layout.index(k) for k in ("x", "y", "vx", "vy")]
        return TargetEstimate(t=max(float(t), self.t), p_W=x[idx[:2]], v_W=x[idx[2:]],
                              P=0.5 * (P + P.T)[np.ix_(idx, idx)])

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


class InformationReporter:
    """A UAV's estimator under base-station fusion: a local EIF whose scan information also goes to the base.

    At each step the tracker absorbs the detections with :meth:`SingleTargetTracker.step_information` (initiation,
    gating and association as usual; the scans taken at the step time give their information contribution against the
    track's prior), adds that contribution to the prior (the local update, ``S_h = tria([S_h⁻, S_I])``,
    ``ĥ = ĥ⁻ + i``) and keeps it in :attr:`contribution` as the packet for the base (None when the step gave none:
    no track yet, or no gated detection at the step time).

    Parameters
    ----------
    tracker : SingleTargetTracker
        The UAV's tracker; needs the ``scif`` filter.
    """

    def __init__(self, tracker: SingleTargetTracker) -> None:
        if tracker.config.filter != "scif":
            raise TypeError(f"InformationReporter needs the information filter (scif), not {tracker.config.filter!r}")
        self.tracker = tracker
        self.layout = tracker.layout
        self.contribution: InformationContribution | None = None

    def step(self, t: float, detections: Sequence[object]) -> TargetEstimate | None:
        """Absorb ``detections`` (sorted by ``t_meas``) and return the local estimate at ``t`` (s), or None."""
        info = self.tracker.step_information(t, detections)
        self.contribution = None
        if info is None:
            return None
        if info.contribution is not None:
            c = info.contribution
            self.tracker.set_information(add_information(info.prior, c))
            self.contribution = InformationContribution(info_matrix=c.Y, info_vector=np.array(c.h, dtype=float),
                                                        t_meas=info.t)
        return self.tracker.current_estimate()
