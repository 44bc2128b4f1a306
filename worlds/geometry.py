"""Static obstacles of a world: buildings as extruded footprints (cuboids are the common case).

Frames: world ENU, metres; yaw counter-clockwise from +x, radians.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Building"]


@dataclass(frozen=True, kw_only=True)
class Building:
    """A building: a simple polygon footprint extruded from ``base_z`` up to ``base_z + height``.

    Attributes
    ----------
    footprint : np.ndarray
        (K, 2) polygon vertices in the world x-y plane, counter-clockwise, not closed (m).
    height : float
        Height above ``base_z`` (m), > 0.
    base_z : float
        Ground level of the footprint (m).
    name : str
        Optional label (an OSM id, ``"b17"``); not used by physics.
    """

    footprint: np.ndarray
    height: float
    base_z: float = 0.0
    name: str = ""
    _cuboid: tuple[float, float, float, float, float] | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        fp = np.asarray(self.footprint, dtype=float)
        if fp.ndim != 2 or fp.shape[1] != 2 or fp.shape[0] < 3:
            raise ValueError(f"Building.footprint must be (K>=3, 2), got shape {fp.shape}")
        if not np.all(np.isfinite(fp)):
            raise ValueError("Building.footprint has non-finite vertices")
        if not (self.height > 0):
            raise ValueError(f"Building.height must be > 0 m, got {self.height}")
        x, y = fp[:, 0], fp[:, 1]
        area2 = float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
        if area2 == 0.0:
            raise ValueError("Building.footprint has zero area")
        if area2 < 0:
            fp = fp[::-1].copy()
        fp.setflags(write=False)
        object.__setattr__(self, "footprint", fp)

    @classmethod
    def cuboid(cls, center: tuple[float, float], size: tuple[float, float, float], yaw: float = 0.0,
               base_z: float = 0.0, name: str = "") -> "Building":
        """A box of ``size`` = (length along yaw, width, height) m centred at ``center`` (x, y) m on the ground."""
        sx, sy, sz = (float(v) for v in size)
        if sx <= 0 or sy <= 0 or sz <= 0:
            raise ValueError(f"Building size must be positive, got {size}")
        c, s = np.cos(yaw), np.sin(yaw)
        half = np.array([[sx, sy], [-sx, sy], [-sx, -sy], [sx, -sy]]) / 2.0
        half = half[[2, 3, 0, 1]]  # start at (-,-) and go counter-clockwise
        R = np.array([[c, -s], [s, c]])
        fp = half @ R.T + np.asarray(center, dtype=float)
        b = cls(footprint=fp, height=sz, base_z=base_z, name=name)
        object.__setattr__(b, "_cuboid", (float(center[0]), float(center[1]), sx, sy, float(yaw)))
        return b

    @property
    def is_cuboid(self) -> bool:
        return self._cuboid is not None

    @property
    def cuboid_params(self) -> tuple[np.ndarray, np.ndarray, float]:
        """(centre (3,) m, full size (3,) m, yaw rad) of a cuboid building; raises for general footprints."""
        if self._cuboid is None:
            raise ValueError("not a cuboid building")
        cx, cy, sx, sy, yaw = self._cuboid
        return np.array([cx, cy, self.base_z + self.height / 2]), np.array([sx, sy, self.height]), yaw

    @property
    def top_z(self) -> float:
        return self.base_z + self.height
