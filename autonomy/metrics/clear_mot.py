"""The CLEAR-MOT pairing of vehicles and tracks step by step, and IDF1's identity true positives.

The rules are those of the MOTChallenge's reference implementation, py-motmetrics 1.4 (``MOTAccumulator.update``),
kept to the same arithmetic so every count and the MOTP sum come out the same to the bit
(``tests/autonomy/test_clear_mot.py`` compares them with motmetrics on random crowds). At each step, given the
pairs within the match radius (the only ones that may match):

1. a vehicle keeps the track it was last matched to when that track is present, not yet taken this step and within
   the radius (a MATCH), vehicles in the order given;
2. the rest are paired by one least-total-distance assignment (SciPy's ``linear_sum_assignment`` on the distance
   matrix with the pairs beyond the radius or already taken made too dear to choose, exactly as motmetrics builds
   it), each pair a SWITCH when its vehicle was last matched to another track, else a MATCH;
3. the vehicles left are misses, the tracks left false positives.

IDF1's IDTP is the largest total, over one-to-one assignments of vehicles to tracks, of the steps each assigned pair
spent within the radius of each other (motmetrics' global assignment of whole trajectories; its dummy rows and
columns only let a vehicle or track go unassigned). It is solved cluster by cluster of the pairs that ever met.

This replaces motmetrics inside a run: its accumulator appends a Python event per pair and step and scores through
pandas tables, which took about a tenth of a 200-car city run's loop and, at import, half a second of its setup.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["ClearMotMatcher", "identity_true_positives"]


class ClearMotMatcher:
    """The running CLEAR-MOT counts of one tracker (module docstring)."""

    def __init__(self) -> None:
        self._last: dict[int, int] = {}  # vehicle id -> the track it was last matched to
        self.matches = 0
        """MATCH events: pairs kept or made with the vehicle's last track (or its first)."""
        self.switches = 0
        """SWITCH events: pairs made with another track than the vehicle's last."""
        self.misses = 0
        self.false_positives = 0
        self.tracked: dict[int, int] = {}
        """Vehicle id -> steps matched (MATCH or SWITCH)."""
        self._distances: list[np.ndarray] = []  # per step: matched distances in motmetrics' event order, 0 elsewhere
        self._pairs: list[np.ndarray] = []  # per step since the last summary: (vehicle id, track id) within the radius
        self._met = np.zeros((0, 2), dtype=np.int64)  # the distinct pairs of earlier steps ...
        self._met_steps = np.zeros(0, dtype=np.int64)  # ... and the steps each was within the radius

    def update(self, oids: np.ndarray, hids: np.ndarray, pair_o: np.ndarray, pair_h: np.ndarray,
               pair_d: np.ndarray) -> None:
        """One step: vehicles ``oids`` (n,), tracks ``hids`` (m,) (int64, unique) and the pairs within the match
        radius: vehicle ``oids[pair_o[k]]`` and track ``hids[pair_h[k]]``, ``pair_d[k]`` apart (m), each pair once."""
        no, nh = len(oids), len(hids)
        self._pairs.append(np.stack((oids[pair_o], hids[pair_h]), axis=1))
        d = np.full((no, nh), np.nan)  # NaN: cannot match
        d[pair_o, pair_h] = pair_d
        finite = ~np.isnan(d)
        o_done = np.zeros(no, dtype=bool)
        h_done = np.zeros(nh, dtype=bool)
        matched: list[float] = []
        if no and nh:
            column = {h: j for j, h in enumerate(hids.tolist())}
            last = self._last
            for i, o in enumerate(oids.tolist()):  # 1. carry the last pairs forward
                h = last.get(o)
                j = None if h is None else column.get(h)
                if j is None or h_done[j] or not finite[i, j]:
                    continue
                o_done[i] = h_done[j] = True
                self.matches += 1
                self.tracked[o] = self.tracked.get(o, 0) + 1
                matched.append(float(d[i, j]))
            rest = d.astype(float, copy=True)  # 2. the least-total-distance assignment of the rest
            rest[o_done, :] = np.nan
            rest[:, h_done] = np.nan
            for i, j in zip(*_assignment(rest), strict=True):
                if not np.isfinite(rest[i, j]):
                    continue
                o, h = int(oids[i]), int(hids[j])
                if o in last and last[o] != h:
                    self.switches += 1
                else:
                    self.matches += 1
                last[o] = h
                self.tracked[o] = self.tracked.get(o, 0) + 1
                o_done[i] = h_done[j] = True
                matched.append(float(rest[i, j]))
        missed, false = no - int(o_done.sum()), nh - int(h_done.sum())
        self.misses += missed
        self.false_positives += false
        # motmetrics' events of the step in order: the matches carried forward, the assignment's, then the misses and
        # false positives (no distance: 0 in its sum)
        self._distances.append(np.concatenate((np.asarray(matched, dtype=float), np.zeros(missed + false))))

    @property
    def detections(self) -> int:
        """Matched pairs, switches included (MOTP's denominator)."""
        return self.matches + self.switches

    def distance_sum(self) -> float:
        """The sum of the matched pairs' distances (m), summed as motmetrics sums its event table."""
        if not self._distances:
            return 0.0
        self._distances = [np.concatenate(self._distances)]  # one array: a run asks at every flush
        return float(self._distances[0].sum())

    def identity_true_positives(self) -> int:
        """IDF1's IDTP over every step so far (module docstring)."""
        if self._pairs:  # fold the new steps into the counts, so each summary costs what is new and what met
            new = np.concatenate(self._pairs)
            self._met, self._met_steps = _counted(np.concatenate((self._met, new)),
                                                  np.concatenate((self._met_steps, np.ones(len(new), dtype=np.int64))))
            self._pairs = []
        return _best_total(self._met, self._met_steps)


