"""Measurements and their models (radar, bearings, linear position).

Every measurement carries its :class:`DetectionModel` (``meas.model``), attached by the sensor that made it: the
model knows the measurement's name (``"radar"``, ``"bearing"``, ``"camera"``, ``"box"``: what the records call its
``kind``), its dimension, which components are angles, the state-space model ``z = h(x) + v`` on a filter's state
layout (:meth:`DetectionModel.bind`, with ``h``, its Jacobian and the residual), and, where one measurement alone
fixes a ground position, its inverse (:meth:`DetectionModel.ground_fix`). Filters and trackers ask the model; nothing
dispatches on the name.

The z layouts and the state-space models are in :mod:`autonomy.estimation.measurement_models` (re-exported here):
``"radar"`` ``[r, az(, el(, ṙ))]``, ``"bearing"`` / ``"camera"`` ``[az(, el)]``, ``"box"`` ``[x, y(, z)]``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import ClassVar, Protocol, runtime_checkable

import numpy as np

from autonomy.estimation.measurement_models import (
    BearingModel,
    MeasurementModel,
    NadirRadarModel,
    PositionModel,
    RadarModel,
    StackedModel,
    state_indices,
    wrap_angle,
)

__all__ = [
    "MeasurementLike", "Measurement", "StackedMeasurement", "MeasurementModel", "RadarModel", "NadirRadarModel",
    "BearingModel", "PositionModel", "StackedModel", "measurement_model", "wrap_angle", "state_indices",
    "DetectionModel", "RadarDetectionModel", "BearingDetectionModel", "PositionDetectionModel",
    "StackedDetectionModel", "attach_model", "detection_model",
]


@runtime_checkable
class MeasurementLike(Protocol):
    """What a filter needs from a measurement (the sensing layer's ``Detection`` satisfies it)."""

    z: np.ndarray
    R: np.ndarray
    t_meas: float
    t_arrival: float
    sensor_id: int | str
    p_sensor_W: np.ndarray
    model: DetectionModel


@dataclass(frozen=True, kw_only=True, eq=False)
class Measurement:
    """A timestamped measurement.

    Attributes
    ----------
    z : ndarray
        Measured values, layout set by ``model`` (see the module docstring); m, rad, m/s.
    R : ndarray
        Noise covariance of ``z``, same units squared.
    t_meas : float
        Time the measurement was taken, s.
    t_arrival : float
        Time it reached the estimator, s (``>= t_meas``).
    sensor_id : int or str
        Which sensor took it.
    p_sensor_W : ndarray
        Sensor position in the world frame at ``t_meas``, m (3,).
    model : DetectionModel
        What was measured (:class:`DetectionModel`); built from ``kind`` and ``len(z)`` when not given.
    kind : str
        The model's name, ``"radar"`` (the default), ``"bearing"``, ``"camera"`` or ``"box"``: give ``model`` or
        ``kind`` (a name read back from a record); after construction it always equals ``model.name``.
    v_sensor_W : ndarray or None
        Sensor velocity in the world frame, m/s (used by range rate; zero if None).
    """

    z: np.ndarray
    R: np.ndarray
    t_meas: float
    t_arrival: float | None = None
    sensor_id: int | str = 0
    p_sensor_W: np.ndarray = field(default_factory=lambda: np.zeros(3))
    model: DetectionModel | None = None
    kind: str | None = None
    v_sensor_W: np.ndarray | None = None

    def __post_init__(self) -> None:
        z = np.atleast_1d(np.asarray(self.z, dtype=float))
        R = np.atleast_2d(np.asarray(self.R, dtype=float))
        if R.shape != (z.size, z.size):
            raise ValueError(f"R must have shape {(z.size, z.size)} for z of length {z.size}, got {R.shape}")
        if not np.allclose(R, R.T):
            raise ValueError(f"R must be symmetric, got {R!r}")
        model = attach_model(self.model, self.kind, z.size, default="radar")
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "kind", model.name)
        t_arr = self.t_meas if self.t_arrival is None else self.t_arrival
        if t_arr < self.t_meas:
            raise ValueError(f"t_arrival must be >= t_meas={self.t_meas}, got {t_arr}")
        p = np.asarray(self.p_sensor_W, dtype=float).reshape(-1)
        if p.size not in (2, 3):
            raise ValueError(f"p_sensor_W must have 2 or 3 components, got {p.size}")
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "t_arrival", float(t_arr))
        object.__setattr__(self, "p_sensor_W", p if p.size == 3 else np.append(p, 0.0))


