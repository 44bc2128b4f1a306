"""The parts of the road-network API (:mod:`worlds.roads`) the drivers use, as structural types.

Any object with these members works, so drivers are tested on simple analytic roads as well as on the world's
spline roads. Frames: world ENU x-y plane, metres; headings counter-clockwise from +x, radians; curvature signed,
positive for a left turn (1/m).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["RoadLike", "NetworkLike", "sample_road"]


@runtime_checkable
class RoadLike(Protocol):
    """A directed road: a centre-line parametrised by arc length s in [0, length]."""

    id: str
    start_node: str
    end_node: str
    lanes: int
    lane_width: float
    speed_limit: float
    twin: str | None

    @property
    def length(self) -> float: ...

    def point(self, s: float | np.ndarray) -> np.ndarray: ...

    def heading(self, s: float | np.ndarray) -> float | np.ndarray: ...

    def curvature(self, s: float | np.ndarray) -> float | np.ndarray: ...

    def project(self, p_xy: np.ndarray) -> tuple[float, float]: ...

    def lane_offset(self, lane: int = 0) -> float: ...


@runtime_checkable
class NetworkLike(Protocol):
    """A directed road graph."""

    roads: Mapping[str, RoadLike]

    def random_route(self, start_road: str, n_roads: int, rng: np.random.Generator) -> list[str]: ...


def _vectorised(fn, s: np.ndarray) -> np.ndarray:
    """``fn`` evaluated at every element of ``s``, whether or not ``fn`` accepts arrays."""
    try:
        out = np.asarray(fn(s), dtype=float)
        if out.shape[0] == s.shape[0]:
            return out
    except (TypeError, ValueError, IndexError):
        pass
    return np.array([np.asarray(fn(float(si)), dtype=float) for si in s])


def sample_road(road: RoadLike, s: np.ndarray, offset: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points, headings and curvatures of the curve at lateral ``offset`` from the centre-line of ``road``.

    The offset curve is q(s) = p(s) + d n(s) with n = (-sin h, cos h) the left normal; its heading is the
    centre-line heading h(s) and its curvature kappa_d = kappa / (1 - d kappa).

    Parameters
    ----------
    road : RoadLike
        The road.
    s : np.ndarray
        (M,) arc lengths on the centre-line (m).
    offset : float
        Lateral offset d (m), positive to the left.

    Returns
    -------
    xy : np.ndarray
        (M, 2) points (m).
    heading : np.ndarray
        (M,) headings (rad).
    kappa : np.ndarray
        (M,) signed curvatures of the offset curve (1/m).
    """
    s = np.asarray(s, dtype=float)
    both = getattr(road, "sample", None)  # a road that evaluates all three at once (worlds.roads.road.Road)
    if both is not None:
        xy, h, k = both(s)
    else:
        xy = _vectorised(road.point, s).reshape(len(s), 2)
        h = _vectorised(road.heading, s).reshape(len(s))
        k = _vectorised(road.curvature, s).reshape(len(s))
    n = np.stack([-np.sin(h), np.cos(h)], axis=1)
    denom = np.maximum(1.0 - offset * k, 1e-3)
    return xy + offset * n, h, k / denom
