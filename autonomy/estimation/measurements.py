"""Measurements and their models (radar, bearings, linear position).

Every measurement carries its :class:`DetectionModel` (``meas.model``), attached by the sensor that made it: the
model knows the measurement's name (``"radar"``, ``"bearing"``, ``"camera"``, ``"box"``: what the records call its
``kind``), its dimension, which components are angles, the state-space model ``z = h(x) + v`` on a filter's state
layout (:meth:`DetectionModel.bind`, with ``h``, its Jacobian and the residual), and, where one measurement alone
fixes a ground position, its inverse (:meth:`DetectionModel.ground_fix`). Filters and trackers ask the model; nothing
dispatches on the name.

z layouts (d = target − sensor in the ENU world frame, ρ = √(dx² + dy²), r = ‖d‖):

- ``"radar"``: ``[r, azimuth]``, ``[r, azimuth, elevation]`` or ``[r, azimuth, elevation, range_rate]``;
  azimuth = atan2(dy, dx), elevation = atan2(dz, ρ), range_rate = dᵀ(v_target − v_sensor)/r.
- ``"bearing"`` / ``"camera"``: ``[azimuth]`` or ``[azimuth, elevation]``.
- ``"box"``: ``[x, y]`` or ``[x, y, z]`` (a position).

Paper 000's radar measures the angle from nadir instead of the elevation, ϕ = atan2(ρ, −dz); pass a
:class:`NadirRadarModel` explicitly to a filter's ``update`` for it. Targets whose state has no ``z`` are taken to lie
on the plane ``z = target_height`` (0 m by default: ground vehicles).
"""

from __future__ import annotations

import functools
import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar, Protocol, runtime_checkable

import numpy as np

__all__ = [
    "MeasurementLike", "Measurement", "StackedMeasurement", "MeasurementModel", "RadarModel", "NadirRadarModel",
    "BearingModel", "PositionModel", "StackedModel", "measurement_model", "wrap_angle", "state_indices",
    "DetectionModel", "RadarDetectionModel", "BearingDetectionModel", "PositionDetectionModel",
    "StackedDetectionModel", "attach_model", "detection_model",
]

TWO_PI = 2.0 * np.pi
_ZERO3 = np.zeros(3)
_ZERO3.setflags(write=False)
_RADAR_MASKS = {m: np.array([False, True, True, False][:m]) for m in (2, 3, 4)}
_RADAR_IDX = {m: np.flatnonzero(mask) for m, mask in _RADAR_MASKS.items()}


def wrap_angle(a: np.ndarray | float) -> np.ndarray | float:
    """Wrap angles (rad) to ``[−π, π)``."""
    return (a + np.pi) % TWO_PI - np.pi


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


@functools.lru_cache(maxsize=32)
def state_indices(layout: tuple[str, ...]) -> tuple[tuple[int, ...], tuple[int, ...] | None]:
    """Indices of the position components (x, y[, z]) and velocity components (vx, vy[, vz]) in ``layout``."""
    pos = tuple(layout.index(a) for a in ("x", "y", "z") if a in layout)
    if len(pos) < 2 or pos[:2] != (layout.index("x"), layout.index("y")):
        raise ValueError(f"layout must contain 'x' and 'y', got {layout}")
    vel_names = ("vx", "vy", "vz")[: len(pos)]
    vel = tuple(layout.index(v) for v in vel_names) if all(v in layout for v in vel_names) else None
    return pos, vel


