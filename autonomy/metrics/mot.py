"""Multi-object tracking scores of one UAV's tracks against every ground vehicle: CLEAR-MOT, IDF1 and GOSPA.

Per step, the truth (ids and horizontal positions of all ground vehicles) and the UAV's confirmed tracks (ids and
positions) are paired with the Euclidean distance as the cost; a pair farther apart than ``match_radius_m`` can never
match. The pairing and the scores are those of the MOTChallenge's reference, py-motmetrics 1.4 (Heindl et al.), to
the bit (:mod:`autonomy.metrics.clear_mot`, which says why it does not call motmetrics itself):

- MOTA (Bernardin & Stiefelhagen 2008) :math:`= 1 - (\\mathrm{FN} + \\mathrm{FP} + \\mathrm{IDSW}) / \\mathrm{GT}`
  over all steps, GT the number of (step, vehicle) truth instances;
- MOTP: the mean distance of the matched pairs (m; lower is better);
- IDF1 (Ristani et al. 2016) :math:`= 2\\,\\mathrm{IDTP} / (2\\,\\mathrm{IDTP} + \\mathrm{IDFP} + \\mathrm{IDFN})`,
  from the one-to-one assignment of whole track trajectories to whole truth trajectories;
- ID switches: steps at which a vehicle is matched to another track than the one it was last matched to
  (motmetrics keeps a previous pair whenever it is still within the radius, so a switch needs the old pair broken);
- mostly tracked / mostly lost: vehicles matched in at least 80 % / under 20 % of the steps they exist;
- false positives (unmatched tracks) and misses (unmatched vehicles), summed over the steps;

and, from :func:`autonomy.metrics.multi_target.gospa` with cut-off ``c = match_radius_m`` and ``p = 2``, the mean
GOSPA distance over the steps (m).

HOTA (Luiten et al. 2021) is not reported: motmetrics 1.4 does not compute it, and TrackEval, which does, requires the
GUI build of OpenCV on PyPI (it conflicts with the headless build the camera uses).

The steps are stored as they come and scored only when :meth:`ClearMot.summary` is asked (the matcher is fed the
steps added since the previous call), so adding a step costs a few array copies.

What the matcher is fed. A vehicle with no track within the radius at a step can only be a miss there, and a track
with no vehicle within the radius only a false positive: no pairing rule can match them. The matcher is fed, at each
step, only the vehicles and tracks that have a counterpart within the radius (in their order), and the others are
added to the counts they can only be in: misses and truth instances, false positives and track instances, and each
vehicle's steps present (the denominator of its tracked ratio, for mostly tracked / lost). Nothing else changes:
matching and switches only ever involve pairs within the radius (motmetrics' switch window is unbounded), IDTP is the
largest total of steps within the radius over one-to-one trajectory assignments (unmatchable steps add to no pair),
and MOTA = 1 − (FN + FP + IDSW) / GT, IDF1 = 2 IDTP / (GT + predictions), the fraction tracked = matched steps /
steps present are motmetrics' own formulas on the completed counts (tests/autonomy/test_mot_metrics.py compares every
score with motmetrics fed every vehicle and track, on random crowds). Among a city's 1000 vehicles, most are far from
every track of a UAV at every step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from autonomy.metrics.clear_mot import ClearMotMatcher
from autonomy.metrics.multi_target import gospa_of_pairs, pairs_within

__all__ = ["DEFAULT_MATCH_RADIUS_M", "ClearMot", "MotSummary", "check_match_radius"]

DEFAULT_MATCH_RADIUS_M = 20.0
"""Default distance (m) beyond which a track and a vehicle are not a match."""

def check_match_radius(match_radius_m: float) -> float:
    """``match_radius_m`` as a float, or a ValueError unless it is finite and > 0."""
    r = float(match_radius_m)
    if not (math.isfinite(r) and r > 0.0):
        raise ValueError(f"match_radius_m must be finite and > 0 (m), got {match_radius_m!r}")
    return r


@dataclass(frozen=True, kw_only=True)
class MotSummary:
    """The scores of a sequence of steps (module docstring); NaN where undefined (no step, or no truth instance for
    MOTA / no match for MOTP).

    Attributes
    ----------
    steps : int
        Steps scored.
    match_radius_m : float
        Distance beyond which a pair is not a match (m); also the GOSPA cut-off.
    mota, idf1 : float
        Fractions (MOTA may be negative).
    motp_m : float
        Mean distance of the matched pairs (m).
    num_switches, mostly_tracked, mostly_lost, false_positives, misses : int
        Counts over the whole sequence.
    truth_instances : int
        (step, vehicle) pairs: the number of vehicles summed over the steps (MOTA's denominator).
    matches : int
        Matched (vehicle, track) pairs summed over the steps, those at an ID switch included (MOTP's denominator).
    gospa_mean_m : float
        Mean GOSPA distance over the steps (m).
    """

    steps: int
    match_radius_m: float
    mota: float
    motp_m: float
    idf1: float
    num_switches: int
    mostly_tracked: int
    mostly_lost: int
    false_positives: int
    misses: int
    truth_instances: int
    matches: int
    gospa_mean_m: float

    def as_dict(self) -> dict[str, Any]:
        """The fields by name (for ``metrics.json``)."""
        return asdict(self)


class ClearMot:
    """A sequence of steps of one tracker against the truth, scored on demand.

    Parameters
    ----------
    match_radius_m : float
        Distance (m) beyond which a track and a vehicle are not a match, > 0.
    """

    def __init__(self, match_radius_m: float = DEFAULT_MATCH_RADIUS_M) -> None:
        self.match_radius_m = check_match_radius(match_radius_m)
        self._steps: list[tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
        self._matcher = ClearMotMatcher()
        self._fed = 0  # steps fed to the matcher
        self._fed_truth = 0  # truth and track instances fed to it
        self._fed_tracks = 0
        self._gospa: list[float] = []
        self._truth_ids: list[np.ndarray] = []  # per step fed since the last summary: the vehicles present
        self._present = np.zeros(0, dtype=np.int64)  # the vehicles of earlier steps (fed to the matcher or not) ...
        self._steps_present = np.zeros(0, dtype=np.int64)  # ... and the steps each was present
        self._unfed_truth = 0  # truth instances with no track within the radius: misses by construction
        self._unfed_tracks = 0  # track instances with no vehicle within the radius: false positives by construction

    @property
    def steps(self) -> int:
        """Steps added so far."""
        return len(self._steps)

    def add(self, t: float, truth_ids: Sequence[int], truth_xy: np.ndarray, track_ids: Sequence[int],
            track_xy: np.ndarray) -> None:
        """One step at time ``t`` (s, after the previous step's): the vehicles ``truth_ids`` at ``truth_xy`` (M, 2) m
        and the tracks ``track_ids`` at ``track_xy`` (K, 2) m (ids unique within the step; truth and track ids are
        separate name spaces)."""
        t = float(t)
        if self._steps and not t > self._steps[-1][0]:
            raise ValueError(f"step times must increase: {t} after {self._steps[-1][0]}")
        gt_ids, gt_xy = _ids_and_points("truth", truth_ids, truth_xy)
        hyp_ids, hyp_xy = _ids_and_points("track", track_ids, track_xy)
        self._steps.append((t, gt_ids, gt_xy, hyp_ids, hyp_xy))

    def summary(self) -> MotSummary:
        """The scores of every step added so far."""
        r = self.match_radius_m
        if not self._steps:
            nan = float("nan")
            return MotSummary(steps=0, match_radius_m=r, mota=nan, motp_m=nan, idf1=nan, num_switches=0,
                              mostly_tracked=0, mostly_lost=0, false_positives=0, misses=0, truth_instances=0,
                              matches=0, gospa_mean_m=nan)
        for k in range(self._fed, len(self._steps)):
            _, gt_ids, gt_xy, hyp_ids, hyp_xy = self._steps[k]
            i, j, dij = pairs_within(gt_xy, hyp_xy, r)  # a k-d tree: a city's vehicles are mostly far from a track
            self._truth_ids.append(gt_ids)
            rows, i_at = np.unique(i, return_inverse=True)  # only those with a counterpart (module docstring)
            cols, j_at = np.unique(j, return_inverse=True)
            self._unfed_truth += len(gt_ids) - len(rows)
            self._unfed_tracks += len(hyp_ids) - len(cols)
            self._fed_truth += len(rows)
            self._fed_tracks += len(cols)
            self._matcher.update(gt_ids[rows], hyp_ids[cols], i_at, j_at, dij)
            self._gospa.append(gospa_of_pairs(len(gt_ids), len(hyp_ids), i, j, dij, c=r, p=2.0).distance)
        self._fed = len(self._steps)
        m = self._matcher
        objects = self._fed_truth + self._unfed_truth
        misses = m.misses + self._unfed_truth
        false = m.false_positives + self._unfed_tracks
        predictions = self._fed_tracks + self._unfed_tracks
        switches = m.switches
        ids = np.concatenate((self._present, *self._truth_ids))
        counts = np.concatenate((self._steps_present, np.ones(len(ids) - len(self._present), dtype=np.int64)))
        present, at = np.unique(ids, return_inverse=True)  # folded: each summary costs what is new and who was seen
        steps_present = np.bincount(at.reshape(-1), weights=counts, minlength=len(present)).astype(np.int64)
        self._present, self._steps_present, self._truth_ids = present, steps_present, []
        tracked = m.tracked
        ratios = np.array([tracked.get(g, 0) for g in present.tolist()], dtype=float) / steps_present
        return MotSummary(steps=len(self._steps), match_radius_m=r,
                          mota=1.0 - _divide(misses + switches + false, objects),
                          motp_m=_divide(m.distance_sum(), m.detections),
                          idf1=_divide(2 * m.identity_true_positives(), objects + predictions),
                          num_switches=switches, mostly_tracked=int(np.sum(ratios >= 0.8)),
                          mostly_lost=int(np.sum(ratios < 0.2)), false_positives=false, misses=misses,
                          truth_instances=objects, matches=m.detections, gospa_mean_m=float(np.mean(self._gospa)))


def _divide(a: float, b: float) -> float:
    """``a / b`` in float64, NaN for 0 / 0 and ±inf for x / 0 without a warning (motmetrics' ``quiet_divide``)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.true_divide(a, b))


def _ids_and_points(what: str, ids: Sequence[int], xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    ids_a = np.asarray(ids, dtype=np.int64).reshape(-1)
    xy_a = np.asarray(xy, dtype=float)
    if xy_a.size == 0:
        xy_a = np.zeros((0, 2))
    if xy_a.shape != (ids_a.size, 2) or not np.all(np.isfinite(xy_a)):
        raise ValueError(f"{what}_xy must be a finite ({ids_a.size}, 2) array (m), got shape {np.shape(xy)}")
    if np.unique(ids_a).size != ids_a.size:
        raise ValueError(f"{what}_ids must be unique within a step, got {ids_a.tolist()}")
    return ids_a, xy_a.copy()
