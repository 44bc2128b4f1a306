"""Track pictures as arrays for the team's association: predicted once for all receivers, associated through a k-d tree.

Team fusion among traffic (:mod:`.track_association`) predicts every track of every teammate's picture to the fusion
time and associates it with one's own. The teammates of a broadcast receive the same picture and fuse at the same
tick, so the prediction (:class:`~.track_fusion.PredictedEstimates`, the same numbers for every receiver) is made
once and handed to each (:func:`track_set`): among 200 cars and 50 UAVs, predicting each picture 49 times was a third
of the team's autonomy time. :func:`associate_sets` makes the pairs of
:func:`~.track_association.associate_positions` from the pairs k-d trees find within each track's reach instead of the
distance of every own track to every teammate track: a pair inside the gate lies within ``sqrt(χ² (λ_a + λ_b))``,
the λ the largest eigenvalues of the two tracks' covariances (``dᵀ(P_a + P_b)⁻¹d ≥ |d|² / (λ_a + λ_b)``), so within
``sqrt(2 χ² λ)`` of whichever of the two has the larger λ; each tree is asked for the other set's tracks within that
radius of each of its own (a radius per track: one new or coasting track with a covariance of hundreds of metres
no longer widens the search for all), and solves each connected component of the
gating graph alone with the tracker's compiled GNN kernels: with a cost ``big`` for a pair outside the gate, the
dense assignment's cost is ``big · min(n, m) + Σ (c − big)`` over the gated pairs it makes (every partial matching
extends to a full one with non-gated pairs), and with the same miss cost ``big`` for every track the least-cost
assignment with misses makes the same matching of greatest ``Σ (big − c)``, which splits over the components.

A gated pair's cost ``c = d² + c_id`` adds to the Mahalanobis distance what the two tracks' target probabilities say
about whether they are one car (feature-aided track association; :func:`identity_cost`): a teammate's track it takes
for the target pairs with one's own target track before a track one holds for another car, where the kinematics
alone cannot tell (two tracks of a car that stopped and drove off, a radar track left where it stood).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from autonomy.estimation.tracking import assignment_kernels as kernels
from autonomy.estimation.tracking.assignment import solve_component
from interfaces.state import TrackPicture, TrackReport

from .track_fusion import PredictedEstimates

__all__ = ["ID_COST_SPAN", "TrackSet", "associate_sets", "identity_cost", "mahalanobis2", "set_pairs",
           "track_set"]

P_FLOOR = 1e-4
"""Target probabilities are taken within ``[P_FLOOR, 1 − P_FLOOR]`` in the association: no belief is certain."""
ID_COST_SPAN = float(-2.0 * math.log(P_FLOOR * (1.0 - P_FLOOR)))
"""The largest :func:`identity_cost` (≈ 18.4)."""


def identity_cost(qa: np.ndarray, qb: np.ndarray, n_tracks: int) -> np.ndarray:
    """What the target probabilities ``qa`` and ``qb`` of two tracks (broadcast) add to their association cost:
    ``−2 ln κ`` with ``κ = q_a q_b / π + (1 − q_a)(1 − q_b) / (1 − π)`` the likelihood ratio of the two beliefs under
    "one car" against "two cars" (under one car both speak of one identity, drawn with prior ``π``; under two the
    beliefs are independent), ``π = 1 / (n_tracks + 1)`` the prior that a track is the target among ``n_tracks``
    (and "in no track"). Shifted by ``2 ln max(1/π, 1/(1 − π))``, the largest κ, so every cost is in
    ``[0, ID_COST_SPAN]``: among matchings with as many pairs (what the association compares) the shift cancels."""
    prior = 1.0 / (max(int(n_tracks), 1) + 1.0)
    a = np.clip(qa, P_FLOOR, 1.0 - P_FLOOR)
    b = np.clip(qb, P_FLOOR, 1.0 - P_FLOOR)
    kappa = a * b / prior + (1.0 - a) * (1.0 - b) / (1.0 - prior)
    return 2.0 * np.log(max(1.0 / prior, 1.0 / (1.0 - prior)) / kappa)


def mahalanobis2(pa: np.ndarray, Pa: np.ndarray, pb: np.ndarray, Pb: np.ndarray) -> np.ndarray:
    """``dᵀ (P_a + P_b)⁻¹ d`` with ``d = p_a − p_b`` over broadcast positions (..., 2) and covariances (..., 2, 2),
    the 2×2 inverse in closed form (the same float operations whatever the broadcast)."""
    d = pa - pb
    S = Pa + Pb
    det = S[..., 0, 0] * S[..., 1, 1] - S[..., 0, 1] * S[..., 1, 0]
    return (S[..., 1, 1] * d[..., 0] ** 2 - 2 * S[..., 0, 1] * d[..., 0] * d[..., 1]
            + S[..., 0, 0] * d[..., 1] ** 2) / np.maximum(det, 1e-300)


@dataclass(eq=False)
class TrackSet:
    """Tracks with a covariance predicted to one time, as arrays.

    Attributes
    ----------
    reports : list[TrackReport]
        The tracks, in the order of the arrays.
    est : PredictedEstimates
        Their predictions.
    xy : np.ndarray
        (n, 2) predicted positions (m).
    P : np.ndarray
        (n, 2, 2) their covariances (m²).
    p : np.ndarray
        (n,) target probabilities.
    lam : np.ndarray
        (n,) largest eigenvalue of each of ``P`` (m²): how far a pair with the track can reach (module docstring).
    """

    reports: list[TrackReport]
    est: PredictedEstimates
    xy: np.ndarray
    P: np.ndarray
    p: np.ndarray
    lam: np.ndarray
    _tree: cKDTree | None = field(default=None, repr=False)

    def tree(self) -> cKDTree:
        """k-d tree of :attr:`xy` (made once)."""
        if self._tree is None:
            self._tree = cKDTree(self.xy)
        return self._tree

    @classmethod
    def of(cls, reports: Sequence[TrackReport], t: float, q: float) -> TrackSet:
        """``reports`` (each with a covariance) predicted to ``t`` (s) with white-acceleration density ``q``
        (m²/s³)."""
        est = PredictedEstimates([r.estimate for r in reports], t, q)
        P = est.P_xy
        a, b, c = P[:, 0, 0], 0.5 * (P[:, 0, 1] + P[:, 1, 0]), P[:, 1, 1]
        lam = 0.5 * (a + c) + np.sqrt(0.25 * (a - c) ** 2 + b * b)
        return cls(reports=list(reports), est=est, xy=est.xy, P=P,
                   p=np.array([r.target_probability for r in reports], dtype=float), lam=lam)


_PREDICTED: dict[tuple[int, float], tuple[TrackPicture, TrackSet]] = {}
"""The predictions of the current fusion time, per (picture, q); the picture is held, so its id is not reused."""
_AT: list[float] = [float("nan")]


def track_set(picture: TrackPicture, t: float, q: float) -> TrackSet:
    """The tracks of ``picture`` that have a covariance, predicted to ``t`` (s) (:meth:`TrackSet.of`): made once per
    picture and ``q`` for all the receivers that fuse at ``t``; those of an earlier time are let go."""
    if t != _AT[0]:
        _PREDICTED.clear()
        _AT[0] = float(t)
    key = (id(picture), float(q))
    hit = _PREDICTED.get(key)
    if hit is not None and hit[0] is picture:
        return hit[1]
    made = TrackSet.of([r for r in picture.tracks if r.estimate.P is not None], t, q)
    _PREDICTED[key] = (picture, made)
    return made


def big_cost(threshold: float) -> float:
    """The cost of a pair outside the gate (and of a track left alone): above every gated pair's cost by far."""
    return (threshold + ID_COST_SPAN) * 10.0 + 1.0