class MeasurementModel(ABC):
    """``z = h(x) + v``, ``v ~ N(0, R)``. ``angle_mask`` flags the components that are angles (residuals wrapped)."""

    angle_mask: np.ndarray
    n_state: int
    _angle_idx: np.ndarray | None = None

    @abstractmethod
    def h(self, X: np.ndarray) -> np.ndarray:
        """Predicted measurement of a state ``(n,)`` or of columns of states ``(n, m)``."""

    @abstractmethod
    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """``∂h/∂x`` at ``x``, shape ``(len(z), n)``."""

    def linearise(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(h(x), ∂h/∂x)`` at one state (models override it to share the geometry between the two)."""
        return self.h(x), self.jacobian(x)

    def residual(self, z: np.ndarray, z_pred: np.ndarray) -> np.ndarray:
        """``z − z_pred`` with angle components wrapped to ``[−π, π)``."""
        nu = z - z_pred
        idx = self._angle_idx
        if idx is None:
            idx = self._angle_idx = np.flatnonzero(self.angle_mask)
        if idx.size:
            nu[idx] = (nu[idx] + np.pi) % TWO_PI - np.pi
        return nu


class _Geometric(MeasurementModel):
    """Shared geometry: relative position ``d = p_target − p_sensor`` from the state."""

    def __init__(self, layout: tuple[str, ...], p_sensor_W: np.ndarray, target_height: float = 0.0) -> None:
        self.n_state = len(layout)
        self.pos, self.vel = state_indices(layout)
        self.p_s = p_sensor_W if isinstance(p_sensor_W, np.ndarray) else np.asarray(p_sensor_W, dtype=float)
        self.target_height = float(target_height)
        self.has_z = len(self.pos) == 3

    def _d(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        dx = X[self.pos[0]] - self.p_s[0]
        dy = X[self.pos[1]] - self.p_s[1]
        dz = (X[self.pos[2]] if self.has_z else self.target_height) - self.p_s[2]
        return dx, dy, dz + 0.0 * dx

    def _d_single(self, x: np.ndarray) -> tuple[float, float, float]:
        p, s = self.pos, self.p_s
        dz = (float(x[p[2]]) if self.has_z else self.target_height) - s[2]
        return float(x[p[0]] - s[0]), float(x[p[1]] - s[1]), float(dz)

    def _put_pos(self, H: np.ndarray, row: int, g: np.ndarray) -> None:
        """Write the gradient ``g`` w.r.t. (x, y, z) into row ``row`` (the z part is dropped for planar states)."""
        H[row, self.pos[0]] = g[0]
        H[row, self.pos[1]] = g[1]
        if self.has_z:
            H[row, self.pos[2]] = g[2]


class RadarModel(_Geometric):
    """Radar ``[r, az]``, ``[r, az, el]`` or ``[r, az, el, ṙ]`` (see the module docstring)."""

    def __init__(self, layout: tuple[str, ...], p_sensor_W: np.ndarray, m: int = 3,
                 v_sensor_W: np.ndarray | None = None, target_height: float = 0.0) -> None:
        super().__init__(layout, p_sensor_W, target_height)
        if m not in (2, 3, 4):
            raise ValueError(f"radar z must have 2, 3 or 4 components, got {m}")
        if m == 4 and self.vel is None:
            raise ValueError(f"range rate needs velocities in the state layout, got {layout}")
        self.m = m
        self.v_s = _ZERO3 if v_sensor_W is None else np.asarray(v_sensor_W, dtype=float)
        self.angle_mask = _RADAR_MASKS[m]
        self._angle_idx = _RADAR_IDX[m]

    def h(self, X: np.ndarray) -> np.ndarray:
        if X.ndim == 1:
            return self._h_single(X)
        dx, dy, dz = self._d(X)
        rho2 = dx * dx + dy * dy
        r = np.sqrt(rho2 + dz * dz)
        out = [r, np.arctan2(dy, dx)]
        if self.m >= 3:
            out.append(np.arctan2(dz, np.sqrt(rho2)))
        if self.m == 4:
            vz = X[self.vel[2]] if self.has_z else 0.0
            v = self.vel
            rr = (dx * (X[v[0]] - self.v_s[0]) + dy * (X[v[1]] - self.v_s[1]) + dz * (vz - self.v_s[2])) / r
            out.append(rr)
        return np.array(out)

    def _h_single(self, x: np.ndarray) -> np.ndarray:
        """Scalar-math evaluation for one state (the EKF hot path)."""
        dx, dy, dz = self._d_single(x)
        rho = math.hypot(dx, dy)
        r = math.hypot(rho, dz)
        if self.m == 2:
            return np.array((r, math.atan2(dy, dx)))
        if self.m == 3:
            return np.array((r, math.atan2(dy, dx), math.atan2(dz, rho)))
        v = self.vel
        vz = float(x[v[2]]) if self.has_z else 0.0
        rr = (dx * (x[v[0]] - self.v_s[0]) + dy * (x[v[1]] - self.v_s[1]) + dz * (vz - self.v_s[2])) / r
        return np.array((r, math.atan2(dy, dx), math.atan2(dz, rho), float(rr)))

    def linearise(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.m == 4:
            return self._h_single(x), self.jacobian(x)
        dx, dy, dz = self._d_single(x)
        rho2 = dx * dx + dy * dy
        rho = math.sqrt(rho2)
        r2 = rho2 + dz * dz
        r = math.sqrt(r2)
        az = math.atan2(dy, dx)
        z = np.array((r, az)) if self.m == 2 else np.array((r, az, math.atan2(dz, rho)))
        return z, self._jacobian(dx, dy, dz, rho2, rho, r2, r, x)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        dx, dy, dz = self._d_single(x)
        rho2 = dx * dx + dy * dy
        rho = math.sqrt(rho2)
        r2 = rho2 + dz * dz
        return self._jacobian(dx, dy, dz, rho2, rho, r2, math.sqrt(r2), x)

    def _jacobian(self, dx: float, dy: float, dz: float, rho2: float, rho: float, r2: float, r: float,
                  x: np.ndarray) -> np.ndarray:
        H = np.zeros((self.m, self.n_state))
        ix, iy = self.pos[0], self.pos[1]
        H[0, ix], H[0, iy] = dx / r, dy / r
        H[1, ix], H[1, iy] = -dy / rho2, dx / rho2
        if self.has_z:
            H[0, self.pos[2]] = dz / r
        if self.m >= 3:
            c = -dz / (rho * r2)
            H[2, ix], H[2, iy] = c * dx, c * dy
            if self.has_z:
                H[2, self.pos[2]] = rho / r2
        if self.m == 4:
            vz = x[self.vel[2]] if self.has_z else 0.0
            v_rel = np.array([x[self.vel[0]], x[self.vel[1]], vz]) - self.v_s
            d = np.array([dx, dy, dz])
            rr = d @ v_rel / r
            self._put_pos(H, 3, (v_rel - rr * d / r) / r)
            H[3, self.vel[0]] = dx / r
            H[3, self.vel[1]] = dy / r
            if self.has_z:
                H[3, self.vel[2]] = dz / r
        return H


class NadirRadarModel(_Geometric):
    """Paper 000's radar ``[r, az, ϕ]`` with ϕ = atan2(ρ, −dz), the angle from nadir (sensor above the target)."""

    def __init__(self, layout: tuple[str, ...], p_sensor_W: np.ndarray, target_height: float = 0.0) -> None:
        super().__init__(layout, p_sensor_W, target_height)
        self.angle_mask = _RADAR_MASKS[3]
        self._angle_idx = _RADAR_IDX[3]

    def h(self, X: np.ndarray) -> np.ndarray:
        dx, dy, dz = self._d(X)
        rho = np.sqrt(dx * dx + dy * dy)
        return np.array([np.sqrt(rho * rho + dz * dz), np.arctan2(dy, dx), np.arctan2(rho, -dz)])

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        dx, dy, dz = self._d_single(x)
        rho2 = dx * dx + dy * dy
        rho = np.sqrt(rho2)
        r2 = rho2 + dz * dz
        r = np.sqrt(r2)
        hh = -dz
        H = np.zeros((3, self.n_state))
        self._put_pos(H, 0, (dx / r, dy / r, dz / r))
        self._put_pos(H, 1, (-dy / rho2, dx / rho2, 0.0))
        self._put_pos(H, 2, (hh * dx / (rho * r2), hh * dy / (rho * r2), rho / r2))
        return H


class BearingModel(_Geometric):
    """Bearings ``[az]`` or ``[az, el]`` (passive sensor or camera)."""

    def __init__(self, layout: tuple[str, ...], p_sensor_W: np.ndarray, m: int = 1,
                 target_height: float = 0.0) -> None:
        super().__init__(layout, p_sensor_W, target_height)
        if m not in (1, 2):
            raise ValueError(f"bearing z must have 1 or 2 components, got {m}")
        self.m = m
        self.angle_mask = np.ones(m, dtype=bool)

    def h(self, X: np.ndarray) -> np.ndarray:
        dx, dy, dz = self._d(X)
        if self.m == 1:
            return np.array([np.arctan2(dy, dx)])
        return np.array([np.arctan2(dy, dx), np.arctan2(dz, np.sqrt(dx * dx + dy * dy))])

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        dx, dy, dz = self._d_single(x)
        rho2 = dx * dx + dy * dy
        H = np.zeros((self.m, self.n_state))
        self._put_pos(H, 0, (-dy / rho2, dx / rho2, 0.0))
        if self.m == 2:
            rho, r2 = np.sqrt(rho2), rho2 + dz * dz
            self._put_pos(H, 1, (-dz * dx / (rho * r2), -dz * dy / (rho * r2), rho / r2))
        return H


class PositionModel(MeasurementModel):
    """Linear position measurement ``z = [x, y]`` or ``[x, y, z]`` (``H`` selects the position components)."""

    def __init__(self, layout: tuple[str, ...], m: int = 2) -> None:
        pos, _ = state_indices(layout)
        if m not in (2, 3) or m > len(pos):
            raise ValueError(f"position z must have 2 or 3 components (at most the state's {len(pos)}), got {m}")
        self.n_state = len(layout)
        self.H = np.zeros((m, self.n_state))
        self.H[np.arange(m), list(pos[:m])] = 1.0
        self.idx = list(pos[:m])
        self.angle_mask = np.zeros(m, dtype=bool)

    def h(self, X: np.ndarray) -> np.ndarray:
        return X[self.idx]

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        return self.H


class StackedModel(MeasurementModel):
    """Concatenation of several measurement models (rows stacked)."""

    def __init__(self, models: Sequence[MeasurementModel]) -> None:
        self.models = tuple(models)
        self.n_state = self.models[0].n_state
        self.angle_mask = np.concatenate([m.angle_mask for m in self.models])

    def h(self, X: np.ndarray) -> np.ndarray:
        return np.concatenate([m.h(X) for m in self.models], axis=0)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        return np.vstack([m.jacobian(x) for m in self.models])


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
        """Range and azimuth to a point on the plane ``z = target_height``; first-order covariance: the range error
        along the line of sight (scaled by ``r/ρ``), the azimuth error across it."""
        z = np.asarray(meas.z, dtype=float)
        R = np.asarray(meas.R, dtype=float)
        p_s = np.asarray(meas.p_sensor_W, dtype=float)
        rng, az = z[0], z[1]
        dz = target_height - p_s[2]
        rho2 = rng * rng - dz * dz
        rho = np.sqrt(rho2) if rho2 > 0 else 0.0
        xy = p_s[:2] + rho * np.array([np.cos(az), np.sin(az)])
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
