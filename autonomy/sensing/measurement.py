"""Measurement types shared by every sensor, and the sensor base class.

A sensor's :meth:`Sensor.measure` returns a :class:`SensorOutput`: the :class:`Detection` list an estimator may
see, and separately the truth association (target id per detection, ``-1`` for clutter) that only the recorder
may read.

Each detection carries its measurement model (:class:`~autonomy.estimation.measurements.DetectionModel`), attached
by the sensor: what the estimators ask for ``h(x)``, its dimension and its name (the ``kind`` the records store).

Measurement layouts (``d = p_target - p_sensor`` in ENU):

- ``"radar"``: ``z = [r, az, el]`` or ``[r, az, el, r_dot]`` with ``r = |d|``, ``az = atan2(d_y, d_x)``,
  ``el = atan2(d_z, hypot(d_x, d_y))``, ``r_dot = d . (v_target - v_sensor) / r``;
- ``"bearing"`` and ``"camera"``: ``z = [az]`` or ``[az, el]`` (world frame);
- ``"box"``: ``z = [x, y]`` with the bounded error ``|z - p_xy| <= bound`` per component.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from autonomy.estimation.measurements import DetectionModel, attach_model

from .scene import SceneQuery, SensorPose, TargetTruth

__all__ = ["CLUTTER_ID", "ClassMeasurement", "Detection", "MeasurementKind", "Sensor",
           "SensorOutput", "azimuth_elevation", "wrap_angle"]

MeasurementKind = Literal["radar", "bearing", "camera", "box"]
CLUTTER_ID = -1


def wrap_angle(a: np.ndarray | float) -> np.ndarray | float:
    """Wrap angles to [-pi, pi) (rad)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def azimuth_elevation(d_W: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Azimuth ``atan2(d_y, d_x)`` and elevation ``atan2(d_z, hypot(d_x, d_y))`` (rad) of vectors (N, 3)."""
    d = np.atleast_2d(d_W)
    return np.arctan2(d[:, 1], d[:, 0]), np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1]))


_CHECKED_CONFUSIONS: dict[int, np.ndarray] = {}
"""Read-only confusion matrices (owning their data) already checked, by id; kept here so that no id is reused."""


@dataclass(frozen=True, kw_only=True)
class ClassMeasurement:
    """A sensor's reading of one class attribute of what it detected (a car's colour, body type, length class).

    Attributes
    ----------
    attribute : str
        Which attribute (``"colour"``, ``"body"``, ``"length"``): the keys of :attr:`TargetTruth.attributes`.
    observed : int
        The class the sensor reported, an index into the attribute's class list (``worlds.catalog``).
    confusion : np.ndarray
        (K, K) row-stochastic confusion matrix of the sensor: ``confusion[true, observed]`` is the probability of
        reporting ``observed`` for a target of class ``true``. An estimator needs nothing else to update a class
        belief by Bayes' rule.
    """

    attribute: str
    observed: int
    confusion: np.ndarray

    def __post_init__(self) -> None:
        C = self.confusion
        if _CHECKED_CONFUSIONS.get(id(C)) is not C:  # a sensor hands the same read-only matrix to every reading
            C = np.array(C, dtype=float)
            if C.ndim != 2 or C.shape[0] != C.shape[1] or C.shape[0] < 1:
                raise ValueError(f"ClassMeasurement.confusion must be a square (K, K) array, got shape {C.shape}")
            if np.any(C < 0) or not np.allclose(C.sum(axis=1), 1.0, atol=1e-9):
                raise ValueError("ClassMeasurement.confusion must have non-negative rows that sum to 1")
            C.setflags(write=False)
            given = self.confusion
            if isinstance(given, np.ndarray) and given.base is None and not given.flags.writeable \
                    and given.dtype == np.float64 and np.array_equal(given, C):
                if len(_CHECKED_CONFUSIONS) >= 256:
                    _CHECKED_CONFUSIONS.clear()
                _CHECKED_CONFUSIONS[id(given)] = given
        if int(self.observed) != self.observed or not 0 <= self.observed < C.shape[0]:
            raise ValueError(f"ClassMeasurement.observed must be a class index in [0, {C.shape[0]}), "
                             f"got {self.observed!r}")
        object.__setattr__(self, "confusion", C)
        object.__setattr__(self, "observed", int(self.observed))

    def likelihood(self) -> np.ndarray:
        """(K,) ``p(observed | true class k)`` for every class k: the column of the confusion matrix."""
        return self.confusion[:, self.observed]


@dataclass(frozen=True, kw_only=True)
class Detection:
    """One measurement.

    Attributes
    ----------
    z : np.ndarray
        (m,) measurement vector in the layout of ``model`` (module docstring): m, rad, m/s.
    R : np.ndarray
        (m, m) noise covariance in the units of ``z`` squared (for ``"box"``: the covariance of the uniform error,
        ``bound**2 / 3``).
    t_meas : float
        When the measurement was taken (s).
    t_arrival : float
        When it reaches the consumer (s), ``t_meas + latency``.
    sensor_id : str
        Which sensor produced it.
    p_sensor_W : np.ndarray
        (3,) sensor position at ``t_meas`` (m).
    model : DetectionModel
        What was measured: ``h(x)`` on any state layout, the dimension, the name; the sensor attaches it (built from
        ``kind`` and ``len(z)`` when not given).
    kind : str
        The model's name, ``"radar"``, ``"bearing"``, ``"camera"`` or ``"box"``: give ``model`` or ``kind`` (a name
        read back from a record); after construction it always equals ``model.name``.
    pixel_box : np.ndarray | None
        Camera only: (4,) ``[u_min, v_min, u_max, v_max]`` of the detected blob (px, continuous coordinates).
    bound : np.ndarray | None
        Box sensor only: (m,) half-widths of the bounded error, so the truth lies in ``[z - bound, z + bound]`` (m).
    classes : tuple[ClassMeasurement, ...]
        The sensor's class readings of the detected object (a camera's colour and body type, a radar's length class
        from its range profile); empty for sensors that classify nothing and for false alarms' attributes drawn
        from the background population.
    """

    z: np.ndarray
    R: np.ndarray
    t_meas: float
    t_arrival: float
    sensor_id: str
    p_sensor_W: np.ndarray
    model: DetectionModel | None = None
    kind: MeasurementKind | None = None
    pixel_box: np.ndarray | None = None
    bound: np.ndarray | None = None
    classes: tuple[ClassMeasurement, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "classes", tuple(self.classes))
        z = np.array(self.z, dtype=float).reshape(-1)
        R = np.array(self.R, dtype=float)
        if R.shape != (z.size, z.size):
            raise ValueError(f"Detection.R must be ({z.size}, {z.size}), got {R.shape}")
        if self.t_arrival < self.t_meas:
            raise ValueError(f"Detection.t_arrival ({self.t_arrival}) must be >= t_meas ({self.t_meas})")
        try:
            model = attach_model(self.model, self.kind, z.size)
        except ValueError as e:
            raise ValueError(f"Detection.model: {e}") from None
        if model.name not in ("radar", "bearing", "camera", "box"):
            raise ValueError(f"Detection.kind must be radar|bearing|camera|box, got {model.name!r}")
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "kind", model.name)
        for arr in (z, R):
            arr.setflags(write=False)
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "p_sensor_W", np.array(self.p_sensor_W, dtype=float).reshape(3))


@dataclass(frozen=True, kw_only=True)
class SensorOutput:
    """What one scan produced.

    Attributes
    ----------
    detections : tuple[Detection, ...]
        Measurements for the estimators (in random order: the order carries no truth).
    truth_ids : np.ndarray
        (len(detections),) target id behind each detection, ``-1`` for a false alarm; for the recorder only.
    extras : dict[str, Any]
        Sensor-specific by-products that are not truth (the box sensor's observed region, a camera frame).
    """

    detections: tuple[Detection, ...] = ()
    truth_ids: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    extras: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        ids = np.array(self.truth_ids, dtype=int).reshape(-1)
        if ids.size != len(self.detections):
            raise ValueError(f"SensorOutput.truth_ids has {ids.size} entries for {len(self.detections)} detections")
        object.__setattr__(self, "truth_ids", ids)
        object.__setattr__(self, "detections", tuple(self.detections))


class Sensor(ABC):
    """A sensor model: one main method, :meth:`measure`.

    Subclasses expose ``sensor_id`` (str), ``rate_hz`` (scans per second) and ``latency_s`` (s).
    """

    sensor_id: str
    rate_hz: float
    latency_s: float

    @abstractmethod
    def measure(
        self, tick_time_s: float, pose: SensorPose, targets: TargetTruth, scene: SceneQuery, rng: np.random.Generator
    ) -> SensorOutput:
        """Scan at ``tick_time_s`` (s) from ``pose``; ``rng`` supplies all randomness."""
