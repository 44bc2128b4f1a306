"""Keep-out regions around buildings for horizontal path planning at a fixed altitude.

A cuboid footprint with half-sides (a, b) inflated by a margin m is enclosed by the ellipse with semi-axes
(√2 (a + m), √2 (b + m)) in the building frame (the corners (a + m, b + m) lie on it), so a point outside the ellipse is
at least m away from the footprint: the constraint is conservative. A general footprint gets the circle about its
vertex centroid through its farthest vertex, inflated by m. The smooth constraint used by the planner is

    h(p) = | diag(1/α, 1/β) R(yaw)ᵀ (p − c) |² − 1 ≥ 0 .

The exact signed horizontal distance to a footprint (negative inside) is given by :func:`footprint_distance` for checks.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from worlds.geometry import Building

__all__ = ["KeepOutEllipse", "keepout_ellipse", "footprint_distance", "nearby_keepouts"]


@dataclass(frozen=True, kw_only=True)
class KeepOutEllipse:
    """An ellipse the planner keeps out of.

    Attributes
    ----------
    center : np.ndarray
        (2,) centre in the world x-y plane (m).
    yaw : float
        Orientation of the first semi-axis from +x (rad).
    semi_axes : np.ndarray
        (2,) semi-axes (α, β) (m), > 0.
    """

    center: np.ndarray
    yaw: float
    semi_axes: np.ndarray

    def __post_init__(self) -> None:
        c = np.asarray(self.center, dtype=float).reshape(-1)
        ax = np.asarray(self.semi_axes, dtype=float).reshape(-1)
        if c.shape != (2,) or ax.shape != (2,) or not np.all(ax > 0):
            raise ValueError(f"KeepOutEllipse needs center (2,) and positive semi_axes (2,), "
                             f"got {self.center}, {self.semi_axes}")
        object.__setattr__(self, "center", c)
        object.__setattr__(self, "semi_axes", ax)

    def h(self, p_W: np.ndarray) -> np.ndarray:
        """Constraint value |diag(1/α, 1/β) Rᵀ (p − c)|² − 1 (−) at points ``p_W`` (..., 2); >= 0 outside."""
        d = np.asarray(p_W, dtype=float)[..., :2] - self.center
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        lx = (c * d[..., 0] + s * d[..., 1]) / self.semi_axes[0]
        ly = (-s * d[..., 0] + c * d[..., 1]) / self.semi_axes[1]
        return lx * lx + ly * ly - 1.0

    def params(self) -> np.ndarray:
        """(cx, cy, cos yaw, sin yaw, 1/α, 1/β), the planner's parameter layout."""
        a, b = self.semi_axes
        return np.array([*self.center, np.cos(self.yaw), np.sin(self.yaw), 1 / a, 1 / b])


def keepout_ellipse(building: Building, margin: float) -> KeepOutEllipse:
    """Conservative keep-out ellipse of ``building`` inflated by ``margin`` (m), see the module docstring."""
    if margin < 0:
        raise ValueError(f"margin must be >= 0 m, got {margin}")
    if building.is_cuboid:
        center, size, yaw = building.cuboid_params
        axes = np.sqrt(2.0) * (size[:2] / 2.0 + margin)
        return KeepOutEllipse(center=center[:2], yaw=yaw, semi_axes=axes)
    fp = building.footprint
    c = fp.mean(axis=0)
    rad = float(np.max(np.linalg.norm(fp - c, axis=1))) + margin
    return KeepOutEllipse(center=c, yaw=0.0, semi_axes=np.array([rad, rad]))


def footprint_distance(building: Building, p_W: np.ndarray) -> float:
    """Signed horizontal distance (m) from ``p_W`` (2 or 3,) to the footprint: positive outside, negative inside."""
    p = np.asarray(p_W, dtype=float)[:2]
    a = building.footprint
    b = np.roll(a, -1, axis=0)
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    d = float(np.min(np.linalg.norm(a + t[:, None] * ab - p, axis=1)))
    # even-odd ray casting for inside
    cond = (a[:, 1] > p[1]) != (b[:, 1] > p[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[:, 0] + (p[1] - a[:, 1]) * ab[:, 0] / ab[:, 1]
    inside = bool(np.count_nonzero(cond & (p[0] < x_cross)) % 2)
    return -d if inside else d


def nearby_keepouts(buildings: Sequence[Building], p_W: np.ndarray, altitude: float, reach: float, margin: float,
                    vertical_clearance: float, max_count: int) -> list[KeepOutEllipse]:
    """Keep-out ellipses of the buildings that matter for a plan from ``p_W`` at ``altitude`` (m).

    A building matters when its top is above ``altitude − vertical_clearance`` (else the UAV flies over it) and its
    ellipse comes within ``reach`` (m) of ``p_W`` horizontally. The ``max_count`` nearest are returned, nearest first.
    """
    p = np.asarray(p_W, dtype=float)[:2]
    found: list[tuple[float, KeepOutEllipse]] = []
    for b in buildings:
        if b.top_z < altitude - vertical_clearance:
            continue
        e = keepout_ellipse(b, margin)
        gap = float(np.linalg.norm(p - e.center)) - float(np.max(e.semi_axes))
        if gap <= reach:
            found.append((gap, e))
    found.sort(key=lambda ge: ge[0])
    return [e for _, e in found[:max_count]]
