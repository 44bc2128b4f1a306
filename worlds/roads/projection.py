"""A road's table evaluated and points projected onto roads, compiled: :meth:`~worlds.roads.road.Road._interp`
(:func:`hermite_many`), :meth:`~worlds.roads.road.Road.project` (:func:`project_one`) and its batch form over a
network's roads, for :meth:`~worlds.roads.network.RoadNetwork.project_on` and ``nearest_many``.

A projection takes the road's nearest table sample (points, headings, curvatures at its spacing), then
osculating-circle steps to the foot point (at most ``MAX_PROJECT_STEPS``; clipped at the road's ends with the lateral
offset along the end normal). In Python a projection cost ≈ 14 µs; compiled ≈ 1 µs for one call and 0.3 µs per point
in a batch. The batch form lays every road's table end to end in one set of arrays: a run that records a city's
traffic needs every vehicle's road position at every record tick, and a vehicle inside a junction asks
:meth:`RoadNetwork.nearest`, which projects it onto every road meeting there (in Python, a third of a 1000-vehicle
SUMO run's loop).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

if TYPE_CHECKING:
    from worlds.roads.road import Road

__all__ = ["MAX_PROJECT_STEPS", "RoadTables", "hermite_many", "project_one", "project_pairs"]

MAX_PROJECT_STEPS = 8
"""Osculating-circle steps a projection takes at most."""


@dataclass(frozen=True)
class RoadTables:
    """The tables of ``roads`` end to end: road ``k``'s samples are rows ``start[k] .. start[k] + n[k]`` of ``xy``,
    ``th`` and ``ka``, spaced ``h[k]`` over its ``length[k]``."""

    xy: np.ndarray
    th: np.ndarray
    ka: np.ndarray
    start: np.ndarray
    n: np.ndarray
    h: np.ndarray
    length: np.ndarray

    @classmethod
    def of(cls, roads: Sequence[Road]) -> RoadTables:
        sizes = np.array([r._n + 1 for r in roads], dtype=np.int64)
        start = np.zeros(len(roads), dtype=np.int64)
        start[1:] = np.cumsum(sizes)[:-1]
        return cls(xy=np.ascontiguousarray(np.vstack([r._xy for r in roads])),
                   th=np.ascontiguousarray(np.concatenate([r._th for r in roads])),
                   ka=np.ascontiguousarray(np.concatenate([r._ka for r in roads])),
                   start=start, n=np.array([r._n for r in roads], dtype=np.int64),
                   h=np.array([r._h for r in roads], dtype=float), length=np.array([r.length for r in roads]))


def project_pairs(tables: RoadTables, road: np.ndarray,
                  points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(s, lateral, distance) of each ``points[i]`` (P, 2) m projected onto road ``road[i]`` (indices into the roads
    of ``tables``): :meth:`Road.project`'s arc length and lateral offset, and the distance from the point to the road
    point at that arc length (what :meth:`RoadNetwork.nearest` compares)."""
    pts = np.ascontiguousarray(points, dtype=float).reshape(-1, 2)
    k = np.ascontiguousarray(road, dtype=np.int64).reshape(-1)
    if k.size != len(pts):
        raise ValueError(f"project_pairs: {k.size} roads for {len(pts)} points")
    return _project(tables.xy, tables.th, tables.ka, tables.start, tables.n, tables.h, tables.length, k, pts)


@njit(cache=True)
def _interp1(xy, th_t, ka_t, o, n, h, length, s):  # pragma: no cover - compiled
    """Road._interp1 of the road whose table starts at row ``o``."""
    s = min(max(s, 0.0), length)
    j = min(int(s / h), n - 1)
    u = s / h - j
    u2, u3 = u * u, u * u * u
    h00, h10, h01, h11 = 2 * u3 - 3 * u2 + 1, u3 - 2 * u2 + u, 3 * u2 - 2 * u3, u3 - u2
    th0, th1, k0, k1 = th_t[o + j], th_t[o + j + 1], ka_t[o + j], ka_t[o + j + 1]
    x = h00 * xy[o + j, 0] + h10 * h * math.cos(th0) + h01 * xy[o + j + 1, 0] + h11 * h * math.cos(th1)
    y = h00 * xy[o + j, 1] + h10 * h * math.sin(th0) + h01 * xy[o + j + 1, 1] + h11 * h * math.sin(th1)
    th = h00 * th0 + h10 * h * k0 + h01 * th1 + h11 * h * k1
    ka = ((6 * u2 - 6 * u) * th0 + (6 * u - 6 * u2) * th1) / h + (3 * u2 - 4 * u + 1) * k0 + (3 * u2 - 2 * u) * k1
    return x, y, th, ka