@dataclass(frozen=True, kw_only=True, eq=False)
class StackedMeasurement:
    """Several simultaneous measurements treated as one (paper 003's centralised augmented measurement).

    ``z`` is the concatenation of the parts' ``z``; ``R`` their block diagonal; ``t_meas`` the common time (s).
    """

    parts: tuple[MeasurementLike, ...]

    def __post_init__(self) -> None:
        if len(self.parts) == 0:
            raise ValueError("parts must hold at least one measurement, got none")
        ts = {float(m.t_meas) for m in self.parts}
        if len(ts) != 1:
            raise ValueError(f"parts must share one t_meas, got {sorted(ts)}")

    @property
    def z(self) -> np.ndarray:
        """Concatenated measurements."""
        return np.concatenate([np.atleast_1d(m.z) for m in self.parts])

    @property
    def R(self) -> np.ndarray:
        """Block-diagonal noise covariance."""
        sizes = [np.atleast_1d(m.z).size for m in self.parts]
        R = np.zeros((sum(sizes), sum(sizes)))
        k = 0
        for m, s in zip(self.parts, sizes, strict=True):
            R[k:k + s, k:k + s] = m.R
            k += s
        return R

    @property
    def t_meas(self) -> float:
        """Common measurement time, s."""
        return float(self.parts[0].t_meas)

    @property
    def t_arrival(self) -> float:
        """Latest arrival among the parts, s."""
        return max(float(m.t_arrival) for m in self.parts)

    @property
    def model(self) -> StackedDetectionModel:
        """The parts' models, stacked."""
        return StackedDetectionModel(parts=tuple(m.model for m in self.parts))

    sensor_id = "stacked"
    kind = "stacked"


def measurement_model(meas: MeasurementLike, layout: tuple[str, ...], target_height: float = 0.0) -> MeasurementModel:
    """The state-space model of ``meas`` on a state ``layout``: ``meas.model.bind(meas, layout, target_height)``."""
    return meas.model.bind(meas, layout, target_height)


class DetectionModel(ABC):
    """What one measurement is, as the sensor that made it declares it (Stone Soup's ``measurement_model`` of a
    detection): a name, a dimension, angle components, ``h(x)`` on any state layout and, where it exists, the inverse
    to a ground position.

    Attributes
    ----------
    name : str
        The measurement's name, as the records call its ``kind``.
    dim : int
        Length of ``z``.
    fixes_position : bool
        Whether one such measurement alone fixes a ground position (:meth:`ground_fix` gives it).
    """

    name: str
    dim: int
    fixes_position: ClassVar[bool] = False

    @abstractmethod
    def bind(self, meas: MeasurementLike, layout: tuple[str, ...], target_height: float = 0.0) -> MeasurementModel:
        """``z = h(x) + v`` for ``meas`` (its sensor pose) on the state ``layout``; targets without a ``z`` state lie
        on the plane ``z = target_height`` (m). The model gives ``h``, its Jacobian and the wrapped residual; the
        noise covariance is ``meas.R``."""

    def ground_fix(self, meas: MeasurementLike, target_height: float = 0.0) -> tuple[np.ndarray, np.ndarray] | None:
        """Ground position ``(x, y)`` (m) and its 2x2 covariance (m²) from ``meas`` alone (the inverse of ``h``), or
        None if one such measurement cannot fix a position."""
        return None

    def bearing_line(self, meas: MeasurementLike) -> tuple[float, float] | None:
        """``(azimuth, variance)`` (rad, rad²) of the line of sight of a bearing-only measurement, or None for any
        other (crossing lines of several bearings fix a position)."""
        return None

    def _check_dim(self, allowed: tuple[int, ...]) -> None:
        if self.dim not in allowed:
            raise ValueError(f"{type(self).__name__}.dim must be one of {allowed} for {self.name!r}, got {self.dim!r}")