def associate_sets(a: TrackSet, b: TrackSet, threshold: float) -> list[tuple[int, int]]:
    """:func:`~.track_association.associate_positions` of the tracks of ``a`` and ``b`` (the same pairs, sorted),
    gating only the pairs the k-d trees find within each track's reach, and solving each connected component of the
    gating graph alone (module docstring)."""
    rows, cols = set_pairs(a, b, threshold)
    return list(zip(rows.tolist(), cols.tolist(), strict=True))


def set_pairs(a: TrackSet, b: TrackSet, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """The pairs of :func:`associate_sets` as two int64 arrays (a's tracks and b's), in the order of a's tracks."""
    n, m = len(a.xy), len(b.xy)
    none = np.zeros(0, dtype=np.int64)
    if not n or not m:
        return none, none
    # a gated pair lies within the reach of the one of its tracks with the larger λ: each search keeps the pairs of
    # its own tracks' reach that are theirs by that rule (a's on a tie), so the two are disjoint and hold every one
    i_a, j_a = _within(b.tree(), a.xy, a.lam, threshold)  # b's tracks within the reach of each of a's
    mine = a.lam[i_a] >= b.lam[j_a]
    j_b, i_b = _within(a.tree(), b.xy, b.lam, threshold)  # and a's within the reach of each of b's
    theirs = b.lam[j_b] > a.lam[i_b]
    near = np.sort(np.concatenate((i_a[mine] * m + j_a[mine], i_b[theirs] * m + j_b[theirs])))  # row-major: the
    i, j = near // m, near % m  # kernels' order
    d2 = mahalanobis2(a.xy[i], a.P[i], b.xy[j], b.P[j])
    keep = d2 <= threshold
    rows, cols = i[keep], j[keep]
    if not rows.size:
        return none, none
    cost = d2[keep] + identity_cost(a.p[rows], b.p[cols], max(n, m))
    # with the same cost ``big`` for every own track left alone, the least-cost assignment with misses is the
    # assignment of least cost with ``big`` outside the gate: both make the gated matching of greatest Σ (big − c)
    miss = np.full(n, big_cost(threshold))
    order, starts = kernels.pair_clusters(rows, cols, n)
    take, hard = kernels.gnn_clusters(rows, cols, cost, miss, order, starts, n, m, 500)
    chosen = [take] + [solve_component(*kernels.cluster_matrix(rows, cols, cost, order, starts[h], starts[h + 1], n,
                                                               m), miss) for h in hard]
    picked = np.concatenate(chosen).astype(np.int64)
    picked = picked[np.argsort(rows[picked], kind="stable")]  # a matching: each of a's tracks once
    return rows[picked], cols[picked]


def _within(tree: cKDTree, xy: np.ndarray, lam: np.ndarray, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """(k, j) of every point j of ``tree`` within ``sqrt(2 · threshold · lam[k])`` of ``xy[k]`` (widened by a relative
    1e-9 and 1e-9 m against round-off), as two int64 arrays."""
    radius = np.sqrt(2.0 * threshold * lam) * (1.0 + 1e-9) + 1e-9
    found = tree.query_ball_point(xy, radius)
    counts = np.fromiter(map(len, found), dtype=np.int64, count=len(found))
    j = np.fromiter(itertools.chain.from_iterable(found), dtype=np.int64, count=int(counts.sum()))
    return np.repeat(np.arange(len(found), dtype=np.int64), counts), j