@njit(cache=True)
def hermite_many(xy, th_t, ka_t, h, n, length, s, out, wrap):  # pragma: no cover - compiled
    """:func:`_interp1` of a road's table (rows ``0 .. n``) at each arc length of ``s`` (M,): x, y, theta (wrapped to
    (-pi, pi] by ``atan2(sin, cos)`` when ``wrap``), kappa and the clipped arc length into the rows of ``out`` (5, M);
    :meth:`Road._interp` is this. The operations, in their order, of the vectorised NumPy form it replaced, so the
    numbers are the same (tested); a NaN arc length raises (it has no table interval)."""
    for i in range(s.shape[0]):
        si = s[i]
        if si != si:
            raise ValueError("Road: arc length is NaN")
        x, y, th, ka = _interp1(xy, th_t, ka_t, 0, n, h, length, si)
        out[0, i], out[1, i], out[3, i] = x, y, ka
        out[2, i] = math.atan2(math.sin(th), math.cos(th)) if wrap else th
        out[4, i] = min(max(si, 0.0), length)


@njit(cache=True)
def project_one(xy, th_t, ka_t, o, n, h, length, px, py):  # pragma: no cover - compiled
    """(s, lateral) of the point (px, py) on the road whose table is rows ``o .. o + n`` of ``xy``, ``th_t``,
    ``ka_t`` (spacing ``h``, arc length ``length``): the first nearest table sample (as ``np.argmin``), then
    osculating-circle steps to the foot point; :meth:`Road.project` is this."""
    best, j = np.inf, 0
    for r in range(n + 1):
        dx, dy = xy[o + r, 0] - px, xy[o + r, 1] - py
        d2 = dx * dx + dy * dy
        if d2 < best:
            best, j = d2, r
    s, x, y, th, ka = j * h, xy[o + j, 0], xy[o + j, 1], th_t[o + j], ka_t[o + j]
    lat = 0.0
    for _ in range(MAX_PROJECT_STEPS):
        c, sn = math.cos(th), math.sin(th)
        a = (px - x) * c + (py - y) * sn
        lat = -(px - x) * sn + (py - y) * c
        if abs(ka) * (abs(a) + abs(lat)) < 1e-9:
            ds = a
        else:
            ds = math.atan2(ka * a, 1.0 - ka * lat) / ka
            lat = (1.0 - np.hypot(1.0 - ka * lat, ka * a)) / ka
        s_new = min(max(s + ds, 0.0), length)
        if s_new != s + ds:  # clipped at an end: lateral along the end normal
            x, y, th, ka = _interp1(xy, th_t, ka_t, o, n, h, length, s_new)
            lat = -(px - x) * math.sin(th) + (py - y) * math.cos(th)
            return s_new, lat
        s = s_new
        if abs(ds) < 1e-9:
            return s, lat
        x, y, th, ka = _interp1(xy, th_t, ka_t, o, n, h, length, s)
    return s, lat


@njit(cache=True)
def _project(xy, th_t, ka_t, start, n_t, h_t, len_t, road, pts):  # pragma: no cover - compiled
    m = pts.shape[0]
    s_out, lat_out, dist_out = np.empty(m), np.empty(m), np.empty(m)
    for i in range(m):
        k = road[i]
        o, n, h, length = start[k], n_t[k], h_t[k], len_t[k]
        px, py = pts[i, 0], pts[i, 1]
        s, lat = project_one(xy, th_t, ka_t, o, n, h, length, px, py)
        fx, fy, _, _ = _interp1(xy, th_t, ka_t, o, n, h, length, s)
        s_out[i], lat_out[i], dist_out[i] = s, lat, np.hypot(fx - px, fy - py)
    return s_out, lat_out, dist_out
