"""Constant-curvature approximation of a road centre-line: lines and circular arcs joined into biarcs (paper 002).

Frames: world ENU x-y plane, metres; headings counter-clockwise from +x (rad); lateral offsets positive to the left of
the direction of travel; signed curvature κ positive when turning left (1/m).

Biarc between two vertices
--------------------------
Given vertices :math:`P_0, P_1` with unit tangents :math:`t_0, t_1`, :math:`v = P_1 - P_0`, :math:`t = t_0 + t_1`,
the equal-control-length biarc takes the positive root of

.. math:: 2(1 - t_0 \\cdot t_1)\\, d^2 + 2 (v \\cdot t)\\, d - v \\cdot v = 0,
          \\qquad d = \\frac{2\\, v\\cdot v}
          {2 v\\cdot t + \\sqrt{(2 v\\cdot t)^2 + 8 (1 - t_0\\cdot t_1)\\, v\\cdot v}},

and joins :math:`P_0` to :math:`J = ((P_0 + d t_0) + (P_1 - d t_1))/2` and :math:`J` to :math:`P_1` by circular arcs
tangent to :math:`t_0` at :math:`P_0` and to the joint tangent :math:`(P_1 - d t_1 - P_0 - d t_0)/2d` at :math:`J`.
An arc from :math:`A` with tangent :math:`t_A` to :math:`B` (chord :math:`c = B - A`) has
:math:`\\kappa = 2 (t_A \\times c)/|c|^2` and sweep
:math:`\\varphi = 2\\,\\mathrm{atan2}(t_A \\times c, t_A \\cdot c)`, length :math:`\\varphi / \\kappa`.
Pieces with :math:`|\\kappa|` below ``line_curvature`` become straight lines along the chord.

Vertex tangents are the tangents of the circle through each vertex and its two neighbours (at the ends, through the
first / last three): :math:`t_i \\propto a/|a|^2 + b/|b|^2` with :math:`a = P_i - P_{i-1}`, :math:`b = P_{i+1} - P_i`,
which is the central difference :math:`P_{i+1} - P_{i-1}` for equal chords and is exact for vertices on a circle with
any spacing, so a circle is reproduced exactly (both arcs of every biarc lie on it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from worlds.roads.road import Road

__all__ = ["Segment", "RoadApproximation", "biarc", "vertex_tangents", "approximation_error"]

_MIN_CHORD = 1e-9  # m; shorter pieces are dropped
_MIN_KAPPA = 1e-9  # 1/m; flatter pieces are always lines (an arc of radius > 1e6 km loses precision)


def _wrap(a: np.ndarray | float) -> np.ndarray | float:
    return (a + np.pi) % (2.0 * np.pi) - np.pi


@dataclass(frozen=True, kw_only=True, eq=False)
class Segment:
    """One constant-curvature piece of a road centre-line.

    Attributes
    ----------
    kind : {"line", "arc"}
        Straight line or circular arc.
    p0 : ndarray
        Start point (2,), m.
    p1 : ndarray
        End point (2,), m.
    theta0 : float
        Heading at the start, rad (counter-clockwise from +x).
    kappa : float
        Signed curvature, 1/m (0 for a line; > 0 turning left).
    length : float
        Arc length, m, > 0.
    order : int
        Index of the segment along its road, >= 0.
    road_id : str
        Id of the road the segment approximates.
    centre : ndarray or None
        Arc centre ``p0 + n0 / κ`` (2,), m, with ``n0`` the left normal at the start; None for a line.
    """

    kind: Literal["line", "arc"]
    p0: np.ndarray
    p1: np.ndarray
    theta0: float
    kappa: float
    length: float
    order: int = 0
    road_id: str = ""
    centre: np.ndarray | None = field(init=False, default=None)

    def __post_init__(self) -> None:
        if self.kind not in ("line", "arc"):
            raise ValueError(f"Segment.kind must be 'line' or 'arc', got {self.kind!r}")
        if not (np.isfinite(self.length) and self.length > 0):
            raise ValueError(f"Segment.length must be finite and > 0 m, got {self.length!r}")
        if self.kind == "arc" and not (np.isfinite(self.kappa) and self.kappa != 0.0):
            raise ValueError(f"Segment.kappa of an arc must be finite and non-zero (1/m), got {self.kappa!r}")
        if self.kind == "line" and self.kappa != 0.0:
            raise ValueError(f"Segment.kappa of a line must be 0, got {self.kappa!r}")
        if self.order < 0:
            raise ValueError(f"Segment.order must be >= 0, got {self.order!r}")
        object.__setattr__(self, "p0", np.array(self.p0, dtype=float))
        object.__setattr__(self, "p1", np.array(self.p1, dtype=float))
        if self.kind == "arc":
            n0 = np.array([-math.sin(self.theta0), math.cos(self.theta0)])
            object.__setattr__(self, "centre", self.p0 + n0 / self.kappa)

    @property
    def radius(self) -> float:
        """``1/|κ|`` (m); infinite for a line."""
        return math.inf if self.kind == "line" else 1.0 / abs(self.kappa)

    def heading(self, sigma: float | np.ndarray) -> float | np.ndarray:
        """Heading ``θ0 + κσ`` at arc length ``σ`` from the start (rad, not wrapped)."""
        return self.theta0 + self.kappa * sigma

    def tangent(self, sigma: float | np.ndarray) -> np.ndarray:
        """Unit tangent at ``σ``; (2,) or (2, M)."""
        th = self.heading(sigma)
        return np.array([np.cos(th), np.sin(th)])

    def curvature(self, sigma: float | np.ndarray = 0.0) -> float | np.ndarray:
        """Signed curvature at ``σ`` (constant on the segment), 1/m."""
        return self.kappa + 0.0 * np.asarray(sigma, dtype=float)

    def point(self, sigma: float | np.ndarray, lateral: float | np.ndarray = 0.0) -> np.ndarray:
        """Point at arc length ``σ`` (m) shifted ``lateral`` m to the left; (2,) or (2, M).

        Line: ``p0 + σ t0 + ℓ n0``; arc: ``c − (1/κ − ℓ) n(θ0 + κσ)`` with ``n(θ) = (−sin θ, cos θ)`` (beyond the
        ends this follows the arc's circle, unlike :meth:`local`, which continues along the end tangents).
        """
        th = self.heading(sigma)
        n = np.array([-np.sin(th), np.cos(th)])
        if self.kind == "line":
            t = np.array([np.cos(th), np.sin(th)])
            p = self.p0.reshape((2,) + (1,) * (t.ndim - 1))
            return p + sigma * t + lateral * n
        c = self.centre.reshape((2,) + (1,) * (n.ndim - 1))
        return c - (1.0 / self.kappa - lateral) * n

    def local(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Foot-point coordinates of points ``p`` ((2,) or (2, M), m) on the extended segment.

        Returns ``(σ, ℓ, n)``: arc length of the foot point from ``p0`` (m; outside ``[0, length]`` beyond the ends,
        arcs measured within half a turn of the segment's middle), signed lateral offset (m, left positive) and the
        left unit normal at the foot point ((2,) or (2, M)). Line: ``σ = (p − p0)·t0``, ``ℓ = (p − p0)·n0``;
        arc with ``u = p − c``, ``r = |u|``: ``ℓ = sgn(κ)(1/|κ| − r)``, ``n = −sgn(κ) u / r``, continued beyond its
        ends by its end tangent lines.
        """
        p = np.asarray(p, dtype=float)
        if p.ndim == 1:
            return self._local1(float(p[0]), float(p[1]))
        if self.kind == "line":
            c, s = math.cos(self.theta0), math.sin(self.theta0)
            dx, dy = p[0] - self.p0[0], p[1] - self.p0[1]
            n = np.array([[-s], [c]]) * np.ones_like(dx)
            return dx * c + dy * s, -dx * s + dy * c, n
        ux, uy = p[0] - self.centre[0], p[1] - self.centre[1]
        r = np.hypot(ux, uy)
        r = np.where(r > 0.0, r, 1e-12)
        sg = 1.0 if self.kappa > 0 else -1.0
        theta = np.arctan2(sg * ux, -sg * uy)  # heading of the foot point
        half = 0.5 * self.kappa * self.length
        sigma = (_wrap(theta - self.theta0 - half) + half) / self.kappa
        lat = sg * (1.0 / abs(self.kappa) - r)
        n = -sg * np.array([ux, uy]) / r
        before, after = sigma < 0.0, sigma > self.length
        if not (np.any(before) or np.any(after)):
            return sigma, lat, n
        # beyond an end the arc continues as its end tangent line (a full circle would turn back on itself)
        th1 = self.theta0 + self.kappa * self.length
        for mask, q, th, s0 in ((before, self.p0, self.theta0, 0.0), (after, self.p1, th1, self.length)):
            if not np.any(mask):
                continue
            c, sn = math.cos(th), math.sin(th)
            dx, dy = p[0] - q[0], p[1] - q[1]
            sigma = np.where(mask, s0 + dx * c + dy * sn, sigma)
            lat = np.where(mask, -dx * sn + dy * c, lat)
            n = np.where(mask, np.array([[-sn], [c]]), n)
        return sigma, lat, n

    def _local1(self, px: float, py: float) -> tuple[float, float, np.ndarray]:
        """:meth:`local` of one point in scalar arithmetic."""
        L = self.length
        if self.kind == "arc":
            ux, uy = px - self.centre[0], py - self.centre[1]
            r = max(math.hypot(ux, uy), 1e-12)
            sg = 1.0 if self.kappa > 0 else -1.0
            half = 0.5 * self.kappa * L
            d = math.atan2(sg * ux, -sg * uy) - self.theta0 - half
            sigma = ((d + math.pi) % (2.0 * math.pi) - math.pi + half) / self.kappa
            if 0.0 <= sigma <= L:
                return sigma, sg * (1.0 / abs(self.kappa) - r), np.array([-sg * ux / r, -sg * uy / r])
            if sigma < 0.0:
                q, th, s0 = self.p0, self.theta0, 0.0
            else:
                q, th, s0 = self.p1, self.theta0 + self.kappa * L, L
        else:
            q, th, s0 = self.p0, self.theta0, 0.0
        c, sn = math.cos(th), math.sin(th)
        dx, dy = px - q[0], py - q[1]
        return s0 + dx * c + dy * sn, -dx * sn + dy * c, np.array([-sn, c])

    def heading_at(self, p: np.ndarray) -> float:
        """Heading (rad) at the foot point of ``p`` (2,), constant beyond the ends (the tangent-line extensions)."""
        sigma = float(self._local1(float(p[0]), float(p[1]))[0])
        return float(self.heading(min(max(sigma, 0.0), self.length)))

    def distance(self, p: np.ndarray) -> float:
        """Euclidean distance (m) from ``p`` (2,) to the finite segment."""
        sigma, lat, _ = self.local(p)
        if 0.0 <= sigma <= self.length:
            return abs(float(lat))
        return float(min(np.hypot(*(p - self.p0)), np.hypot(*(p - self.p1))))


def vertex_tangents(vertices: np.ndarray) -> np.ndarray:
    """Unit tangents (K, 2) at the vertices: tangents of the circle through each vertex and its neighbours."""
    v = np.asarray(vertices, dtype=float)
    if v.shape[0] == 2:
        d = (v[1] - v[0]) / np.hypot(*(v[1] - v[0]))
        return np.vstack([d, d])
    a = v[1:-1] - v[:-2]
    b = v[2:] - v[1:-1]
    t_in = a / np.sum(a * a, axis=1, keepdims=True) + b / np.sum(b * b, axis=1, keepdims=True)
    t_in /= np.hypot(t_in[:, 0], t_in[:, 1])[:, None]

    def reflect(t: np.ndarray, chord: np.ndarray) -> np.ndarray:  # tangent at the other end of a circular chord
        c = chord / np.hypot(*chord)
        return 2.0 * (c @ t) * c - t

    t0 = reflect(t_in[0], v[1] - v[0])
    t_end = reflect(t_in[-1], v[-1] - v[-2])
    return np.vstack([t0, t_in, t_end])


def _arc(a: np.ndarray, t_a: np.ndarray, b: np.ndarray, order: int, road_id: str,
         line_curvature: float) -> Segment | None:
    """The segment from ``a`` (tangent ``t_a``) to ``b``: an arc, or a line along the chord when nearly straight."""
    chord = b - a
    c2 = float(chord @ chord)
    if c2 < _MIN_CHORD**2:
        return None
    cross = float(t_a[0] * chord[1] - t_a[1] * chord[0])
    dot = float(t_a @ chord)
    kappa = 2.0 * cross / c2
    if abs(kappa) < max(line_curvature, _MIN_KAPPA):
        return Segment(kind="line", p0=a, p1=b, theta0=math.atan2(chord[1], chord[0]), kappa=0.0,
                       length=math.sqrt(c2), order=order, road_id=road_id)
    half_sweep = math.atan2(cross, dot)
    return Segment(kind="arc", p0=a, p1=b, theta0=math.atan2(t_a[1], t_a[0]), kappa=kappa,
                   length=2.0 * half_sweep / kappa, order=order, road_id=road_id)


def biarc(p0: np.ndarray, t0: np.ndarray, p1: np.ndarray, t1: np.ndarray, *, order: int = 0, road_id: str = "",
          line_curvature: float = 1e-4) -> list[Segment]:
    """The equal-control-length biarc from ``p0`` (unit tangent ``t0``) to ``p1`` (``t1``): one or two segments.

    ``order`` numbers the first segment; the second gets ``order + 1``.
    """
    p0, t0, p1, t1 = (np.asarray(a, dtype=float) for a in (p0, t0, p1, t1))
    v = p1 - p0
    vv = float(v @ v)
    b = 2.0 * float(v @ (t0 + t1))
    a = 2.0 * (1.0 - float(t0 @ t1))
    den = b + math.sqrt(max(b * b + 4.0 * a * vv, 0.0))
    if den <= 1e-12 * math.sqrt(vv):  # tangents parallel and opposed to the chord: no finite biarc, use one arc
        seg = _arc(p0, t0, p1, order, road_id, line_curvature)
        return [] if seg is None else [seg]
    d = 2.0 * vv / den
    q0, q1 = p0 + d * t0, p1 - d * t1
    joint = 0.5 * (q0 + q1)
    tj = q1 - q0
    nj = math.hypot(*tj)
    tj = tj / nj if nj > 0 else t0
    out = []
    for a_, ta, b_ in ((p0, t0, joint), (joint, tj, p1)):
        seg = _arc(a_, ta, b_, order + len(out), road_id, line_curvature)
        if seg is not None:
            out.append(seg)
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class RoadApproximation:
    """Biarc approximation of one directed road.

    Attributes
    ----------
    road_id : str
        The road approximated.
    segments : tuple of Segment
        Pieces in the direction of travel, ``order`` 0, 1, ...
    s_start : ndarray
        Arc length (m) along the approximation at the start of each segment, plus the total length last.
    """

    road_id: str
    segments: tuple[Segment, ...]
    s_start: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.segments:
            raise ValueError(f"RoadApproximation {self.road_id!r}: segments must not be empty")
        s = np.concatenate([[0.0], np.cumsum([g.length for g in self.segments])])
        s.setflags(write=False)
        object.__setattr__(self, "s_start", s)

    @property
    def length(self) -> float:
        """Total arc length of the approximation (m)."""
        return float(self.s_start[-1])

    @classmethod
    def from_vertices(cls, vertices: np.ndarray, *, road_id: str = "", line_curvature: float = 1e-4
                      ) -> "RoadApproximation":
        """Biarcs through the polyline ``vertices`` (K >= 2, 2) with :func:`vertex_tangents`."""
        v = np.asarray(vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 2:
            raise ValueError(f"vertices must be (K>=2, 2), got shape {v.shape}")
        if not (line_curvature >= 0):
            raise ValueError(f"line_curvature must be >= 0 (1/m), got {line_curvature!r}")
        tan = vertex_tangents(v)
        segs: list[Segment] = []
        for i in range(len(v) - 1):
            segs += biarc(v[i], tan[i], v[i + 1], tan[i + 1], order=len(segs), road_id=road_id,
                          line_curvature=line_curvature)
        return cls(road_id=road_id, segments=tuple(segs))

    @classmethod
    def from_road(cls, road: Road, *, max_spacing: float | None = None, line_curvature: float = 1e-4
                  ) -> "RoadApproximation":
        """Biarcs through ``road.vertices``, or, with ``max_spacing`` (m), through centre-line points at most that far
        apart (the road's smooth centre-line resampled at uniform arc length: the vertex-density knob)."""
        if max_spacing is None:
            return cls.from_vertices(road.vertices, road_id=road.id, line_curvature=line_curvature)
        if not (max_spacing > 0):
            raise ValueError(f"max_spacing must be > 0 m, got {max_spacing!r}")
        n = max(1, int(math.ceil(road.length / max_spacing)))
        pts = road.point(np.linspace(0.0, road.length, n + 1))
        return cls.from_vertices(pts, road_id=road.id, line_curvature=line_curvature)

    def locate(self, p: np.ndarray) -> int:
        """Index of the segment nearest to ``p`` (2,) (m)."""
        return int(np.argmin([g.distance(p) for g in self.segments]))

    def project(self, p: np.ndarray) -> tuple[float, float]:
        """(s, lateral) of ``p`` (2,) on the nearest segment: arc length along the approximation and left offset (m)."""
        k = self.locate(p)
        sigma, lat, _ = self.segments[k].local(np.asarray(p, dtype=float))
        return float(self.s_start[k] + sigma), float(lat)

    def point(self, s: float | np.ndarray) -> np.ndarray:
        """Points at arc lengths ``s`` along the approximation (clipped to its ends); (2,) or (M, 2)."""
        s_arr = np.clip(np.atleast_1d(np.asarray(s, dtype=float)), 0.0, self.length)
        k = np.clip(np.searchsorted(self.s_start, s_arr, side="right") - 1, 0, len(self.segments) - 1)
        out = np.array([self.segments[j].point(si - self.s_start[j]) for j, si in zip(k, s_arr, strict=True)])
        return out[0] if np.ndim(s) == 0 else out


def approximation_error(approx: RoadApproximation, road: Road, *, step: float = 0.5) -> float:
    """Largest distance (m) between the approximation and the road's smooth centre-line, both ways.

    Points every ``step`` m along each are measured against the other (road side: nearest point on any segment;
    approximation side: :meth:`Road.project_many`), so the figure is a sampled Hausdorff distance.
    """
    s = np.linspace(0.0, approx.length, max(2, int(math.ceil(approx.length / step)) + 1))
    pa = approx.point(s)
    sr, _ = road.project_many(pa)
    e1 = float(np.max(np.hypot(*(road.point(sr) - pa).T)))
    pr = road.point(np.linspace(0.0, road.length, max(2, int(math.ceil(road.length / step)) + 1))).T
    d2 = np.full(pr.shape[1], np.inf)
    for g in approx.segments:
        sigma, lat, _ = g.local(pr)
        inside = (sigma >= 0.0) & (sigma <= g.length)
        ends = np.minimum(np.hypot(*(pr - g.p0[:, None])), np.hypot(*(pr - g.p1[:, None])))
        d2 = np.minimum(d2, np.where(inside, np.abs(lat), ends))
    return max(e1, float(d2.max()))