@dataclass(frozen=True, kw_only=True)
class RadarDetectionModel(DetectionModel):
    """Radar ``[r, az]``, ``[r, az, el]`` or ``[r, az, el, ṙ]`` (module docstring); ``dim`` is the length of ``z``."""

    dim: int
    name: str = field(default="radar", init=False)
    fixes_position: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._check_dim((2, 3, 4))

    def bind(self, meas: MeasurementLike, layout: tuple[str, ...], target_height: float = 0.0) -> RadarModel:
        return RadarModel(layout, meas.p_sensor_W, self.dim, getattr(meas, "v_sensor_W", None), target_height)

    def ground_fix(self, meas: MeasurementLike, target_height: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Range and azimuth to a point on the plane ``z = target_height``: the ground range ``ρ = √(r² − Δz²)``
        (0 where ``r ≤ |Δz|``) along the azimuth.

        Its covariance, away from the nadir (the range one standard deviation short, ``r − σ_r``, still reaches the
        plane), is first-order: the range error along the line of sight scaled by ``r/ρ``, the azimuth error across
        it. Nearer the nadir ``ρ`` is no function of ``r`` a tangent describes (it stops at 0, and ``r/ρ`` grows
        without bound), and the first-order covariance is far too small (at the nadir, no spread across the
        azimuth at all). There the ground range's standard deviation is the larger one-sided change of ``ρ`` over
        ``r ± σ_r`` (``ρ`` clipped at 0; a range short of the plane counts as reaching it), and the azimuth error
        acts on the true ground range, anywhere in that spread: variance ``(ρ² + σ_ρ²) σ_az²`` across (range and
        azimuth errors taken independent)."""
        z = np.asarray(meas.z, dtype=float)
        R = np.asarray(meas.R, dtype=float)
        p_s = np.asarray(meas.p_sensor_W, dtype=float)
        rng, az = z[0], z[1]
        dz = target_height - p_s[2]

        def ground(r: float) -> float:  # the ground range of slant range r
            return float(np.sqrt(max(r * r - dz * dz, 0.0)))

        rho = ground(rng)
        u = np.array([np.cos(az), np.sin(az)])
        xy = p_s[:2] + rho * u
        sigma_r = float(np.sqrt(max(R[0, 0], 0.0)))
        if rng - sigma_r <= abs(dz):  # near the nadir (docstring)
            s_rho = max(ground(max(rng, abs(dz)) + sigma_r) - rho, rho - ground(rng - sigma_r))
            n = np.array([-u[1], u[0]])
            return xy, s_rho**2 * np.outer(u, u) + (rho * rho + s_rho**2) * R[1, 1] * np.outer(n, n)
        along = (rng / rho) if rho > 1e-6 else 1.0
        J = np.array([[np.cos(az) * along, -rho * np.sin(az)], [np.sin(az) * along, rho * np.cos(az)]])
        P = J @ R[:2, :2] @ J.T
        return xy, P


@dataclass(frozen=True, kw_only=True)
class BearingDetectionModel(DetectionModel):
    """Bearings ``[az]`` or ``[az, el]`` of a passive sensor (``name="bearing"``) or a camera (``name="camera"``)."""

    dim: int
    name: str = "bearing"

    def __post_init__(self) -> None:
        if self.name not in ("bearing", "camera"):
            raise ValueError(f"BearingDetectionModel.name must be 'bearing' or 'camera', got {self.name!r}")
        self._check_dim((1, 2))

    def bind(self, meas: MeasurementLike, layout: tuple[str, ...], target_height: float = 0.0) -> BearingModel:
        return BearingModel(layout, meas.p_sensor_W, self.dim, target_height)

    def bearing_line(self, meas: MeasurementLike) -> tuple[float, float]:
        return float(np.atleast_1d(meas.z)[0]), float(np.atleast_2d(meas.R)[0, 0])


@dataclass(frozen=True, kw_only=True)
class PositionDetectionModel(DetectionModel):
    """A position ``[x, y]`` or ``[x, y, z]`` (the bounded-error box sensor)."""

    dim: int
    name: str = field(default="box", init=False)
    fixes_position: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._check_dim((2, 3))

    def bind(self, meas: MeasurementLike, layout: tuple[str, ...], target_height: float = 0.0) -> PositionModel:
        return PositionModel(layout, self.dim)

    def ground_fix(self, meas: MeasurementLike, target_height: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        z = np.asarray(meas.z, dtype=float)
        R = np.asarray(meas.R, dtype=float)
        return z[:2].copy(), R[:2, :2].copy()


@dataclass(frozen=True, kw_only=True)
class StackedDetectionModel(DetectionModel):
    """The models of a :class:`StackedMeasurement`'s parts, rows stacked."""

    parts: tuple[DetectionModel, ...]
    name: str = field(default="stacked", init=False)

    @property
    def dim(self) -> int:  # type: ignore[override]
        return sum(m.dim for m in self.parts)

    def bind(self, meas: MeasurementLike, layout: tuple[str, ...], target_height: float = 0.0) -> StackedModel:
        return StackedModel([p.model.bind(p, layout, target_height) for p in meas.parts])  # type: ignore[attr-defined]


def detection_model(name: str, dim: int) -> DetectionModel:
    """The model called ``name`` (``"radar"``, ``"bearing"``, ``"camera"`` or ``"box"``) for a ``z`` of length
    ``dim``: how a measurement read back from a record by its ``kind`` gets its model."""
    if name == "radar":
        return RadarDetectionModel(dim=dim)
    if name in ("bearing", "camera"):
        return BearingDetectionModel(dim=dim, name=name)
    if name == "box":
        return PositionDetectionModel(dim=dim)
    raise ValueError(f"kind must be 'radar', 'bearing', 'camera' or 'box', got {name!r}")


def attach_model(model: DetectionModel | None, kind: str | None, dim: int,
                 default: str | None = None) -> DetectionModel:
    """A measurement's model from its constructor's ``model`` or ``kind`` (a name, :func:`detection_model`;
    ``default`` when both are None), checked against the length ``dim`` of its ``z``."""
    if model is None:
        if kind is None and default is None:
            raise ValueError("a measurement needs its model (or the kind that names it)")
        model = detection_model(default if kind is None else kind, dim)
    elif kind is not None and kind != model.name:
        raise ValueError(f"kind {kind!r} contradicts the model {model.name!r}")
    if model.dim != dim:
        raise ValueError(f"z has {dim} components, the {model.name!r} model {model.dim}")
    return model
