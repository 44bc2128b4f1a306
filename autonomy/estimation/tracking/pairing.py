"""Track initiation for many targets: the two-point logic of :mod:`.initiator`, generalised.

The position fixes of a scan that no track took (:class:`~.fixes.PositionFixer`) are paired with the tentative fixes
of earlier scans (at most ``tentative_window_s`` old): a pair is possible when the two lie within
``max_target_speed · Δt`` plus 3σ of each other, and the pairs are chosen by a minimum-distance assignment
(``scipy.optimize.linear_sum_assignment``), so each fix starts at most one track. Each pair starts a *tentative* track
with the position of the newer fix and the velocity of the pair (fused with the zero-mean speed prior), two hits in two
scans; the tracker's M-of-N logic confirms or drops it. The fixes that pair with nothing become tentative fixes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from .fixes import Fix
from .initiator import FilterFactory, two_point_prior
from .track import Track

__all__ = ["PairingInitiator"]

_NO_PAIR = 1e12


class PairingInitiator:
    """Starts tentative tracks from pairs of unassociated position fixes of two scans (module docstring).

    Parameters
    ----------
    filters : FilterFactory
        Builds a new track's filter.
    layout : tuple[str, ...]
        State layout of the filters (holds ``x, y, vx, vy``).
    max_target_speed : float
        Fastest plausible target (m/s).
    tentative_window_s : float
        How long a tentative fix waits for its partner (s).
    initial_speed_sigma : float or None
        Standard deviation of the zero-mean speed prior per velocity component (m/s); None: none.
    """

    def __init__(self, *, filters: FilterFactory, layout: tuple[str, ...], max_target_speed: float,
                 tentative_window_s: float, initial_speed_sigma: float | None) -> None:
        self.filters = filters
        self.layout = tuple(layout)
        self.max_target_speed = float(max_target_speed)
        self.tentative_window_s = float(tentative_window_s)
        self.initial_speed_sigma = initial_speed_sigma
        self._t = np.zeros(0)
        self._xy = np.zeros((0, 2))
        self._sd = np.zeros(0)  # largest standard deviation of each tentative fix's position (m)
        self._P: list[np.ndarray] = []

    @property
    def tentative(self) -> int:
        """Tentative fixes waiting for a partner."""
        return self._t.size

    def reset(self) -> None:
        """Forget every tentative fix."""
        self._t, self._xy, self._sd, self._P = np.zeros(0), np.zeros((0, 2)), np.zeros(0), []

    def initiate(self, fixes: Sequence[Fix]) -> list[Track]:
        """Tentative tracks (``hits = scans = 2``, not confirmed) from ``fixes`` (of one scan, taken at one time)
        paired with earlier tentative fixes; the unpaired ``fixes`` become tentative."""
        if not fixes:
            return []
        t_now = float(fixes[0][0].t_meas)
        keep = (t_now - self._t > 0) & (t_now - self._t <= self.tentative_window_s)
        self._t, self._xy, self._sd = self._t[keep], self._xy[keep], self._sd[keep]
        self._P = [P for P, k in zip(self._P, keep, strict=True) if k]
        xy = np.array([f[1] for f in fixes], dtype=float).reshape(-1, 2)
        sd = np.array([_largest_sd(f[2]) for f in fixes])
        new: list[Track] = []
        paired_old: set[int] = set()
        paired_new: set[int] = set()
        if self._t.size:
            dt = t_now - self._t                                           # (n_old,)
            gap = np.linalg.norm(xy[:, None, :] - self._xy[None, :, :], axis=-1)  # (n_new, n_old)
            reach = self.max_target_speed * dt[None, :] + 3.0 * np.hypot(sd[:, None], self._sd[None, :])
            ok = gap <= reach
            if ok.any():
                rows, cols = np.nonzero(ok.any(axis=1))[0], np.nonzero(ok.any(axis=0))[0]
                cost = np.where(ok, gap, _NO_PAIR)[np.ix_(rows, cols)]
                for r, c in zip(*linear_sum_assignment(cost), strict=True):
                    if cost[r, c] >= _NO_PAIR:
                        continue
                    i, j = int(rows[r]), int(cols[c])
                    d = float(dt[j])
                    v = (xy[i] - self._xy[j]) / d
                    Pv = (fixes[i][2] + self._P[j]) / d ** 2
                    x0, P0 = two_point_prior(self.layout, xy[i], fixes[i][2], v, Pv, self.initial_speed_sigma)
                    new.append(Track(self.filters(x0, P0, t_now), t_now, hits=2, scans=2, confirmed=False))
                    paired_old.add(j)
                    paired_new.add(i)
        keep_old = np.array([j not in paired_old for j in range(self._t.size)], dtype=bool)
        lone = [i for i in range(len(fixes)) if i not in paired_new]
        self._t = np.concatenate([self._t[keep_old], np.full(len(lone), t_now)])
        self._xy = np.vstack([self._xy[keep_old], xy[lone]])
        self._sd = np.concatenate([self._sd[keep_old], sd[lone]])
        self._P = [P for P, k in zip(self._P, keep_old, strict=True) if k] + [fixes[i][2] for i in lone]
        return new


def _largest_sd(P: np.ndarray) -> float:
    """Square root of the largest eigenvalue of the 2×2 covariance ``P`` (m), in closed form."""
    a, b, d = float(P[0, 0]), 0.5 * float(P[0, 1] + P[1, 0]), float(P[1, 1])
    return float(np.sqrt(0.5 * (a + d) + np.sqrt(0.25 * (a - d) ** 2 + b * b)))
