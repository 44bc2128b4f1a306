"""Centre-line construction for :class:`~worlds.roads.road.Road`: knots, a clamped C2 cubic spline and its arc-length
table (see the ``road`` module docstring for the method). Frames: world ENU x-y plane, metres, radians."""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import solve_banded

__all__ = ["knots", "line_table", "spline_table"]

_GL_X, _GL_W = np.polynomial.legendre.leggauss(5)
_CORNER_ANGLE = np.deg2rad(30.0)  # rad; a vertex turning more than this is a corner
_CORNER_SETBACK = 6.0  # m; knots added this far from a corner (at most 30 % of the chord)
_CHORD_RATIO = 3.0  # largest ratio of neighbouring knot spacings left unsplit
_MAX_GRADING_PASSES = 20
_MAX_TURN_PER_SAMPLE = 0.01  # rad; the table is refined until the heading changes less than this between samples


def line_table(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Exact table of a two-vertex straight road: (its two end points, headings, zero curvatures, length)."""
    d = v[1] - v[0]
    length = float(np.hypot(*d))
    th = math.atan2(d[1], d[0])
    return v.copy(), np.array([th, th]), np.zeros(2), length


def knots(v: np.ndarray) -> np.ndarray:
    """Spline knots: the vertices plus points on the chords that keep the interpolant close to the polyline.

    1. At a corner (heading change > ``_CORNER_ANGLE``) a knot is added on each adjacent chord, ``_CORNER_SETBACK``
       (at most 30 % of the chord) from the vertex, so the turn happens near the corner.
    2. A chord longer than ``_CHORD_RATIO`` times a neighbouring one is split ``2 x`` that neighbour's length from the
       shared end, repeatedly, so knot spacing grows at most geometrically (large spacing jumps make C2 splines ring).

    Evenly spaced vertices on a gentle curve (every turn below the corner angle, similar chords) get no extra knots.
    """
    pts = [p for p in v]
    d = np.diff(v, axis=0)
    heading = np.arctan2(d[:, 1], d[:, 0])
    turn = np.abs(np.angle(np.exp(1j * np.diff(heading))))
    out = [pts[0]]
    for i in range(1, len(pts)):
        a, b = pts[i - 1], pts[i]
        chord = float(np.hypot(*(b - a)))
        cut = min(_CORNER_SETBACK, 0.3 * chord)
        if i >= 2 and turn[i - 2] > _CORNER_ANGLE:
            out.append(a + (b - a) * cut / chord)
        if i <= len(pts) - 2 and turn[i - 1] > _CORNER_ANGLE:
            out.append(b - (b - a) * cut / chord)
        out.append(b)
    k = np.array(out)
    for _ in range(_MAX_GRADING_PASSES):
        c = np.hypot(*np.diff(k, axis=0).T)
        left = np.concatenate([[np.inf], c[:-1]])
        right = np.concatenate([c[1:], [np.inf]])
        if not np.any((c > _CHORD_RATIO * left) | (c > _CHORD_RATIO * right)):
            break
        new = [k[0]]
        for i in range(len(c)):
            cuts = []  # distances from k[i] along the chord; symmetric, so a reversed polyline gets the same knots
            from_left, from_right = c[i] > _CHORD_RATIO * left[i], c[i] > _CHORD_RATIO * right[i]
            if from_left and from_right:
                a, b = 2.0 * left[i], c[i] - 2.0 * right[i]
                cuts = [a, b] if b - a >= min(left[i], right[i]) else [c[i] / 2.0]
            elif from_left:
                cuts = [2.0 * left[i]]
            elif from_right:
                cuts = [c[i] - 2.0 * right[i]]
            new += [k[i] + (k[i + 1] - k[i]) * (x / c[i]) for x in cuts]
            new.append(k[i + 1])
        k = np.array(new)
    return k


def spline_table(v: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Arc-length table of the chord-length cubic spline through knots ``v`` (K >= 3, 2), m.

    Returns (xy (N+1, 2) m, unwrapped heading (N+1,) rad, curvature (N+1,) 1/m, length m) at N+1 uniformly spaced
    arc lengths, with spacing at most ``spacing`` m and a heading change of at most about 0.01 rad between samples.
    """
    chords = np.hypot(*np.diff(v, axis=0).T)
    t = np.concatenate([[0.0], np.cumsum(chords)])
    spl = _ClampedSpline(t, v)
    # Sub-intervals of every knot span, short enough for 5-point Gauss-Legendre to be exact to rounding.
    n_sub = np.maximum(2, np.ceil(chords / (2.0 * spacing))).astype(int)
    tk = np.concatenate([np.linspace(t[i], t[i + 1], n_sub[i], endpoint=False) for i in range(len(chords))] + [t[-1:]])
    mid, half = (tk[:-1] + tk[1:]) / 2.0, (tk[1:] - tk[:-1]) / 2.0
    nodes = (mid[:, None] + half[:, None] * _GL_X[None, :]).ravel()
    speed_nodes = np.hypot(*spl(nodes, 1).T).reshape(-1, len(_GL_X))
    sk = np.concatenate([[0.0], np.cumsum(half * (speed_nodes @ _GL_W))])
    length = float(sk[-1])
    _, r1k, r2k = spl.eval3(tk)
    speed_k = np.hypot(*r1k.T)
    turn = float(np.sum(np.abs(r1k[:, 0] * r2k[:, 1] - r1k[:, 1] * r2k[:, 0]) / speed_k**2 * np.gradient(tk)))
    n = max(2, int(math.ceil(length / spacing)), int(math.ceil(turn / _MAX_TURN_PER_SAMPLE)))
    s_tab = np.linspace(0.0, length, n + 1)
    # t(s) first by cubic Hermite interpolation of the (sk, tk) table with slopes dt/ds = 1 / |r'(tk)|.
    k = np.clip(np.searchsorted(sk, s_tab, side="right") - 1, 0, len(sk) - 2)
    hs = sk[k + 1] - sk[k]
    u = (s_tab - sk[k]) / hs
    u2, u3 = u * u, u * u * u
    t_tab = ((2 * u3 - 3 * u2 + 1) * tk[k] + (u3 - 2 * u2 + u) * hs / speed_k[k]
             + (3 * u2 - 2 * u3) * tk[k + 1] + (u3 - u2) * hs / speed_k[k + 1])
    # One Newton step on s(t) = sk[k] + integral_{tk[k]}^{t} |r'| dt = s_tab makes it exact to rounding.
    mid, half = (tk[k] + t_tab) / 2.0, (t_tab - tk[k]) / 2.0
    nodes = (mid[:, None] + half[:, None] * _GL_X[None, :]).ravel()
    s_at = sk[k] + half * (np.hypot(*spl(nodes, 1).T).reshape(-1, len(_GL_X)) @ _GL_W)
    t_tab = t_tab - (s_at - s_tab) / np.hypot(*spl(t_tab, 1).T)
    t_tab[0], t_tab[-1] = t[0], t[-1]
    xy, r1, r2 = spl.eval3(t_tab)
    xy[0], xy[-1] = v[0], v[-1]
    sp = np.hypot(r1[:, 0], r1[:, 1])
    th = np.unwrap(np.arctan2(r1[:, 1], r1[:, 0]))
    ka = (r1[:, 0] * r2[:, 1] - r1[:, 1] * r2[:, 0]) / sp**3
    return xy, th, ka, length


class _ClampedSpline:
    """C2 cubic spline through ``y`` (K >= 3, D) at knots ``t``, clamped to the slopes of the end parabolas.

    On :math:`[t_i, t_{i+1}]` with :math:`h_i = t_{i+1} - t_i`, :math:`a = t_{i+1} - t`, :math:`b = t - t_i`:
    :math:`S = M_i a^3 / 6h + M_{i+1} b^3 / 6h + (y_i / h - M_i h / 6) a + (y_{i+1} / h - M_{i+1} h / 6) b`,
    the knot second derivatives :math:`M` solving the usual tridiagonal continuity system.
    """

    def __init__(self, t: np.ndarray, y: np.ndarray) -> None:
        h = np.diff(t)
        n = len(t)
        dy = np.diff(y, axis=0) / h[:, None]
        h0, h1, g0, g1 = h[0], h[1], h[-1], h[-2]
        # derivative of the parabola through the first (last) three vertices at the end vertex
        slope0 = (-(2 * h0 + h1) / (h0 * (h0 + h1)) * y[0] + (h0 + h1) / (h0 * h1) * y[1]
                  - h0 / (h1 * (h0 + h1)) * y[2])
        slope1 = ((2 * g0 + g1) / (g0 * (g0 + g1)) * y[-1] - (g0 + g1) / (g0 * g1) * y[-2]
                  + g0 / (g1 * (g0 + g1)) * y[-3])
        ab = np.zeros((3, n))
        ab[0, 1:] = h  # super-diagonal
        ab[2, :-1] = h  # sub-diagonal
        ab[1, 0], ab[1, -1] = 2 * h[0], 2 * h[-1]
        ab[1, 1:-1] = 2 * (h[:-1] + h[1:])
        rhs = np.empty_like(y)
        rhs[0] = 6 * (dy[0] - slope0)
        rhs[-1] = 6 * (slope1 - dy[-1])
        rhs[1:-1] = 6 * (dy[1:] - dy[:-1])
        self.t, self.y, self.h = t, y, h
        self.M = solve_banded((1, 1), ab, rhs, check_finite=False)

    def eval3(self, tt: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Value, first and second derivative at parameters ``tt``; each (N, D)."""
        i = np.clip(np.searchsorted(self.t, tt, side="right") - 1, 0, len(self.h) - 1)
        h = self.h[i][:, None]
        a = (self.t[i + 1] - tt)[:, None]
        b = (tt - self.t[i])[:, None]
        m0, m1 = self.M[i], self.M[i + 1]
        c0, c1 = self.y[i] / h - m0 * h / 6, self.y[i + 1] / h - m1 * h / 6
        value = (m0 * a**3 + m1 * b**3) / (6 * h) + c0 * a + c1 * b
        slope = (m1 * b**2 - m0 * a**2) / (2 * h) - c0 + c1
        return value, slope, (m0 * a + m1 * b) / h

    def __call__(self, tt: np.ndarray, nu: int = 0) -> np.ndarray:
        """Value (``nu`` = 0) or ``nu``-th derivative (1, 2) at parameters ``tt``; (N, D)."""
        tt = np.asarray(tt, dtype=float)
        i = np.clip(np.searchsorted(self.t, tt, side="right") - 1, 0, len(self.h) - 1)
        h = self.h[i][:, None]
        a = (self.t[i + 1] - tt)[:, None]
        b = (tt - self.t[i])[:, None]
        m0, m1, y0, y1 = self.M[i], self.M[i + 1], self.y[i], self.y[i + 1]
        if nu == 0:
            return (m0 * a**3 + m1 * b**3) / (6 * h) + (y0 / h - m0 * h / 6) * a + (y1 / h - m1 * h / 6) * b
        if nu == 1:
            return (-m0 * a**2 + m1 * b**2) / (2 * h) - (y0 / h - m0 * h / 6) + (y1 / h - m1 * h / 6)
        return (m0 * a + m1 * b) / h
