"""Recursive-feasibility ("safe loiter") test of the search UAVs' obstacle clearance — an addition to the paper.

Under the search's discrete model (speed ``V``, step ``T``, ``psi_{k+1} = psi_k + u``,
``p_{k+1} = p_k + V T (cos psi_{k+1}, sin psi_{k+1})``, ``|u| <= u_max``), a UAV that turns by ``+u_max`` (left) or
``-u_max`` (right) every step visits the vertices of a regular polygon inscribed in a circle of radius
``R = V T / (2 sin(u_max / 2))`` centred at

    c_left  = p + (V T / 2) e(psi + u_max) + a e(psi + u_max + pi/2),
    c_right = p + (V T / 2) e(psi - u_max) + a e(psi - u_max - pi/2),

with ``e(t) = (cos t, sin t)`` and the apothem ``a = V T / (2 tan(u_max / 2))``. The polygon's vertex sequence runs
backwards too: the vertex before ``p`` is ``p - V T e(psi)``, the position one step earlier. So:

- the *loiter* of a state (position, heading) on one side is the path flown by holding the maximum turn forever;
  when ``2 pi / u_max`` is an integer ``n`` (45 deg: ``n = 8``) it is a closed ``n``-gon of chords ``V T``, whose
  last chord is the one flown *into* the state; otherwise its chords fill the annulus between the apothem and
  ``R``, and the disc of radius ``R`` is used (conservative by ``R - a``);
- the *clearance* of a state is the larger, over the two sides, of the distance from its loiter (the polygon's
  chords, or the disc) to the nearest obstacle footprint (or to the outside of a keep-in area);
- a state is *safe* when its clearance is at least ``d_col + margin``.

Induction: if the state at step ``k`` is safe on one side, the control ``u = +-u_max`` of that side leads to a
state whose loiter on that side is the same polygon, so it is safe too; the chord flown from ``k`` to ``k+1`` is a
chord of the loiter of the state at ``k+1``. A planner that admits only controls whose next state is safe therefore
always has a candidate, and every chord it flies stays at least ``d_col + margin`` from every obstacle, for all
time, as long as the start state was safe. (Up to the rounding slack ``TOL``, far below any margin.)

The guarantee is about the discrete model the kinematic mission flies; a physical UAV tracking the velocity
set-points deviates from the chords by its tracking error, which the margin must absorb.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

__all__ = ["LoiterSafety", "TOL"]

TOL = 1e-6  # m, rounding slack of the safe test: a state recomputed along its own loiter stays safe
_CLOSE_TOL = 1e-9  # |2 pi / u_max - n| below which the loiter counts as a closed n-gon
_KEEP_IN_PAD = 1e5  # m, extent of the outside of a keep-in area treated as an obstacle


class LoiterSafety:
    """Clearance of the left and right maximum-turn loiters of UAV states (module docstring).

    Parameters
    ----------
    speed : float
        UAV speed ``V`` (m/s), > 0.
    dt : float
        Step ``T`` (s), > 0.
    max_turn : float
        Turn bound ``u_max`` per step (rad), in (0, pi].
    required : float
        Clearance a safe state needs, ``d_col + margin`` (m), >= 0.
    obstacles : BaseGeometry
        Union of the obstacle footprints (m); may be empty.
    keep_in : BaseGeometry | None
        Area the UAVs must stay in (m), or ``None``; its outside counts as an obstacle.
    """

    def __init__(self, *, speed: float, dt: float, max_turn: float, required: float, obstacles: BaseGeometry,
                 keep_in: BaseGeometry | None = None):
        if not (speed > 0 and dt > 0):
            raise ValueError(f"LoiterSafety needs speed > 0 m/s and dt > 0 s, got {speed}, {dt}")
        if not (0 < max_turn <= np.pi):
            raise ValueError(f"LoiterSafety.max_turn must be in (0, pi] rad, got {max_turn}")
        if not (required >= 0):
            raise ValueError(f"LoiterSafety.required must be >= 0 m, got {required}")
        self.chord = float(speed * dt)
        self.max_turn = float(max_turn)
        self.required = float(required)
        self.radius = self.chord / (2.0 * np.sin(max_turn / 2.0))
        self.apothem = self.chord / (2.0 * np.tan(max_turn / 2.0)) if max_turn < np.pi else 0.0
        n = 2.0 * np.pi / max_turn
        self.n_chords = int(round(n)) if abs(n - round(n)) < _CLOSE_TOL else None
        geoms = [] if obstacles is None or obstacles.is_empty else [obstacles]
        if keep_in is not None:
            x0, y0, x1, y1 = keep_in.bounds
            pad = _KEEP_IN_PAD
            geoms.append(shapely.difference(shapely.box(x0 - pad, y0 - pad, x1 + pad, y1 + pad), keep_in))
        self.obstacles = shapely.union_all(geoms) if geoms else shapely.GeometryCollection()
        self.active = not self.obstacles.is_empty
        # a state whose position is this far from every obstacle is safe on both sides
        self._far = 2.0 * self.radius + self.required + 1.0

    def centres(self, p_xy: np.ndarray, heading: np.ndarray) -> np.ndarray:
        """(N, 2, 2) loiter centres (m) of states at ``p_xy`` (N, 2) m with ``heading`` (N,) rad; [:, 0] left."""
        p = np.asarray(p_xy, dtype=float).reshape(-1, 2)
        psi = np.asarray(heading, dtype=float).reshape(-1)
        out = np.empty((len(p), 2, 2))
        for s, sign in enumerate((1.0, -1.0)):
            t = psi + sign * self.max_turn
            n = t + sign * np.pi / 2
            out[:, s] = (p + 0.5 * self.chord * np.column_stack([np.cos(t), np.sin(t)])
                         + self.apothem * np.column_stack([np.cos(n), np.sin(n)]))
        return out

    def loiter(self, p_xy: np.ndarray, heading: np.ndarray) -> np.ndarray:
        """(N, 2, n + 1, 2) vertices (m) of the closed left ([:, 0]) and right loiters, starting and ending at the
        state's position; only when ``2 pi / u_max`` is an integer ``n``."""
        if self.n_chords is None:
            raise ValueError(f"the loiter at max_turn {self.max_turn} rad is not a closed polygon")
        p = np.asarray(p_xy, dtype=float).reshape(-1, 2)
        psi = np.asarray(heading, dtype=float).reshape(-1)
        j = np.arange(1, self.n_chords + 1)
        out = np.empty((len(p), 2, self.n_chords + 1, 2))
        for s, sign in enumerate((1.0, -1.0)):
            t = psi[:, None] + sign * self.max_turn * j[None, :]
            steps = self.chord * np.stack([np.cos(t), np.sin(t)], axis=-1)
            out[:, s, 0] = p
            out[:, s, 1:] = p[:, None, :] + np.cumsum(steps, axis=1)
        return out

    def clearance(self, p_xy: np.ndarray, heading: np.ndarray) -> np.ndarray:
        """(N,) larger clearance (m) of the two loiters of each state; ``inf`` without obstacles.

        States farther than ``2 R + required + 1`` m from every obstacle get the lower bound ``d - 2 R`` (their
        loiters lie within ``2 R`` of the position); a loiter disc that overlaps an obstacle gives a negative value.
        """
        p = np.asarray(p_xy, dtype=float).reshape(-1, 2)
        out = np.full(len(p), np.inf)
        if not self.active or len(p) == 0:
            return out
        psi = np.asarray(heading, dtype=float).reshape(-1)
        d0 = shapely.distance(self.obstacles, shapely.points(p))
        near = d0 < self._far
        out[~near] = d0[~near] - 2.0 * self.radius  # lower bound: every loiter lies within 2 R of the position
        if not near.any():
            return out
        if self.n_chords is not None:
            v = self.loiter(p[near], psi[near])
            d = shapely.distance(self.obstacles, shapely.linestrings(v.reshape(-1, self.n_chords + 1, 2)))
            d = d.reshape(-1, 2)
        else:
            c = self.centres(p[near], psi[near])
            d = shapely.distance(self.obstacles, shapely.points(c.reshape(-1, 2))).reshape(-1, 2) - self.radius
        out[near] = d.max(axis=1)
        return out

    def admits(self, clearance: np.ndarray) -> np.ndarray:
        """Bool array: a clearance (m) is at least ``required`` (up to ``TOL``)."""
        return np.asarray(clearance) >= self.required - TOL

    def is_safe(self, p_xy: np.ndarray, heading: np.ndarray) -> np.ndarray:
        """(N,) bool: the state's clearance is at least ``required`` (up to ``TOL``)."""
        return self.admits(self.clearance(p_xy, heading))