def identity_true_positives(pairs: np.ndarray) -> int:
    """The largest total count over one-to-one assignments of vehicles to tracks, where ``pairs`` (k, 2) lists
    (vehicle id, track id) once per step the two were within the match radius."""
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    return _best_total(*_counted(pairs, np.ones(len(pairs), dtype=np.int64)))


def _best_total(pairs: np.ndarray, counts: np.ndarray) -> int:
    """:func:`identity_true_positives` of the distinct ``pairs`` (k, 2), each met on ``counts`` (k,) steps."""
    if len(pairs) == 0:
        return 0
    (o_ids, oi), (h_ids, hj) = (np.unique(pairs[:, c], return_inverse=True) for c in (0, 1))
    no = len(o_ids)
    graph = coo_matrix((np.ones(len(oi)), (oi, no + hj)), shape=(no + len(h_ids),) * 2)
    _, label = connected_components(graph, directed=False)
    lone = np.bincount(label[oi])[label[oi]] == 1  # a cluster of one pair is that pair
    total = int(counts[lone].sum())
    busy = ~lone
    if not busy.any():
        return total
    order = np.argsort(label[oi[busy]], kind="stable")
    bo, bh, bc, bl = oi[busy][order], hj[busy][order], counts[busy][order], label[oi[busy]][order]
    starts = np.flatnonzero(np.r_[True, bl[1:] != bl[:-1]])
    for a, b in zip(starts, np.r_[starts[1:], len(bl)], strict=True):
        rows, r_at = np.unique(bo[a:b], return_inverse=True)
        cols, c_at = np.unique(bh[a:b], return_inverse=True)
        w = np.zeros((len(rows), len(cols)))
        w[r_at, c_at] = bc[a:b]
        r, c = linear_sum_assignment(w, maximize=True)
        total += int(w[r, c].sum())
    return total


def _counted(pairs: np.ndarray, steps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``pairs`` (k, 2) and the sum of ``steps`` (k,) over each."""
    if len(pairs) == 0:
        return pairs.reshape(0, 2), np.zeros(0, dtype=np.int64)
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))  # the rows np.unique(axis=0) gives, a tenth of its time
    p, st = pairs[order], np.asarray(steps, dtype=np.int64)[order]
    starts = np.flatnonzero(np.r_[True, (p[1:, 0] != p[:-1, 0]) | (p[1:, 1] != p[:-1, 1])])
    return p[starts], np.add.reduceat(st, starts)


def _assignment(costs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """SciPy's assignment of ``costs`` with NaN for "cannot pair", the matrix made finite as motmetrics 1.4's
    ``lap.add_expensive_edges`` makes it (an edge off the graph costs 2 r (max |cost| + 1) + 1, r the smaller side),
    so the same problem is solved; pairs through such an edge are the caller's to drop."""
    valid = np.isfinite(costs)
    if not valid.any():
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    if not valid.all():
        large = 2 * min(costs.shape) * (np.abs(costs[valid]).max() + 1) + 1
        costs = np.where(valid, costs, large)
    return linear_sum_assignment(costs)
