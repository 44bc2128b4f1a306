"""Track initiation by confirmed position fixes (two- or three-point logic).

Each detection that fixes a ground position (:class:`~.fixes.PositionFixer`) is kept as a tentative fix; a fix of a
later scan that lies within ``max_target_speed · Δt`` plus a 3σ margin of a tentative one confirms a track, with the
position of the newer fix and the velocity of the pair. With three-fix confirmation the pair is kept instead, and a
third fix where the pair predicts (within 3σ plus ``max_target_accel · Δt² / 2``) confirms it. A lone false alarm
therefore never starts a track, and clutter pairs are rare when false alarms are spread over a radar's whole field
of regard. The two-point velocity may be fused with a zero-mean speed prior ``N(0, initial_speed_sigma² I)``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from autonomy.estimation.base import Filter
from autonomy.estimation.measurements import MeasurementLike

from .fixes import PositionFixer
from .track import Track

__all__ = ["FilterFactory", "FixConfirmingInitiator", "two_point_prior"]

FilterFactory = Callable[[np.ndarray, np.ndarray, float], Filter]
"""Builds a new track's filter from ``(x0, P0, t0)`` (state, covariance, time in s)."""


class FixConfirmingInitiator:
    """Starts tracks from position fixes confirmed by one or two later fixes (module docstring).

    Parameters
    ----------
    fixer : PositionFixer
        The position fixes of a scan.
    filters : FilterFactory
        Builds a confirmed track's filter.
    layout : tuple[str, ...]
        State layout of the filters (must hold ``x, y, vx, vy``; ``ax, ay`` start with variance 4 m²/s⁴).
    max_target_speed : float
        Fastest plausible target (m/s).
    tentative_window_s : float
        How long a tentative fix waits for its confirming partner (s).
    confirm_fixes : int
        2 or 3 fixes confirm a track.
    max_target_accel : float
        Largest plausible target acceleration (m/s²): widens the third fix's gate.
    initial_speed_sigma : float or None
        Standard deviation of the zero-mean speed prior per velocity component (m/s); None: none.
    """

    def __init__(self, *, fixer: PositionFixer, filters: FilterFactory, layout: tuple[str, ...],
                 max_target_speed: float, tentative_window_s: float, confirm_fixes: int, max_target_accel: float,
                 initial_speed_sigma: float | None) -> None:
        self.fixer = fixer
        self.filters = filters
        self.layout = tuple(layout)
        self.max_target_speed = max_target_speed
        self.tentative_window_s = tentative_window_s
        self.confirm_fixes = confirm_fixes
        self.max_target_accel = max_target_accel
        self.initial_speed_sigma = initial_speed_sigma
        self._ix = [self.layout.index("x"), self.layout.index("y")]
        self._iv = [self.layout.index("vx"), self.layout.index("vy")]
        # tentative fixes (t, xy, P_xy) and, with confirm_fixes = 3, tentative pairs (t, xy, P_xy, v, P_v)
        self._tentative: list[tuple] = []

    def reset(self) -> None:
        """Forget every tentative fix (e.g. when a diverged track is dropped and restarted from a new scan)."""
        self._tentative = []

    def initiate(self, scan: Sequence[MeasurementLike]) -> list[Track]:
        """The tracks this scan's fixes confirm with the tentative fixes of earlier scans (at most one); the fixes
        that confirm nothing are kept as tentative."""
        fixes = self.fixer.fixes(scan)
        if not fixes:
            return []
        t_now = fixes[0][0].t_meas
        self._tentative = [tf for tf in self._tentative if 0 < t_now - tf[0] <= self.tentative_window_s]
        best, pairs = None, []
        for det, xy, Pxy in fixes:
            for t_old, xy_old, P_old, *vel in self._tentative:
                dt = t_now - t_old
                v, Pv = (xy - xy_old) / dt, (Pxy + P_old) / dt ** 2
                if vel:  # a pair: does this fix lie where it predicts?
                    v_old, Pv_old = vel
                    gap = float(np.linalg.norm(xy - xy_old - v_old * dt))
                    margin = (3.0 * float(np.sqrt(np.linalg.eigvalsh(Pxy + P_old + dt ** 2 * Pv_old).max()))
                              + 0.5 * self.max_target_accel * dt ** 2)
                    ok = gap <= margin
                else:
                    gap = float(np.linalg.norm(xy - xy_old))
                    ok = gap <= self.max_target_speed * dt + 3.0 * float(np.sqrt(np.linalg.eigvalsh(Pxy + P_old).max()))
                    if ok and self.confirm_fixes == 3:
                        pairs.append((t_now, xy, Pxy, v, Pv))
                        ok = False
                if ok and (best is None or gap < best[0]):
                    best = (gap, det, xy, Pxy, v, Pv)
        if best is None:
            self._tentative.extend((t_now, xy, Pxy) for _, xy, Pxy in fixes)
            self._tentative.extend(pairs)
            return []
        _, det, xy, Pxy, v, Pv = best
        self._tentative = []
        x0, P0 = self._prior(xy, Pxy, v, Pv)
        return [Track(self.filters(x0, P0, det.t_meas), det.t_meas)]

    def _prior(self, xy: np.ndarray, Pxy: np.ndarray, v: np.ndarray, Pv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A new track's state and covariance from a confirmed fix (m, m²) and its two-point velocity (m/s, m²/s²)."""
        return two_point_prior(self.layout, xy, Pxy, v, Pv, self.initial_speed_sigma)


def two_point_prior(layout: tuple[str, ...], xy: np.ndarray, Pxy: np.ndarray, v: np.ndarray, Pv: np.ndarray,
                    initial_speed_sigma: float | None) -> tuple[np.ndarray, np.ndarray]:
    """A new track's state and covariance in ``layout`` from a fix (m, m²) and its two-point velocity (m/s, m²/s²),
    the velocity fused with the zero-mean prior ``N(0, initial_speed_sigma² I)`` (None: not); ``ax, ay`` start at 0
    with variance 4 m²/s⁴."""
    if initial_speed_sigma is not None:  # fuse with the zero-mean speed prior N(0, σ² I)
        P_prior = np.eye(2) * initial_speed_sigma**2
        K = Pv @ np.linalg.inv(Pv + P_prior)
        v = v - K @ v
        Pv = Pv - K @ Pv
        Pv = 0.5 * (Pv + Pv.T)
    ix = [layout.index("x"), layout.index("y")]
    iv = [layout.index("vx"), layout.index("vy")]
    n = len(layout)
    x0 = np.zeros(n)
    P0 = np.zeros((n, n))
    x0[ix], x0[iv] = xy, v
    P0[np.ix_(ix, ix)] = Pxy + np.eye(2) * 1e-6
    P0[np.ix_(iv, iv)] = Pv + np.eye(2) * 1e-6
    for name in ("ax", "ay"):
        if name in layout:
            i = layout.index(name)
            P0[i, i] = 4.0
    return x0, P0
