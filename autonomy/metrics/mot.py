"""Multi-object tracking scores of one UAV's tracks against every ground vehicle: CLEAR-MOT, IDF1 and GOSPA.

Per step, the truth (ids and horizontal positions of all ground vehicles) and the UAV's confirmed tracks (ids and
positions) go into a :class:`motmetrics.MOTAccumulator` with the Euclidean distance as the cost; a pair farther apart
than ``match_radius_m`` can never match. From it (py-motmetrics, Heindl et al.; the definitions of the MOTChallenge):

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

The steps are stored as they come and scored only when :meth:`ClearMot.summary` is asked (the accumulator is fed the
steps added since the previous call), so adding a step costs a few array copies.

What motmetrics is fed. A vehicle with no track within the radius at a step can only be a miss there, and a track
with no vehicle within the radius only a false positive: no pairing rule can match them. motmetrics is fed, at each
step, only the vehicles and tracks that have a counterpart within the radius (in their order), and the others are
added to the counts they can only be in: misses and truth instances, false positives and track instances, and each
vehicle's steps present (the denominator of its tracked ratio, for mostly tracked / lost). Nothing else changes:
matching and switches only ever involve pairs within the radius (motmetrics' switch window is unbounded), IDTP is the
largest total of co-matched steps over one-to-one trajectory assignments (unmatchable steps add to no pair), and
MOTA = 1 − (FN + FP + IDSW) / GT, IDF1 = 2 IDTP / (GT + predictions), the fraction tracked = matched steps / steps
present are motmetrics' own formulas on the completed counts (tests/autonomy/test_mot_metrics.py compares every
score with motmetrics fed every vehicle and track, on random crowds). Among a city's 1000 vehicles, most are far from
every track of a UAV at every step; feeding them cost most of a run's scoring time. motmetrics (and pandas, about half
a second) are imported when the first scorer is made, not with this module: a run makes its scorers while it is set
up, so the import is not paid inside its loop.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from autonomy.metrics.multi_target import gospa_of_pairs, pairs_within

__all__ = ["DEFAULT_MATCH_RADIUS_M", "ClearMot", "MotSummary", "check_match_radius"]

DEFAULT_MATCH_RADIUS_M = 20.0
"""Default distance (m) beyond which a track and a vehicle are not a match."""

_METRICS = ("motp", "idtp", "num_switches", "num_false_positives", "num_misses", "num_objects", "num_predictions",
            "num_detections", "tracked")
"""What motmetrics computes of the fed part; ``tracked`` (steps matched per vehicle) is registered by
:func:`_metrics_host`."""


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
        self._acc: Any = None  # motmetrics.MOTAccumulator, built at the first summary
        self._fed = 0
        self._gospa: list[float] = []
        self._present: dict[int, int] = {}  # vehicle id -> steps present (fed to motmetrics or not)
        self._unfed_truth = 0  # truth instances with no track within the radius: misses by construction
        self._unfed_tracks = 0  # track instances with no vehicle within the radius: false positives by construction
        _motmetrics()

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
        mm = _motmetrics()
        if self._acc is None:
            self._acc = mm.MOTAccumulator(auto_id=False)
        for k in range(self._fed, len(self._steps)):
            _, gt_ids, gt_xy, hyp_ids, hyp_xy = self._steps[k]
            i, j, dij = pairs_within(gt_xy, hyp_xy, r)  # a k-d tree: a city's vehicles are mostly far from a track
            for g in gt_ids.tolist():
                self._present[g] = self._present.get(g, 0) + 1
            rows, i_at = np.unique(i, return_inverse=True)  # only those with a counterpart (module docstring)
            cols, j_at = np.unique(j, return_inverse=True)
            self._unfed_truth += len(gt_ids) - len(rows)
            self._unfed_tracks += len(hyp_ids) - len(cols)
            d = np.full((len(rows), len(cols)), np.nan)  # motmetrics: NaN is "cannot match"
            d[i_at, j_at] = dij
            self._acc.update(gt_ids[rows].tolist(), hyp_ids[cols].tolist(), d, frameid=k)
            self._gospa.append(gospa_of_pairs(len(gt_ids), len(hyp_ids), i, j, dij, c=r, p=2.0).distance)
        self._fed = len(self._steps)
        s = _metrics_host().compute(self._acc, metrics=list(_METRICS), return_dataframe=False)
        divide = mm.math_util.quiet_divide
        objects = int(s["num_objects"]) + self._unfed_truth
        misses = int(s["num_misses"]) + self._unfed_truth
        false = int(s["num_false_positives"]) + self._unfed_tracks
        predictions = int(s["num_predictions"]) + self._unfed_tracks
        switches = int(s["num_switches"])
        tracked = s["tracked"]
        ratios = [divide(float(tracked.get(g, 0)), float(n)) for g, n in self._present.items()]
        return MotSummary(steps=len(self._steps), match_radius_m=r,
                          mota=float(1.0 - divide(misses + switches + false, objects)), motp_m=float(s["motp"]),
                          idf1=float(divide(2 * int(s["idtp"]), objects + predictions)), num_switches=switches,
                          mostly_tracked=sum(q >= 0.8 for q in ratios), mostly_lost=sum(q < 0.2 for q in ratios),
                          false_positives=false, misses=misses, truth_instances=objects,
                          matches=int(s["num_detections"]), gospa_mean_m=float(np.mean(self._gospa)))


def _motmetrics() -> Any:
    """The motmetrics module (imported at the first call)."""
    import motmetrics

    return motmetrics


@functools.cache
def _metrics_host() -> Any:
    """motmetrics' host of the standard metrics, made once (registering them costs ≈ 10 ms), with ``tracked``:
    the steps each vehicle is matched at (its MATCH and SWITCH events), the numerator of motmetrics' own
    ``track_ratios``, whose denominator here counts the steps it was not fed too."""
    host = _motmetrics().metrics.create()
    host.register(_tracked, formatter="{}".format, name="tracked")
    return host


def _tracked(df: Any) -> dict[int, int]:
    """Steps matched per vehicle id: motmetrics' ``track_ratios`` numerator (events other than MISS with a vehicle)."""
    noraw = df.noraw
    return {int(k): int(v) for k, v in noraw[noraw.Type != "MISS"]["OId"].value_counts().items()}


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
