"""Team fusion among traffic: associate the teammates' tracks with one's own before fusing, and agree on the target.

Each UAV with a multi-target tracker shares a :class:`~interfaces.state.TrackPicture` (its confirmed tracks, their
target probabilities and the class evidence of its own sensors). At a fusion step, for each teammate's picture no
older than ``max_age_s``:

1. every track is predicted to the fusion time (constant velocity, :class:`~.track_fusion.PredictedEstimates`), a
   teammate's picture once for all its receivers (:func:`~.track_sets.track_set`);
2. the teammate's tracks are assigned to one's own by ``scipy.optimize.linear_sum_assignment`` on the Mahalanobis
   distance of the position difference, ``dᵀ (P_a + P_b)⁻¹ d`` (cross-covariance ignored, as the convex fusion
   does; covariance intersection does not need it), gated at the χ²₂ quantile ``gate_probability``, plus what the
   two tracks' target probabilities say about their being one car (:func:`~.track_sets.identity_cost`); only
   assigned pairs are one car (through k-d trees, each cluster of nearby cars alone:
   :func:`~.track_sets.associate_sets`);
3. the team's belief of which car is the target is the linear opinion pool of the members' beliefs: one's own
   track k has team probability ``(p_k + Σ_j p_j) / n``, its own target probability plus those of the teammates'
   tracks assigned to it, over the ``n`` UAVs whose pictures are in (oneself included). A car only a teammate holds
   is, in one's own belief, part of "the target is in none of my tracks" (``p_0``), which one shares out as the
   teammate does: its track j has ``p_j (1 + p_0) / n``, and "in no track" keeps ``p_0 (1 − Σ_loose p_j)`` of
   one's own share. An average of beliefs counts no evidence twice (each member's belief already
   holds its own cue, continuity and class readings), so a UAV that has not yet told the target from a look-alike
   follows a teammate that has;
4. the most probable candidate is the target if it is more probable than "the target is in no track" (whose pooled
   probability is the average of ``1 − Σ p`` over the members) and reaches ``min_probability`` (default 0: the
   maximum a posteriori choice); its estimate is fused (convex or covariance intersection) with every teammate track
   assigned to it. Otherwise the UAV's own estimate stands (its target track, or where it searches).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.special import gammaincinv

from autonomy.diagnostics import HoldsTracks
from interfaces.state import TargetEstimate, TrackPicture, TrackReport

from .track_fusion import PredictedEstimates, fuse_estimates
from .track_sets import TrackSet, big_cost, identity_cost, mahalanobis2, set_pairs, track_set

__all__ = ["TeamTrackFusion", "TeamTarget", "associate_positions", "associate_tracks", "track_picture"]


@dataclass(frozen=True)
class TeamTarget:
    """The team's target at a fusion step.

    Attributes
    ----------
    estimate : TargetEstimate | None
        The fused estimate of the target (None: no candidate reached ``min_probability``).
    probability : float
        Its team probability.
    own_track_id : int | None
        One's own track it is (None: a teammate's track one does not hold, or none).
    fused_with : int
        Teammate tracks fused into it.
    """

    estimate: TargetEstimate | None
    probability: float
    own_track_id: int | None
    fused_with: int


def track_picture(estimator: object, t: float) -> TrackPicture | None:
    """What a UAV with many tracks shares at ``t`` (s): its confirmed tracks and its target track; None for an
    estimator that does not hold tracks (:class:`~autonomy.diagnostics.HoldsTracks`)."""
    if not isinstance(estimator, HoldsTracks):
        return None
    return TrackPicture(t=t, tracks=tuple(r for r in estimator.track_reports() if r.confirmed),
                        target_track_id=estimator.target_track_id)


def associate_tracks(own: Sequence[TargetEstimate], other: Sequence[TargetEstimate],
                     threshold: float) -> list[tuple[int, int]]:
    """Pairs ``(i, j)`` of ``own[i]`` and ``other[j]`` (estimates at one time) that are one car: among the pairs whose
    Mahalanobis position distance is under ``threshold`` (χ², 2 degrees of freedom), the most pairs, and of those
    the assignment of least total distance."""
    if not own or not other:
        return []
    return associate_positions(np.array([e.p_W[:2] for e in own]), np.array([e.P[:2, :2] for e in own]),
                               np.array([e.p_W[:2] for e in other]), np.array([e.P[:2, :2] for e in other]), threshold)


def associate_positions(pa: np.ndarray, Pa: np.ndarray, pb: np.ndarray, Pb: np.ndarray, threshold: float,
                        qa: np.ndarray | None = None, qb: np.ndarray | None = None) -> list[tuple[int, int]]:
    """:func:`associate_tracks` of positions ``pa`` (n, 2) and ``pb`` (m, 2) (m) with covariances ``Pa`` (n, 2, 2) and
    ``Pb`` (m, 2, 2) (m²) and target probabilities ``qa`` (n,) and ``qb`` (m,): the plain dense assignment, the
    reference of :func:`~.track_sets.associate_sets`."""
    if len(pa) == 0 or len(pb) == 0:
        return []
    maha = mahalanobis2(pa[:, None, :], Pa[:, None], pb[None, :, :], Pb[None, :])  # (n, m)
    qa = np.zeros(len(pa)) if qa is None else qa
    qb = np.zeros(len(pb)) if qb is None else qb
    ident = identity_cost(qa[:, None], qb[None, :], max(len(pa), len(pb)))
    big = big_cost(threshold)
    cost = np.where(maha <= threshold, maha + ident, big)
    rows, cols = linear_sum_assignment(cost)
    return [(int(i), int(j)) for i, j in zip(rows, cols, strict=True) if cost[i, j] < big]


class TeamTrackFusion:
    """Associates the teammates' tracks with one's own, picks the team's target and fuses it (module docstring).

    Parameters
    ----------
    method : {"convex", "covariance_intersection"}
        How associated tracks are fused.
    max_age_s : float
        Pictures older than this are ignored (s).
    q : float
        White-acceleration density used to predict tracks to the fusion time (m²/s³).
    gate_probability : float
        Probability of the association gate, in (0, 1).
    min_probability : float
        Team probability the target candidate needs besides beating "in no track", in [0, 1].
    switch_margin : float
        Team probability by which another candidate must beat the own track chosen at the previous step to be taken
        instead, in [0, 1) (0: the most probable candidate at every step).
    """

    def __init__(self, method: str, max_age_s: float, q: float, gate_probability: float = 0.999,
                 min_probability: float = 0.0, switch_margin: float = 0.0) -> None:
        if method not in ("convex", "covariance_intersection"):
            raise ValueError(f"TeamTrackFusion.method must be convex|covariance_intersection, got {method!r}")
        if not 0 < gate_probability < 1:
            raise ValueError(f"TeamTrackFusion.gate_probability must be in (0, 1), got {gate_probability!r}")
        self.method = method
        self.max_age_s = float(max_age_s)
        self.q = float(q)
        self.threshold = float(2.0 * gammaincinv(1.0, gate_probability))
        self.min_probability = float(min_probability)
        if not 0.0 <= switch_margin < 1.0:
            raise ValueError(f"TeamTrackFusion.switch_margin must be in [0, 1), got {switch_margin!r}")
        self.switch_margin = float(switch_margin)
        self._kept: int | None = None  # one's own track chosen at the previous step
        self.associated = 0
        self.disagreements = 0  # steps where the team's target was not one's own target track

    def fuse(self, t: float, local: TargetEstimate | None, own: Sequence[TrackReport], own_target: int | None,
             pictures: Sequence[TrackPicture]) -> TeamTarget:
        """The team's target at ``t`` (s) from one's own confirmed tracks ``own`` (``own_target`` the one taken for
        the target; ``local`` one's own target estimate) and the teammates' ``pictures`` (module docstring)."""
        mine = [r for r in own if r.confirmed and r.estimate.P is not None]
        own_set = TrackSet.of(mine, t, self.q)
        own_est = own_set.est
        pooled = own_set.p.copy()
        own_none = max(0.0, 1.0 - float(pooled.sum()))
        none = 0.0  # the members' pooled "in no track", one's own share added after the loop
        taken: list[tuple[PredictedEstimates, np.ndarray, np.ndarray]] = []  # per picture: its pairs with one's own
        loose: list[tuple[float, PredictedEstimates, int]] = []
        members = 1
        for pic in pictures:
            if not 0.0 <= t - pic.t <= self.max_age_s:
                continue
            members += 1
            their_set = track_set(pic, t, self.q)
            their_est, their_p = their_set.est, their_set.p
            if len(their_p) == len(pic.tracks):  # every track has a covariance: the same sum, added in order
                total = float(np.cumsum(their_p)[-1]) if len(their_p) else 0.0
            else:
                total = sum(r.target_probability for r in pic.tracks)
            none += max(0.0, 1.0 - total)
            rows, cols = set_pairs(own_set, their_set, self.threshold)
            self.associated += len(rows)
            pooled[rows] += their_p[cols]  # a matching: each own track once per picture, pictures in order
            taken.append((their_est, rows, cols))
            free = their_p > 0.0
            free[cols] = False
            loose.extend((p_j, their_est, j) for j, p_j in zip(np.flatnonzero(free).tolist(),
                                                               their_p[free].tolist(), strict=True))
        none += own_none * max(0.0, 1.0 - sum(p for p, _, _ in loose))  # one's own share of "no track"
        best_own = int(np.argmax(pooled)) if len(pooled) else -1
        best_loose = max(range(len(loose)), key=lambda k: loose[k][0]) if loose else -1
        p_own = float(pooled[best_own]) / members if best_own >= 0 else 0.0
        p_loose = loose[best_loose][0] * (1.0 + own_none) / members if best_loose >= 0 else 0.0
        kept = next((k for k, r in enumerate(mine) if r.track_id == self._kept), None) if self.switch_margin else None
        if kept is not None:
            p_kept = float(pooled[kept]) / members
            if (p_kept + self.switch_margin >= max(p_own, p_loose) and p_kept >= self.min_probability
                    and p_kept > none / members):
                best_own, p_own, p_loose = kept, p_kept, 0.0  # not beaten by the margin: kept
        best = max(p_own, p_loose)
        self._kept = None
        if best < self.min_probability or best <= none / members:
            return TeamTarget(estimate=local, probability=max(p_own, p_loose), own_track_id=None, fused_with=0)
        if p_own >= p_loose:
            track_id = self._kept = mine[best_own].track_id
            if track_id != own_target:
                self.disagreements += 1
            parts = [own_est[best_own], *(pred[int(cols[rows == best_own][0])] for pred, rows, cols in taken
                                          if np.any(rows == best_own))]
            return TeamTarget(estimate=fuse_estimates(self.method, t, parts), probability=p_own, own_track_id=track_id,
                              fused_with=len(parts) - 1)
        self.disagreements += 1
        _, pred, j = loose[best_loose]
        return TeamTarget(estimate=pred[j], probability=p_loose, own_track_id=None, fused_with=0)
