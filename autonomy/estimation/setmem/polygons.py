"""Guaranteed (outer) set operations on unions of polygons for set-membership estimation.

Sets are shapely geometries (``Polygon``, ``MultiPolygon`` or an empty geometry) in the ground plane of the world
frame (x east, y north, metres). Every approximation made here is an *outer* approximation: the returned set
contains the exact one, so a target proven to lie in the exact set lies in the approximation too.

Dilation (the Minkowski sum with a disc of radius ``r``)
    ``P (+) B(r) = {p + d : p in P, |d| <= r}``. GEOS approximates each round join by a polyline whose vertices lie
    on the arc, at most ``pi / (2 q)`` rad apart for ``q`` segments per quarter circle, so a chord sags inside the
    arc by at most ``r (1 - cos(pi / (4 q)))``. Buffering by ``r / cos(pi / (4 q))`` puts every chord outside the
    disc of radius ``r``: the result contains ``P (+) B(r)``.

Simplification (bounding the vertex count)
    ``Q = simplify(P (+) B(2 tol), tol) U P``: Douglas-Peucker with tolerance ``tol`` moves the boundary of the
    slightly dilated set by at most ``tol``, so it nearly always already contains ``P``; the union with ``P``
    makes containment hold by construction whatever the simplifier did. Holes smaller than a given area are filled
    (filling a hole only adds points).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

__all__ = [
    "EMPTY",
    "area",
    "as_polygonal",
    "boxes_union",
    "components",
    "contains_points",
    "dilate",
    "distance_to",
    "fill_small_holes",
    "intersection_all",
    "n_vertices",
    "outer_simplify",
    "union_all",
]

EMPTY: BaseGeometry = shapely.Polygon()


def as_polygonal(geom: BaseGeometry | None) -> BaseGeometry:
    """Only the areal parts of ``geom`` (points and lines left by overlays have no area and no target inside
    that is not also in the areal parts' closure), as a ``Polygon``/``MultiPolygon`` or the empty polygon."""
    if geom is None or geom.is_empty:
        return EMPTY
    if geom.geom_type in ("Polygon", "MultiPolygon"):
        return geom
    parts = [g for g in shapely.get_parts(geom) if g.geom_type in ("Polygon", "MultiPolygon") and not g.is_empty]
    if not parts:
        return EMPTY
    return shapely.union_all(parts)


def area(geom: BaseGeometry) -> float:
    """Area of a set (m^2)."""
    return 0.0 if geom.is_empty else float(geom.area)


def n_vertices(geom: BaseGeometry) -> int:
    """Number of coordinates of a geometry (rings counted with their closing vertex)."""
    return int(shapely.get_num_coordinates(geom))


_MAX_QUAD_SEGS = 8


def dilate(geom: BaseGeometry, radius: float, quad_segs: int = 2) -> BaseGeometry:
    """Outer approximation of ``geom (+) B(radius)`` (module docstring), ``radius`` in m, >= 0.

    GEOS can return a self-intersecting buffer (seen on a multi-part set grown by 1.39 m, whose next intersection then
    raised a TopologyException): such a result is recomputed with more segments per quarter circle (each still an
    outer bound, the radius being scaled for its own ``quad_segs``), and as a last resort repaired with
    ``make_valid``, which keeps every point it covered.
    """
    if radius < 0:
        raise ValueError(f"dilate radius must be >= 0 m, got {radius}")
    if geom.is_empty or radius == 0:
        return geom
    for segs in range(quad_segs, max(quad_segs, _MAX_QUAD_SEGS) + 1):
        out = shapely.buffer(geom, radius / np.cos(np.pi / (4 * segs)), quad_segs=segs)
        if out.is_valid:
            return as_polygonal(out)
    return as_polygonal(shapely.make_valid(out))


def fill_small_holes(geom: BaseGeometry, max_hole_area: float) -> BaseGeometry:
    """``geom`` with its interior rings of area <= ``max_hole_area`` (m^2) filled (an outer approximation)."""
    if geom.is_empty or max_hole_area <= 0:
        return geom
    out = []
    changed = False
    for poly in shapely.get_parts(geom):
        holes = list(poly.interiors)
        keep = [h for h in holes if shapely.Polygon(h).area > max_hole_area]
        if len(keep) != len(holes):
            changed = True
            poly = shapely.Polygon(poly.exterior, keep)
        out.append(poly)
    if not changed:
        return geom
    return shapely.union_all(out)


def outer_simplify(geom: BaseGeometry, tol: float, max_hole_area: float = 0.0) -> BaseGeometry:
    """Outer approximation of ``geom`` with fewer vertices (module docstring); ``tol`` in m, ``max_hole_area`` m^2."""
    if geom.is_empty or tol <= 0:
        return fill_small_holes(geom, max_hole_area)
    grown = shapely.buffer(geom, 2.0 * tol, quad_segs=1)
    simple = shapely.simplify(grown, tol, preserve_topology=True)
    out = as_polygonal(shapely.union(simple, geom))
    return fill_small_holes(out, max_hole_area)


def boxes_union(centres: np.ndarray, half_widths: np.ndarray) -> BaseGeometry:
    """Union of the axis-aligned boxes ``[c - w, c + w]`` for centres (N, 2) and half-widths (N, 2) or (2,), m."""
    c = np.asarray(centres, dtype=float).reshape(-1, 2)
    if c.shape[0] == 0:
        return EMPTY
    w = np.broadcast_to(np.asarray(half_widths, dtype=float), c.shape)
    boxes = shapely.box(c[:, 0] - w[:, 0], c[:, 1] - w[:, 1], c[:, 0] + w[:, 0], c[:, 1] + w[:, 1])
    return shapely.union_all(boxes)


def components(geom: BaseGeometry) -> list[BaseGeometry]:
    """Connected polygons of a set, largest first."""
    if geom.is_empty:
        return []
    parts = list(shapely.get_parts(geom))
    return sorted(parts, key=lambda p: -p.area)


def contains_points(geom: BaseGeometry, p_xy: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """(N,) bool: each point (N, 2) m lies in ``geom`` up to ``tol`` m (boundary included)."""
    p = np.asarray(p_xy, dtype=float).reshape(-1, 2)
    if geom.is_empty:
        return np.zeros(len(p), dtype=bool)
    pts = shapely.points(p)
    return np.asarray(shapely.dwithin(geom, pts, tol), dtype=bool)


def distance_to(geom: BaseGeometry, p_xy: np.ndarray) -> np.ndarray:
    """(N,) Euclidean distance (m) from points (N, 2) to a set; 0 inside, ``inf`` for the empty set."""
    p = np.asarray(p_xy, dtype=float).reshape(-1, 2)
    if geom.is_empty:
        return np.full(len(p), np.inf)
    return np.asarray(shapely.distance(geom, shapely.points(p)), dtype=float)


def union_all(geoms: Iterable[BaseGeometry]) -> BaseGeometry:
    """Polygonal union of geometries (the empty polygon for none)."""
    items = [g for g in geoms if g is not None and not g.is_empty]
    if not items:
        return EMPTY
    return as_polygonal(shapely.union_all(items))


def intersection_all(geoms: Sequence[BaseGeometry]) -> BaseGeometry:
    """Polygonal intersection of one or more geometries."""
    if not geoms:
        raise ValueError("intersection_all needs at least one geometry")
    out = geoms[0]
    for g in geoms[1:]:
        if out.is_empty:
            return EMPTY
        out = as_polygonal(shapely.intersection(out, g))
    return as_polygonal(out)
