"""A driver's lane path: the lane centre-line over the next few roads of a route as one dense polyline.

Road sections are sampled from each road's lane centre (:func:`~vehicles.car.road_protocol.sample_road`); at each
junction the last ``corner_length`` metres of the incoming lane and the first ``corner_length`` metres of the outgoing
lane are replaced by a cubic Bezier corner whose handles approximate a circular arc through the heading change
dpsi: handle = chord (4/3) tan(dpsi/4) / (2 sin(dpsi/2)) (-> chord/3 for a straight junction).
Junctions where the lane runs straight on (heading change < 0.02 rad, lanes meeting) are joined directly.
Everything a driver needs (projection, heading, curvature, speed limit, junction stop points) is read from it.
"""

from __future__ import annotations

import functools
import math
from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from vehicles.car.road_protocol import RoadLike, sample_road

__all__ = ["LanePath", "PathProjection"]

_SMOOTH_HEADING = 0.02  # rad; a junction with a smaller heading change (and lane gap) joins without a corner
_SMOOTH_GAP = 0.05  # m


@dataclass(frozen=True, kw_only=True)
class PathProjection:
    """Closest point of a lane path to a query point.

    Attributes
    ----------
    s : float
        Arc length along the path (m).
    lateral : float
        Signed distance from the path, positive to the left of travel (m).
    heading : float
        Path heading there (rad).
    index : int
        Index of the path segment [index, index + 1] holding the point.
    """

    s: float
    lateral: float
    heading: float
    index: int


