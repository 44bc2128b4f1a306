"""A directed road: a smooth centre-line through a vertex polyline, parametrised by arc length.

Frames: world ENU, x-y plane, metres; headings counter-clockwise from +x, radians; lateral offsets positive to the left
of the direction of travel (right-hand traffic drives at negative offsets).

Centre-line
-----------
A C2 cubic spline :math:`r(t)` in the chord-length parameter :math:`t_i = \\sum_{k<i} |K_{k+1} - K_k|` interpolates the
knots :math:`K`, clamped at each end to the slope of the parabola through the three end knots
(:mod:`worlds.roads.spline`). The knots are the vertices plus points on the chords where the polyline asks for them:
next to a corner (a vertex turning by more than 30 degrees, knots 6 m or 30 % of the chord away from it, so the road
turns at the corner instead of bulging out) and along a chord much longer than its neighbour (geometric grading, since
large jumps in knot spacing make interpolating splines ring). Evenly spaced vertices on a gentle curve get no extra
knots; two vertices, or any collinear set, give the exact straight line, since the spline reproduces linear data.

The spline is re-parametrised by arc length :math:`s(t) = \\int_0^t |r'(\\tau)| d\\tau` (5-point Gauss-Legendre on
sub-intervals, inverted by Newton's method) and tabulated at uniform spacing :math:`h \\le` ``sample_spacing`` (finer
where needed so that the heading turns by at most about 0.01 rad between samples): position :math:`q_j`, heading
:math:`\\theta_j` (unwrapped) and signed curvature :math:`\\kappa_j = (x'y'' - y'x'') / |r'|^3`. Queries interpolate the
table with cubic Hermite polynomials: position from :math:`(q_j, h\\,T_j)`, heading from
:math:`(\\theta_j, h\\,\\kappa_j)`; the curvature returned is the derivative of that heading interpolant, so
:math:`d\\theta/ds = \\kappa` holds exactly between samples.

Projection finds the nearest table sample, then steps to the foot point on the local osculating circle: with the offset
:math:`d = p - q` split into along-track :math:`a = d\\cdot T` and left :math:`l = d\\cdot N`,

.. math:: \\Delta s = \\operatorname{atan2}(\\kappa a,\\ 1 - \\kappa l) / \\kappa, \\qquad
          \\text{lateral} = \\bigl(1 - \\sqrt{(1 - \\kappa l)^2 + (\\kappa a)^2}\\bigr) / \\kappa,

which is exact on lines and circles; the step is repeated from the new point until it settles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from worlds.roads.projection import MAX_PROJECT_STEPS, hermite_many, project_one
from worlds.roads.spline import knots, line_table, spline_table

__all__ = ["Road"]

_MIN_CHORD = 1e-6  # m; consecutive vertices closer than this are rejected as duplicates
_PROJECT_CHUNK = 256  # points per block of the nearest-sample search in project_many


@dataclass(frozen=True, kw_only=True, eq=False)
class Road:
    """A directed road: geometry runs from ``start_node`` to ``end_node``; a two-way street is two twin Roads.

    Attributes
    ----------
    id : str
        Unique road id within its network.
    vertices : np.ndarray
        (K >= 2, 2) centre-line polyline in the direction of travel (m); stored read-only.
    start_node, end_node : str
        Ids of the junctions at the start and end of the road.
    lanes : int
        Lanes in this direction (>= 1).
    lane_width : float
        Width of one lane (m), > 0.
    speed_limit : float
        Legal speed (m/s), > 0.
    twin : str | None
        Id of the opposite-direction road of the same street. With a twin the centre-line is the street's dividing line
        and this road's lanes lie to its right; without one the centre-line runs down the middle of the carriageway.
    sample_spacing : float
        Upper bound on the arc-length table spacing (m), > 0. Straight two-vertex roads need no table and ignore it.
    length : float
        Arc length of the smooth centre-line (m); computed.
    """

    id: str
    vertices: np.ndarray = field(repr=False)
    start_node: str
    end_node: str
    lanes: int = 1
    lane_width: float = 3.5
    speed_limit: float = 13.9
    twin: str | None = None
    sample_spacing: float = 1.0
    _reverse_of: "Road | None" = field(default=None, repr=False)
    length: float = field(init=False, repr=True)
    _h: float = field(init=False, repr=False)
    _n: int = field(init=False, repr=False)
    _xy: np.ndarray = field(init=False, repr=False)
    _th: np.ndarray = field(init=False, repr=False)
    _ka: np.ndarray = field(init=False, repr=False)
    _lists: tuple = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not self.id:
            raise ValueError(f"Road.id must be a non-empty string, got {self.id!r}")
        v = np.array(self.vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 2:
            raise ValueError(f"Road {self.id!r}: vertices must be (K>=2, 2), got shape {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"Road {self.id!r}: vertices contain non-finite values")
        chords = np.hypot(*np.diff(v, axis=0).T)
        if np.any(chords < _MIN_CHORD):
            k = int(np.argmin(chords))
            raise ValueError(f"Road {self.id!r}: vertices {k} and {k + 1} coincide ({v[k].tolist()})")
        if not (isinstance(self.lanes, (int, np.integer)) and self.lanes >= 1):
            raise ValueError(f"Road {self.id!r}: lanes must be an integer >= 1, got {self.lanes!r}")
        if not (self.lane_width > 0):
            raise ValueError(f"Road {self.id!r}: lane_width must be > 0 m, got {self.lane_width}")
        if not (self.speed_limit > 0):
            raise ValueError(f"Road {self.id!r}: speed_limit must be > 0 m/s, got {self.speed_limit}")
        if not (self.sample_spacing > 0):
            raise ValueError(f"Road {self.id!r}: sample_spacing must be > 0 m, got {self.sample_spacing}")
        if self.twin == self.id:
            raise ValueError(f"Road {self.id!r}: twin must name another road")
        v.setflags(write=False)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "lanes", int(self.lanes))
        rev = self._reverse_of
        object.__setattr__(self, "_reverse_of", None)
        if rev is not None and rev.vertices.shape == v.shape and np.array_equal(rev.vertices[::-1], v) \
                and rev.sample_spacing == self.sample_spacing:
            xy, th, ka, length = rev._xy[::-1].copy(), rev._th[::-1] + np.pi, -rev._ka[::-1], rev.length
        elif v.shape[0] == 2:
            xy, th, ka, length = line_table(v)
        else:
            xy, th, ka, length = spline_table(knots(v), self.sample_spacing)
        n = xy.shape[0] - 1
        for a in (xy, th, ka):
            a.setflags(write=False)
        object.__setattr__(self, "length", float(length))
        object.__setattr__(self, "_h", float(length) / n)
        object.__setattr__(self, "_n", n)
        object.__setattr__(self, "_xy", xy)
        object.__setattr__(self, "_th", th)
        object.__setattr__(self, "_ka", ka)
        object.__setattr__(self, "_lists", (xy[:, 0].tolist(), xy[:, 1].tolist(), th.tolist(), ka.tolist()))

    def reversed(self, *, id: str, lanes: int | None = None) -> "Road":
        """The opposite-direction twin over the same centre-line, named ``id`` (reuses this road's table).

        This road must already name ``id`` as its twin; lane width and speed limit are copied, ``lanes`` defaults to
        this road's.
        """
        if self.twin != id:
            raise ValueError(f"Road {self.id!r}: reversed(id={id!r}) needs twin={id!r}, got twin={self.twin!r}")
        return Road(id=id, vertices=self.vertices[::-1], start_node=self.end_node, end_node=self.start_node,
                    lanes=self.lanes if lanes is None else lanes, lane_width=self.lane_width,
                    speed_limit=self.speed_limit, twin=self.id, sample_spacing=self.sample_spacing, _reverse_of=self)

    # ------------------------------------------------------------------ evaluation
    def _interp(self, s: np.ndarray, wrap: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                                                  np.ndarray]:
        """Hermite evaluation at arc lengths ``s`` (already an array, any shape): x, y, theta (wrapped to (-pi, pi]
        when ``wrap``), kappa, clipped s (compiled, :func:`~worlds.roads.projection.hermite_many`)."""
        flat = np.ascontiguousarray(s, dtype=float).reshape(-1)
        out = np.empty((5, flat.size))
        hermite_many(self._xy, self._th, self._ka, self._h, self._n, self.length, flat, out, wrap)
        x, y, th, ka, sc = (row.reshape(np.shape(s)) for row in out)
        return x, y, th, ka, sc

    def _interp1(self, s: float) -> tuple[float, float, float, float]:
        """Scalar version of :meth:`_interp` in plain floats (used by :meth:`project`): x, y, theta, kappa."""
        s = min(max(s, 0.0), self.length)
        h = self._h
        j = min(int(s / h), self._n - 1)
        u = s / h - j
        u2, u3 = u * u, u * u * u
        h00, h10, h01, h11 = 2 * u3 - 3 * u2 + 1, u3 - 2 * u2 + u, 3 * u2 - 2 * u3, u3 - u2
        xs, ys, ths, kas = self._lists
        th0, th1, k0, k1 = ths[j], ths[j + 1], kas[j], kas[j + 1]
        x = h00 * xs[j] + h10 * h * math.cos(th0) + h01 * xs[j + 1] + h11 * h * math.cos(th1)
        y = h00 * ys[j] + h10 * h * math.sin(th0) + h01 * ys[j + 1] + h11 * h * math.sin(th1)
        th = h00 * th0 + h10 * h * k0 + h01 * th1 + h11 * h * k1
        ka = ((6 * u2 - 6 * u) * th0 + (6 * u - 6 * u2) * th1) / h + (3 * u2 - 4 * u + 1) * k0 + (3 * u2 - 2 * u) * k1
        return x, y, th, ka

    def point(self, s: float | np.ndarray, lateral: float | np.ndarray = 0.0) -> np.ndarray:
        """Centre-line point at arc length ``s`` (m, clipped to [0, length]), shifted ``lateral`` m to the left.

        Returns (2,) for scalar ``s``, else (M, 2).
        """
        if np.ndim(s) == 0 and np.ndim(lateral) == 0:
            x, y, th, _ = self._interp1(float(s))
            return np.array([x - lateral * math.sin(th), y + lateral * math.cos(th)])
        x, y, th, _, _ = self._interp(np.asarray(s, dtype=float))
        if np.any(lateral):
            x, y = x - lateral * np.sin(th), y + lateral * np.cos(th)
        return np.stack([x, y], axis=-1)

    def sample(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, 2) centre-line points, (M,) headings (wrapped to (-pi, pi]) and (M,) curvatures at arc lengths ``s``
        (an array): what :meth:`point`, :meth:`heading` and :meth:`curvature` give, from one evaluation of the spline
        instead of three."""
        x, y, th, ka, _ = self._interp(s, wrap=True)
        return np.stack([x, y], axis=-1), th, ka

    def tangent(self, s: float | np.ndarray) -> np.ndarray:
        """Unit tangent (direction of travel) at arc length ``s``; (2,) or (M, 2)."""
        if np.ndim(s) == 0:
            th = self._interp1(float(s))[2]
            return np.array([math.cos(th), math.sin(th)])
        th = self._interp(np.asarray(s, dtype=float))[2]
        return np.stack([np.cos(th), np.sin(th)], axis=-1)

    def heading(self, s: float | np.ndarray) -> float | np.ndarray:
        """Heading ``atan2(T_y, T_x)`` at arc length ``s`` (rad, wrapped to (-pi, pi])."""
        if np.ndim(s) == 0:
            th = self._interp1(float(s))[2]
            return math.atan2(math.sin(th), math.cos(th))
        return self._interp(np.asarray(s, dtype=float), wrap=True)[2]

    def curvature(self, s: float | np.ndarray) -> float | np.ndarray:
        """Signed curvature ``d(heading)/ds`` at arc length ``s`` (1/m), positive when turning left (CCW)."""
        if np.ndim(s) == 0:
            return self._interp1(float(s))[3]
        return self._interp(np.asarray(s, dtype=float))[3]

    # ------------------------------------------------------------------ projection
    def project(self, p_xy: np.ndarray) -> tuple[float, float]:
        """(s, lateral) of the centre-line point nearest to ``p_xy`` (m).

        ``lateral`` is positive to the left of travel. Beyond the ends ``s`` is clipped to 0 or ``length`` and
        ``lateral`` is the offset along the end normal. Compiled (:func:`~worlds.roads.projection.project_one`).
        """
        return project_one(self._xy, self._th, self._ka, 0, self._n, self._h, self.length, float(p_xy[0]),
                           float(p_xy[1]))

    def project_many(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`project` of (M, 2) points at once; returns arrays (s, lateral), each (M,)."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        px, py = pts[:, 0], pts[:, 1]
        j = np.empty(len(pts), dtype=np.int64)
        for c in range(0, len(pts), _PROJECT_CHUNK):  # nearest table sample, in chunks to bound memory
            d = pts[c:c + _PROJECT_CHUNK, None, :] - self._xy[None, :, :]
            j[c:c + _PROJECT_CHUNK] = np.argmin(np.einsum("ijk,ijk->ij", d, d), axis=1)
        s = j * self._h
        x, y, th, ka = self._xy[j, 0], self._xy[j, 1], self._th[j], self._ka[j]
        for _ in range(MAX_PROJECT_STEPS):
            dx, dy = px - x, py - y
            a = dx * np.cos(th) + dy * np.sin(th)
            lat = -dx * np.sin(th) + dy * np.cos(th)
            straight = np.abs(ka) * (np.abs(a) + np.abs(lat)) < 1e-9
            k = np.where(straight, 1.0, ka)
            ds = np.where(straight, a, np.arctan2(k * a, 1.0 - k * lat) / k)
            s = np.clip(s + ds, 0.0, self.length)
            x, y, th, ka, _ = self._interp(s)
            if np.all(np.abs(ds) < 1e-9):
                break
        lateral = -(px - x) * np.sin(th) + (py - y) * np.cos(th)
        return s, lateral

    # ------------------------------------------------------------------ lanes
    def lane_offset(self, lane: int = 0) -> float:
        """Lateral offset of the centre of ``lane`` from the centre-line (m; negative = right of travel).

        Right-hand traffic; lane 0 is the rightmost. With a twin the lanes fill ``[-lanes*lane_width, 0]``; without one
        they are centred on the centre-line.
        """
        if not (0 <= lane < self.lanes):
            raise ValueError(f"Road {self.id!r}: lane must be in [0, {self.lanes - 1}], got {lane}")
        right, _ = self.edge_offsets
        return right + (lane + 0.5) * self.lane_width

    @property
    def edge_offsets(self) -> tuple[float, float]:
        """(right, left) lateral offsets of this direction's carriageway edges (m)."""
        width = self.lanes * self.lane_width
        return (-width, 0.0) if self.twin is not None else (-width / 2.0, width / 2.0)

    @property
    def total_turn(self) -> float:
        """Total absolute heading change along the road, the integral of abs(curvature) ds (rad)."""
        return float(np.sum(np.abs(np.diff(self._th))))

    @property
    def samples(self) -> np.ndarray:
        """(N+1, 2) read-only table of centre-line points at uniform arc-length spacing ``length / N`` (m)."""
        return self._xy
