"""State-space measurement models ``z = h(x) + v``, ``v ~ N(0, R)`` (radar, bearings, linear position) on a filter's
state layout.

z layouts (d = target − sensor in the ENU world frame, ρ = √(dx² + dy²), r = ‖d‖):

- radar: ``[r, azimuth]``, ``[r, azimuth, elevation]`` or ``[r, azimuth, elevation, range_rate]``;
  azimuth = atan2(dy, dx), elevation = atan2(dz, ρ), range_rate = dᵀ(v_target − v_sensor)/r.
- bearings (passive sensor, camera): ``[azimuth]`` or ``[azimuth, elevation]``.
- position (box): ``[x, y]`` or ``[x, y, z]``.

Paper 000's radar measures the angle from nadir instead of the elevation, ϕ = atan2(ρ, −dz); pass a
:class:`NadirRadarModel` explicitly to a filter's ``update`` for it. Targets whose state has no ``z`` are taken to lie
on the plane ``z = target_height`` (0 m by default: ground vehicles). A measurement's own
:class:`~autonomy.estimation.measurements.DetectionModel` builds the one that fits it
(:meth:`~autonomy.estimation.measurements.DetectionModel.bind`).
"""

from __future__ import annotations

import functools
import math
from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np

__all__ = [
    "MeasurementModel", "RadarModel", "NadirRadarModel", "BearingModel", "PositionModel", "StackedModel",
    "wrap_angle", "state_indices", "TWO_PI",
]

TWO_PI = 2.0 * np.pi
_ZERO3 = np.zeros(3)
_ZERO3.setflags(write=False)
_RADAR_MASKS = {m: np.array([False, True, True, False][:m]) for m in (2, 3, 4)}
_RADAR_IDX = {m: np.flatnonzero(mask) for m, mask in _RADAR_MASKS.items()}


def wrap_angle(a: np.ndarray | float) -> np.ndarray | float:
    """Wrap angles (rad) to ``[−π, π)``."""
    return (a + np.pi) % TWO_PI - np.pi


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

    def linearise_batch(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(h, ∂h/∂x)`` at each row of ``X`` (n, n_state): shapes ``(n, len(z))`` and ``(n, len(z), n_state)``;
        the rows' :meth:`linearise`, stacked (models override it with array arithmetic)."""
        out = [self.linearise(x) for x in X]
        return np.array([z for z, _ in out]), np.array([H for _, H in out])

    def residual_batch(self, Z: np.ndarray, Z_pred: np.ndarray) -> np.ndarray:
        """:meth:`residual` of each row of ``Z`` (n, len(z)) against ``Z_pred``."""
        nu = Z - Z_pred
        idx = np.flatnonzero(self.angle_mask)
        if idx.size:
            nu[:, idx] = (nu[:, idx] + np.pi) % TWO_PI - np.pi
        return nu

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

    def linearise_batch(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.m == 4:
            return super().linearise_batch(X)
        dx, dy, dz = self._d(X.T)
        rho2 = dx * dx + dy * dy
        rho = np.sqrt(rho2)
        r2 = rho2 + dz * dz
        r = np.sqrt(r2)
        Z = np.stack([r, np.arctan2(dy, dx)] + ([np.arctan2(dz, rho)] if self.m == 3 else []), axis=1)
        H = np.zeros((X.shape[0], self.m, self.n_state))
        ix, iy = self.pos[0], self.pos[1]
        H[:, 0, ix], H[:, 0, iy] = dx / r, dy / r
        H[:, 1, ix], H[:, 1, iy] = -dy / rho2, dx / rho2
        if self.has_z:
            H[:, 0, self.pos[2]] = dz / r
        if self.m == 3:
            c = -dz / (rho * r2)
            H[:, 2, ix], H[:, 2, iy] = c * dx, c * dy
            if self.has_z:
                H[:, 2, self.pos[2]] = rho / r2
        return Z, H

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