def _wrap(a: float | np.ndarray) -> float | np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def _wrap_float(a: float) -> float:
    """:func:`_wrap` of one float in float math (the same operations, so the same result)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


_SAMPLES: dict[tuple[int, float, float, int, float], tuple[object, tuple[np.ndarray, ...]]] = {}
_SAMPLES_MAX = 8192  # sampled lane sections kept (a few MB for a city's worth of roads)


def _sampled(road: RoadLike, a: float, b: float, n: int, offset: float) -> tuple[np.ndarray, ...]:
    """(s, xy, heading, kappa) of ``n`` samples from ``a`` to ``b`` (m) of the lane at ``offset`` on ``road``, kept:
    every path that crosses a road whole samples it the same way, and a car rebuilds its path at each new road
    (drivers of a city's traffic would otherwise spend most of their time sampling splines). The arrays are
    read-only; the same numbers as :func:`sample_road` of ``np.linspace(a, b, n)``."""
    key = (id(road), a, b, n, offset)
    hit = _SAMPLES.get(key)
    if hit is not None and hit[0] is road:
        return hit[1]
    s = np.linspace(a, b, n)
    out = (s, *sample_road(road, s, offset))
    for arr in out:
        arr.setflags(write=False)
    if len(_SAMPLES) >= _SAMPLES_MAX:
        _SAMPLES.clear()
    _SAMPLES[key] = (road, out)
    return out


_JOINS: dict[tuple[int, int, float, float], tuple[object, object, bool]] = {}
_CORNERS: dict[tuple, tuple[object, object, tuple[np.ndarray, ...]]] = {}
_JOINS_MAX = _CORNERS_MAX = 8192  # junctions kept (a city's worth; cleared whole when full, like _SAMPLES)


def _corner(prev: RoadLike, road: RoadLike, end: tuple[np.ndarray, float], start: tuple[np.ndarray, float],
            cut_prev: float, cut: float, ds: float) -> tuple[np.ndarray, ...]:
    """(points, headings, curvatures, road arc lengths) of the inner samples of the junction corner from ``prev``'s
    cut end (point and heading ``end``) into ``road``'s cut start (``start``), kept by its exact inputs: a city's cars
    turn through the same junctions again and again. The same numbers as :func:`_bezier` of those inputs."""
    p0, h0 = end
    p3, h3 = start
    key = (id(prev), id(road), cut_prev, cut, ds, np.concatenate([p0, p3, [h0, h3]]).tobytes())
    hit = _CORNERS.get(key)
    if hit is not None and hit[0] is prev and hit[1] is road:
        return hit[2]
    pts, ch, ck = _bezier(p0, np.array([math.cos(h0), math.sin(h0)]), p3, np.array([math.cos(h3), math.sin(h3)]),
                          max(3, int(math.ceil(2 * (cut_prev + cut) / ds)) + 1))
    inner = slice(1, -1)
    m = len(pts) - 2
    half = m // 2
    u = np.linspace(0, 1, m + 2)[1:-1]
    rs = np.where(np.arange(m) < half, prev.length - cut_prev + 2 * u * cut_prev, (2 * u - 1) * cut)
    out = (pts[inner], ch[inner], ck[inner], rs)
    for arr in out:
        arr.setflags(write=False)
    if len(_CORNERS) >= _CORNERS_MAX:
        _CORNERS.clear()
    _CORNERS[key] = (prev, road, out)
    return out


@njit(cache=True)
def _closest_segment(xy: np.ndarray, t: np.ndarray, seg: np.ndarray, lo: int, hi: int, px: float,
                     py: float) -> tuple[int, float, float]:
    """(k, u, lateral): the segment k in [lo, hi) of the polyline (points ``xy``, unit tangents ``t``, lengths ``seg``)
    closest to (px, py), the distance u along it of the closest point and the signed offset of the query point from
    its line (left positive); the first of equally close segments. Per segment, in this order of operations:
    d = p - a, u = min(max(d . t, 0), len), r = d - u t, |r|^2."""
    best, k_best, u_best, lat_best = np.inf, lo, 0.0, 0.0
    for k in range(lo, hi):
        dx, dy = px - xy[k, 0], py - xy[k, 1]
        tx, ty = t[k, 0], t[k, 1]
        u = min(max(dx * tx + dy * ty, 0.0), seg[k])
        rx, ry = dx - u * tx, dy - u * ty
        r2 = rx * rx + ry * ry
        if r2 < best:
            best, k_best, u_best, lat_best = r2, k, u, tx * dy - ty * dx
    return k_best, u_best, lat_best


def _bezier(p0: np.ndarray, t0: np.ndarray, p3: np.ndarray, t3: np.ndarray,
            n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cubic Bezier corner from p0 (tangent t0) to p3 (tangent t3): points, headings, curvatures at n params."""
    chord = float(np.linalg.norm(p3 - p0))
    dpsi = abs(float(_wrap(math.atan2(t3[1], t3[0]) - math.atan2(t0[1], t0[0]))))
    if dpsi < 1e-6:
        handle = chord / 3.0
    else:
        handle = chord * (4.0 / 3.0) * math.tan(dpsi / 4.0) / (2.0 * math.sin(dpsi / 2.0))
    p1, p2 = p0 + handle * t0, p3 - handle * t3
    u = np.linspace(0.0, 1.0, n)[:, None]
    pts = (1 - u) ** 3 * p0 + 3 * (1 - u) ** 2 * u * p1 + 3 * (1 - u) * u ** 2 * p2 + u ** 3 * p3
    d1 = 3 * (1 - u) ** 2 * (p1 - p0) + 6 * (1 - u) * u * (p2 - p1) + 3 * u ** 2 * (p3 - p2)
    d2 = 6 * (1 - u) * (p2 - 2 * p1 + p0) + 6 * u * (p3 - 2 * p2 + p1)
    speed = np.maximum(np.linalg.norm(d1, axis=1), 1e-9)
    kappa = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / speed ** 3
    return pts, np.arctan2(d1[:, 1], d1[:, 0]), kappa


class LanePath:
    """Lane centre-line through a sequence of connected roads, sampled every ``ds`` metres.

    Parameters
    ----------
    roads : Sequence[RoadLike]
        Consecutive roads (each road's end node is the next one's start node).
    lanes : Sequence[int]
        Lane index to follow on each road (clipped to the road's lane count).
    s_start : float
        Arc length on the first road where the path begins (m).
    ds : float
        Sample spacing (m).
    corner_length : float
        Length cut from each side of a junction and replaced by the corner (m); at most 45 % of a road.

    Attributes
    ----------
    xy, heading, kappa, s : np.ndarray
        (N, 2) points (m), (N,) headings (rad), signed curvatures (1/m), cumulative arc length (m).
    road_index : np.ndarray
        (N,) index into ``roads`` of the road each sample belongs to.
    road_s : np.ndarray
        (N,) arc length of each sample on its road's centre-line (m).
    in_corner : np.ndarray
        (N,) True for the samples of junction corners.
    speed_limit : np.ndarray
        (N,) speed limit of each sample's road (m/s).
    lane_offset : np.ndarray
        (N,) lateral offset of the followed lane from its road's centre-line (m).
    junction_s : np.ndarray
        (len(roads) - 1,) path arc length where the corner into road k + 1 begins, i.e. the stop line of road k (m).
    """

    def __init__(self, roads: Sequence[RoadLike], lanes: Sequence[int], s_start: float = 0.0, ds: float = 1.0,
                 corner_length: float = 8.0) -> None:
        if len(roads) == 0 or len(roads) != len(lanes):
            raise ValueError(f"LanePath needs one lane per road and at least one road, got {len(roads)}/{len(lanes)}")
        self.roads = list(roads)
        offsets = [r.lane_offset(int(min(max(lane, 0), r.lanes - 1))) for r, lane in zip(roads, lanes, strict=True)]
        smooth = [self._smooth_join(roads[k], roads[k + 1], offsets[k], offsets[k + 1])
                  for k in range(len(roads) - 1)]
        cuts = [min(corner_length, 0.45 * r.length) for r in roads]
        xy, hd, kp, rs = [], [], [], []
        piece_road, piece_len, piece_corner = [], [], []  # runs of samples: their road index, count, corner flag
        count = 0  # samples so far
        junction_index: list[int] = []
        for k, road in enumerate(roads):
            a = s_start if k == 0 else (0.0 if smooth[k - 1] else cuts[k])
            b = road.length - cuts[k] if k + 1 < len(roads) and not smooth[k] else road.length
            a = min(a, b)
            n = max(2, int(math.ceil((b - a) / ds)) + 1)
            s, p, h, kap = _sampled(road, a, b, n, offsets[k])
            if k > 0 and smooth[k - 1]:  # tangent-continuous join: no corner, drop the duplicated node sample
                junction_index.append(count - 1)
                s, p, h, kap, n = s[1:], p[1:], h[1:], kap[1:], n - 1
            elif k > 0:  # corner from the previous road's cut end into this road's cut start
                pts, ch, ck, corner_s = _corner(roads[k - 1], road, (xy[-1][-1], float(hd[-1][-1])),
                                                (p[0], float(h[0])), cuts[k - 1], cuts[k], ds)
                m = len(pts)
                half = m // 2
                xy.append(pts), hd.append(ch), kp.append(ck), rs.append(corner_s)
                piece_road += (k - 1, k)
                piece_len += (half, m - half)
                piece_corner += (True, True)
                junction_index.append(count - 1)
                count += m
            xy.append(p), hd.append(h), kp.append(kap), rs.append(s)
            piece_road.append(k), piece_len.append(n), piece_corner.append(False)
            count += n
        self.xy = np.concatenate(xy)
        self.heading = np.concatenate(hd)
        self.kappa = np.concatenate(kp)
        self.road_index = np.repeat(np.array(piece_road, dtype=int), piece_len)
        self.road_s = np.concatenate(rs)
        self.in_corner = np.repeat(np.array(piece_corner, dtype=bool), piece_len)
        d = np.diff(self.xy, axis=0)
        seg = np.linalg.norm(d, axis=1)
        self.s = np.concatenate(([0.0], np.cumsum(seg)))
        self.speed_limit = np.array([r.speed_limit for r in roads], dtype=float)[self.road_index]
        self.lane_offset = np.array(offsets, dtype=float)[self.road_index]
        js = self.s[np.asarray(junction_index, dtype=int)] if junction_index else np.zeros(0)
        # the stop line of a smooth join (no corner) is still ``corner_length`` before the node
        self.junction_s = np.maximum(js - np.where(np.asarray(smooth, dtype=bool), corner_length, 0.0), 0.0)
        self._t = d / np.maximum(seg, 1e-12)[:, None]
        self._seg = seg

    # the same numbers as Python lists, made when first read: the bisections of locate / search are cheaper on them,
    # and most paths of a city's traffic are never searched in Python (vehicles.car.traffic_fleet steps them compiled)
    @functools.cached_property
    def _s_list(self) -> list[float]:
        return self.s.tolist()

    @functools.cached_property
    def _seg_list(self) -> list[float]:
        return self._seg.tolist()

    @functools.cached_property
    def _road_index_list(self) -> list[int]:
        return self.road_index.tolist()

    @functools.cached_property
    def _road_s_list(self) -> list[float]:
        return self.road_s.tolist()

    @staticmethod
    def _smooth_join(a: RoadLike, b: RoadLike, off_a: float, off_b: float) -> bool:
        """True when lane ``a`` runs on into lane ``b`` without a heading or position jump (no corner needed); kept
        per pair of lanes."""
        key = (id(a), id(b), off_a, off_b)
        hit = _JOINS.get(key)
        if hit is not None and hit[0] is a and hit[1] is b:
            return hit[2]
        _, pa, ha, _ = _sampled(a, a.length, a.length, 1, off_a)
        _, pb, hb, _ = _sampled(b, 0.0, 0.0, 1, off_b)
        jump = abs(float(_wrap(hb[0] - ha[0])))
        smooth = jump < _SMOOTH_HEADING and float(np.linalg.norm(pb[0] - pa[0])) < _SMOOTH_GAP
        if len(_JOINS) >= _JOINS_MAX:
            _JOINS.clear()
        _JOINS[key] = (a, b, smooth)
        return smooth

    @property
    def length(self) -> float:
        """Total arc length (m)."""
        return float(self.s[-1])

    def project(self, p_xy: np.ndarray, hint: int | None = None, window: int = 60) -> PathProjection:
        """Closest point of the path to ``p_xy`` (m), searching segments near ``hint`` (all when None)."""
        return self.project_xy(float(p_xy[0]), float(p_xy[1]), hint, window)

    def project_xy(self, px: float, py: float, hint: int | None = None, window: int = 60) -> PathProjection:
        """:meth:`project` of the point (``px``, ``py``) (m) given as two floats."""
        n = self._seg.shape[0]
        lo, hi = (0, n) if hint is None else (max(0, hint - window), min(n, hint + window))
        k, u, lateral = _closest_segment(self.xy, self._t, self._seg, lo, hi, px, py)
        h0, h1 = self.heading.item(k), self.heading.item(k + 1)
        frac = u / max(self._seg.item(k), 1e-12)
        heading = h0 + frac * _wrap_float(h1 - h0)
        return PathProjection(s=self.s.item(k) + u, lateral=lateral, heading=heading, index=k)

    def search(self, s: float) -> int:
        """Number of samples at arc length <= ``s`` (m): ``np.searchsorted(self.s, s, side="right")``."""
        return bisect_right(self._s_list, s)

    def locate(self, s: float) -> tuple[int, float]:
        """(road index, arc length on that road's centre-line (m)) of path arc length ``s``."""
        s_list, road_index, road_s = self._s_list, self._road_index_list, self._road_s_list
        s = min(max(float(s), 0.0), s_list[-1])
        k = min(max(bisect_right(s_list, s) - 1, 0), len(s_list) - 2)
        frac = (s - s_list[k]) / max(self._seg_list[k], 1e-12)
        if road_index[k] != road_index[k + 1]:
            return road_index[k], road_s[k]
        return road_index[k], road_s[k] + frac * (road_s[k + 1] - road_s[k])

    def s_of_road(self, road_index: int, road_s: float) -> float:
        """Path arc length of arc length ``road_s`` on road ``road_index`` (m), clipped to the path."""
        sel = np.flatnonzero(self.road_index == road_index)
        if len(sel) == 0:
            raise ValueError(f"road index {road_index} is not on this path")
        return float(np.interp(road_s, self.road_s[sel], self.s[sel]))
