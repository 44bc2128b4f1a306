"""The composed tracker's multi-target form: every car a track, and a belief of which track is the designated target.

Per scan (the detections of one sensor taken at one time; filters predict to the scan's time stamp):

1. tracks that went ``lost_after_s`` without an update are dropped (coasting through an occlusion until then);
2. the associator assigns the scan's detections to the tracks not newer than the scan: global nearest neighbour
   (``scipy.optimize.linear_sum_assignment`` on the χ²-gated cost matrix, spatially pre-gated) or JPDA (marginal
   association probabilities; every track takes the PDA update);
3. assigned tracks update their filters, and their class readings update the target-identity belief
   (:mod:`.identity`); tentative tracks count the scan towards their M-of-N confirmation (a position-fixing scan is
   a trial; a hit is an update from it): confirmed at ``M`` hits within their first ``N`` scans, dropped once ``M``
   can no longer be reached;
4. the position fixes that no track took start tentative tracks in pairs with earlier ones (:mod:`.pairing`);
5. two confirmed tracks on one car (closer than ``merge_distance_m`` and ``merge_speed_mps``) become one: the older
   stays, with the other's identity weight; two tracks that one of their last scans updated with different
   detections are two cars (two cars stopped side by side at a junction) and stay apart;
6. a camera frame (with ``camera_detection_probability`` > 0, even one that detected nothing) lowers the ``unseen``
   score of each confirmed track it had in view and did not update, and drops a track the cameras keep missing
   (:meth:`MultiTargetTracker.observe_coverage`, :mod:`.unseen`).

:meth:`MultiTargetTracker.step` returns the estimate of the track believed to be the target, or, while no track is,
where the target is believed to be (the cue, or the lost target track's estimate grown with time) so guidance searches
there; None without either.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from scipy.spatial import cKDTree

from autonomy.estimation.base import TIME_TOLERANCE, Filter
from autonomy.estimation.measurements import MeasurementLike
from autonomy.estimation.models import MotionModel
from autonomy.estimation.scif import SqrtInformation, add_information
from interfaces.state import TargetEstimate, TrackReport

from .batch_update import update_pairs
from .class_affinity import ClassAffinity
from .class_readings import Readings, absorb, taken_readings, weighted_readings
from .fixes import PositionFixer
from .gate import ChiSquareGate, PredictedNis
from .identity import CHI2_2_99, IdentityConfig, TargetIdentity
from .information import TrackInformation
from .initiator import FilterFactory
from .pairing import PairingInitiator
from .track import Track
from .unseen import CAMERA_RESOLUTION_M, UNSEEN_DROP_LOG, visible_share

if TYPE_CHECKING:
    from autonomy.estimation.tracker import TrackerConfig
    from autonomy.sensing.coverage import FrameCoverage

__all__ = ["UNRESOLVED_RADIUS_M", "MultiTargetTracker", "MultiTrackerConfig"]

UNRESOLVED_RADIUS_M = 100.0
"""Two tracks farther apart than this (m) are never taken for unresolved (a bound before the χ² test)."""


@dataclass(frozen=True, kw_only=True)
class MultiTrackerConfig:
    """Multi-target settings (the single-target ones, filter, gate, loss, come from a ``TrackerConfig``).

    Attributes
    ----------
    associator : {"gnn", "jpda"}
        Global nearest neighbour or joint probabilistic data association.
    confirm_m, confirm_n : int
        M-of-N confirmation: a tentative track is confirmed at ``confirm_m`` hits within its first ``confirm_n``
        position-fixing scans (the two that started it included), 2 <= M <= N.
    detection_probability : float
        JPDA: probability that a target in view is detected, in (0, 1].
    clutter_density : float
        JPDA: false alarms per unit of measurement space (e.g. per m·rad for a range-azimuth radar), > 0.
    merge_distance_m, merge_speed_mps : float
        Two confirmed tracks closer than this in position (m) and velocity (m/s) are one car, > 0 (unless a recent
        scan updated both with different detections).
    max_tracks : int
        Most live tracks (>= 1); no new track starts beyond it (counted in ``starts_refused``).
    class_aided : bool
        Whether detections' class readings weigh in their association (:mod:`.class_affinity`).
    camera_detection_probability : float
        Probability in [0, 1) that a camera detects a car it has in view (:meth:`MultiTargetTracker.observe_coverage`);
        0 turns the cameras' negative information off.
    """

    associator: Literal["gnn", "jpda"] = "gnn"
    confirm_m: int = 3
    confirm_n: int = 4
    detection_probability: float = 0.9
    clutter_density: float = 1e-6
    merge_distance_m: float = 4.0
    merge_speed_mps: float = 2.0
    max_tracks: int = 500
    class_aided: bool = True
    camera_detection_probability: float = 0.0

    def __post_init__(self) -> None:
        if self.associator not in ("gnn", "jpda"):
            raise ValueError(f"MultiTrackerConfig.associator must be gnn|jpda, got {self.associator!r}")
        for name in ("confirm_m", "confirm_n", "max_tracks"):
            if int(getattr(self, name)) != getattr(self, name):
                raise ValueError(f"MultiTrackerConfig.{name} must be an integer, got {getattr(self, name)!r}")
        if not 2 <= self.confirm_m <= self.confirm_n:
            raise ValueError(f"MultiTrackerConfig needs 2 <= confirm_m <= confirm_n, got {self.confirm_m} of "
                             f"{self.confirm_n}")
        if not 0 < self.detection_probability <= 1:
            raise ValueError(f"MultiTrackerConfig.detection_probability must be in (0, 1], got "
                             f"{self.detection_probability!r}")
        for name in ("clutter_density", "merge_distance_m", "merge_speed_mps"):
            if not getattr(self, name) > 0:
                raise ValueError(f"MultiTrackerConfig.{name} must be > 0, got {getattr(self, name)!r}")
        if not 0 <= self.camera_detection_probability < 1:
            raise ValueError(f"MultiTrackerConfig.camera_detection_probability must be in [0, 1), got "
                             f"{self.camera_detection_probability!r}")
        if self.max_tracks < 1:
            raise ValueError(f"MultiTrackerConfig.max_tracks must be >= 1, got {self.max_tracks!r}")


class MultiTargetTracker:
    """Tracks every car in view and keeps which track is the designated target (module docstring).

    Parameters
    ----------
    config : TrackerConfig
        Filter, motion model, gate, initiation and loss settings (:mod:`autonomy.estimation.tracker`).
    multi : MultiTrackerConfig
        Association, confirmation and merging.
    identity : IdentityConfig
        The target's classes, the background population and the identity thresholds.
    model : MotionModel, optional
        The motion model (default: that of ``config``).
    filters : FilterFactory, optional
        A new track's filter (default: ``config.filter`` on ``model``).
    gating_filter : callable, optional
        The filter gated against, given a track's filter (default: that filter).
    """

    def __init__(self, config: TrackerConfig, multi: MultiTrackerConfig, identity: IdentityConfig, *,
                 model: MotionModel | None = None, filters: FilterFactory | None = None,
                 gating_filter: Callable[[Filter], Filter] | None = None) -> None:
        from autonomy.estimation.tracker import ConfiguredFilters, make_motion_model  # it imports this package

        self.config = config
        self.multi = multi
        model = model if model is not None else make_motion_model(config)
        self.model = model
        self.layout = tuple(model.layout)
        filters = filters if filters is not None else ConfiguredFilters(config, model)
        self.fixer = PositionFixer(config.target_height, None)
        self.initiator = PairingInitiator(filters=filters, layout=self.layout,
                                          max_target_speed=config.max_target_speed,
                                          tentative_window_s=config.tentative_window_s,
                                          initial_speed_sigma=config.initial_speed_sigma)
        self.gate = ChiSquareGate(config.gate_probability)
        self.identity = TargetIdentity(identity)
        affinity = ClassAffinity(identity.background, identity.swap_probability) if multi.class_aided else None
        self.associator = _associator(multi, self.gate, model, config.target_height, gating_filter, affinity)
        self.tracks: list[Track] = []
        self._ix = [self.layout.index("x"), self.layout.index("y")]
        self._iv = [self.layout.index("vx"), self.layout.index("vy")]
        self._ix_at, self._iv_at = np.array(self._ix), np.array(self._iv)
        pv, n = self._ix + self._iv, len(self.layout)
        self._ipv = np.array([[r * n + c for c in pv] for r in pv])  # (x, y, vx, vy) block of a covariance, flat
        self._next_id = 1
        self._target: int | None = None
        self.updates = 0
        self.initiations = 0
        self.confirmations = 0
        self.dropped_tentative = 0
        self.dropped_lost = 0
        self.dropped_unseen = 0
        self.merges = 0
        self.gated_out = 0
        self.starts_refused = 0
        self.used_by_sensor: dict[str, int] = {}
        self._step_detections: dict[int, list] = {}
        self._last_t = 0.0
        self.team_target: int | None = None  # set by a consensus team before a step: the track it takes for the target
        # the last track_reports() and the tracks (ids, filter times) they were made of; None after any change
        self._reports: tuple[tuple, list[TrackReport]] | None = None
        self._defer: tuple[int, float] | None = None  # (target track id, step time) of a consensus step
        self._deferred: list[MeasurementLike] = []
        self._coverage: dict[tuple[float, object], FrameCoverage] = {}  # camera frames not yet processed

    # -- the estimator interface ---------------------------------------------------------------------------------
    def cue(self, t: float, p_W: np.ndarray, sigma_m: float) -> None:
        """The hand-off: the target is near ``p_W`` (m) at ``t`` (s), ``sigma_m`` (m) per axis."""
        self._reports = None
        self.identity.cue(t, p_W, sigma_m)

    def observe_coverage(self, coverages: Sequence[FrameCoverage]) -> None:
        """Camera frames' coverage (:mod:`autonomy.sensing.coverage`), processed at the next :meth:`step` with the
        frames' detections (an empty frame is a scan too): each confirmed track the frame did not update (and with
        no other track within :data:`.unseen.CAMERA_RESOLUTION_M`, whose blob it may have shared) loses
        ``log(1 − p_D v)`` of its ``unseen`` score, ``v`` the share of its position distribution the camera had in
        view and ``p_D`` = ``camera_detection_probability``; a camera detection's update restores it to 0, and a
        track whose score falls below ``log(.unseen.UNSEEN_DROP)`` is dropped: the camera kept looking where it said
        a car was, and saw none. Ignored while ``camera_detection_probability`` is 0."""
        if self.multi.camera_detection_probability <= 0:
            return
        for cov in coverages:
            self._coverage[(float(cov.t_meas), cov.sensor_id)] = cov

    def step(self, t: float, detections: Sequence[MeasurementLike]) -> TargetEstimate | None:
        """Absorb ``detections`` (sorted by ``t_meas``) and return the target's estimate at ``t`` (s): its track's,
        or the search centre's while no track is the target (module docstring)."""
        self._reports = None
        self._step_detections = {}
        for t_meas, scan, coverage in self._scans(detections, t):
            self._drop_lost(t_meas)
            if scan:
                self._process_scan(t_meas, scan)
            if coverage is not None:
                self._unseen(t_meas, scan, coverage)
        self._drop_lost(t)
        self._target = self.identity.target()
        if self.team_target is not None and self._track(self.team_target) is not None:
            self._target = self.team_target  # the team's choice (a consensus team pools its members' beliefs)
        self.team_target = None
        self._last_t = float(t)
        track = self._track(self._target)
        if track is not None:
            if t > track.filter.t:
                track.filter.predict(t)
            return self._estimate(track)
        return self._search_estimate(t)

    def _search_estimate(self, t: float) -> TargetEstimate | None:
        """Where the target is believed to be at ``t`` (s) while no track is it (the cue or the lost track's last
        estimate, grown with time), as an estimate guidance can fly to; None without either."""
        search = self.identity.search_estimate(t)
        if search is None:
            return None
        mean, S = search
        P = np.zeros((4, 4))
        P[:2, :2] = S
        P[2:, 2:] = np.eye(2) * self.identity.config.search_speed ** 2
        return TargetEstimate(t=float(t), p_W=mean, v_W=np.zeros(2), P=P)

    def step_information(self, t: float, detections: Sequence[MeasurementLike]) -> TrackInformation | None:
        """:meth:`step` for a consensus team (HCMCI): every track is updated as usual except the target's, whose
        detections taken at ``t`` (s) are not applied; their information contribution is returned beside the
        target track's prior at ``t`` (:mod:`.information`). If the belief moves to another track during the step,
        the deferred detections update the track they were taken for, and the new target track's information has no
        contribution. Needs information filters (``scif``). None while no track is the target."""
        if self.config.filter != "scif":
            raise TypeError(f"step_information needs the information filter (scif), not {self.config.filter!r}")
        self._defer, self._deferred = (self._target, float(t)) if self._target is not None else None, []
        try:
            self.step(t, detections)
        finally:
            deferred_for = self._defer[0] if self._defer is not None else None
            self._defer = None
            self._reports = None  # the deferred detections and the prediction below change the tracks again
        track = self._track(self._target)
        old = self._track(deferred_for)
        if self._deferred and (track is None or track is not old):
            for det in self._deferred:  # the belief moved: the detections update the track they were taken for
                if old is not None:
                    old.filter.update(det)
            self._deferred = []
        if track is None:
            return None
        parts = [track.filter.information(d)[0] for d in self._deferred]
        self._deferred = []
        if t > track.filter.t:
            track.filter.predict(t)
        total = None if not parts else parts[0] if len(parts) == 1 else add_information(*parts)
        return TrackInformation(t=float(t), prior=track.filter.information_state, contribution=total)

    def set_information(self, info: SqrtInformation) -> None:
        """Replace the target track's estimate by ``info`` (the consensus posterior of the last
        :meth:`step_information`)."""
        track = self._track(self._target)
        if track is None:
            raise ValueError("set_information needs a target track")
        self._reports = None
        track.filter.set_information(info)

    def current_estimate(self) -> TargetEstimate | None:
        """The target track's estimate at its filter's time (after :meth:`set_information`), or, without a target
        track, the search centre's at the last step's time (None without either)."""
        track = self._track(self._target)
        return self._estimate(track) if track is not None else self._search_estimate(self._last_t)

    @property
    def target_track_id(self) -> int | None:
        """Id of the track taken for the target after the last step, or None."""
        return self._target

    @property
    def filter(self) -> Filter | None:
        """The target track's filter, or None."""
        track = self._track(self._target)
        return None if track is None else track.filter

    def detections_of(self, track_id: int) -> list[MeasurementLike]:
        """The detections that updated track ``track_id`` during the last step, in time order (under JPDA, each
        scan's most probable one)."""
        return list(self._step_detections.get(track_id, ()))

    def track_reports(self) -> list[TrackReport]:
        """Every live track at its filter's time, with its target probability and own class evidence.

        Made once per change of the tracker (a step, a consensus posterior, a cue) and handed out again until the
        next: fusion, the team's picture, the record and the metrics each read them after every step, and a road
        filter's mixture estimate costs tens of microseconds per track.
        """
        key = tuple((tr.track_id, tr.filter.t) for tr in self.tracks)
        if self._reports is None or self._reports[0] != key:
            self._reports = (key, [TrackReport(
                track_id=tr.track_id, estimate=est,
                target_probability=min(1.0, max(0.0, self.identity.probability(tr.track_id))),
                evidence=tr.evidence, confirmed=tr.confirmed)
                for tr, est in zip(self.tracks, self._estimates(self.tracks), strict=True)])
        return list(self._reports[1])

    # -- a scan --------------------------------------------------------------------------------------------------
    def _scans(self, detections: Sequence[MeasurementLike], t: float) -> list[tuple[float, list, object]]:
        """The scans in time order (then sensor id): (time, detections, the frame's coverage or None), with the
        camera frames observed by ``t`` (s) that brought no detection."""
        scans: dict[tuple[float, object], list] = {}
        for d in detections:
            scans.setdefault((d.t_meas, d.sensor_id), []).append(d)
        coverage = {}
        if self._coverage:
            for key in [k for k in self._coverage if k[0] <= t + TIME_TOLERANCE]:
                coverage[key] = self._coverage.pop(key)
                scans.setdefault(key, [])
        return [(key[0], dets, coverage.get(key))
                for key, dets in sorted(scans.items(), key=lambda kv: (kv[0][0], str(kv[0][1])))]

    def _process_scan(self, t_meas: float, scan: Sequence[MeasurementLike]) -> None:
        live = [tr for tr in self.tracks if tr.filter.t <= t_meas]
        fixing = self.fixer.fixes_position(scan)
        result = self.associator.assign(live, scan)
        self.gated_out += len(result.gated_out)
        hit: set[int] = set()
        if result.weights is None:
            pairs = [(live[i], result.detections[j]) for i, j in result.pairs]
            applied = pairs
            if self._defer is not None and abs(t_meas - self._defer[1]) <= TIME_TOLERANCE:
                self._deferred.extend(d for tr, d in pairs if tr.track_id == self._defer[0])
                applied = [(tr, d) for tr, d in pairs if tr.track_id != self._defer[0]]
            update_pairs([(tr.filter, det) for tr, det in applied], self.layout, self.config.target_height)
            self._read_taken(pairs)
            for track, det in pairs:
                self._updated(track, det, t_meas)
                hit.add(id(track))
            if pairs:
                sid = pairs[0][1].sensor_id  # one scan: one sensor
                self.updates += len(pairs)
                self.used_by_sensor[sid] = self.used_by_sensor.get(sid, 0) + len(pairs)
        else:
            from .jpda import pda_update

            W = np.asarray(result.weights)
            for i, track in enumerate(live):
                if W[i, 1:].sum() <= 1e-12:
                    continue
                pda_update(track.filter, result.detections, W[i])
                self._read_classes(track, [(float(W[i, 1 + j]), d) for j, d in enumerate(result.detections)],
                                   none_weight=float(W[i, 0]))
                j = int(np.argmax(W[i, 1:]))
                self._updated(track, result.detections[j], t_meas)
                self.updates += 1
                sid = result.detections[j].sensor_id
                self.used_by_sensor[sid] = self.used_by_sensor.get(sid, 0) + 1
                if W[i, 0] < 0.5:
                    hit.add(id(track))
        if fixing:
            unused = [result.detections[j] for j in result.unused]
            fixes = self.fixer.fixes(unused)
            self._searched(t_meas, live, result, fixes)
            self._confirmations(live, hit, t_meas)
            self._initiate(fixes)
        self._merge()

    def _unseen(self, t_meas: float, scan: Sequence[MeasurementLike], coverage: FrameCoverage) -> None:
        """A camera frame at ``t_meas`` (s) with detections ``scan``: the confirmed tracks it updated are seen; every
        other one with no other track within :data:`.unseen.CAMERA_RESOLUTION_M` that it had in view loses
        ``log(1 − p_D v)`` (:meth:`observe_coverage`), ``v`` its visible share (:func:`.unseen.visible_share`) of
        its position distribution moved on with its velocity to ``t_meas``."""
        taken = {id(d) for d in scan}
        seen = {tr.track_id for tr in self.tracks
                if any(id(d) in taken for d in self._step_detections.get(tr.track_id, ()))}
        rest = []
        for tr in self.tracks:
            if tr.track_id in seen:
                tr.unseen = 0.0
            elif tr.confirmed and tr.filter.t <= t_meas + TIME_TOLERANCE:
                rest.append(tr)
        if not rest:
            return
        at = {id(tr): tr.filter.x[self._ix] + (t_meas - tr.filter.t) * tr.filter.x[self._iv] for tr in self.tracks}
        mean = np.array([at[id(tr)] for tr in rest])
        near = cKDTree(np.array(list(at.values()))).query_ball_point(mean, CAMERA_RESOLUTION_M)
        alone = np.array([len(n) == 1 for n in near])  # the track itself only
        if not alone.any():
            return
        rest = [tr for tr, a in zip(rest, alone.tolist(), strict=True) if a]
        ix = np.ix_(self._ix, self._ix)
        share = visible_share(mean[alone], np.array([tr.filter.P[ix] for tr in rest]), coverage,
                              self.config.target_height)
        pd = self.multi.camera_detection_probability
        for tr, v in zip(rest, share.tolist(), strict=True):
            if v <= 0.0:
                continue
            tr.unseen += math.log1p(-pd * min(v, 1.0))
            if tr.unseen < UNSEEN_DROP_LOG:
                self.tracks.remove(tr)
                self.dropped_unseen += 1
                self.identity.deleted(tr.track_id, *self._where(tr))

    def _unresolved(self, live: Sequence[Track]) -> list[tuple[int, int]]:
        """Pairs of ids of confirmed tracks the identity belief holds whose estimates' difference lies inside the
        99 % χ² gate of their summed position covariances (within ``UNRESOLVED_RADIUS_M`` first)."""
        holds = self.identity.holds
        held = [tr for tr in live if tr.confirmed and holds(tr.track_id)]
        if len(held) < 2:
            return []
        p = self._xy(held)
        pairs = cKDTree(p).query_pairs(UNRESOLVED_RADIUS_M, output_type="ndarray")
        if not len(pairs):
            return []
        a, b = pairs[:, 0], pairs[:, 1]
        both = np.unique(pairs)  # the covariances of the tracks in a pair only
        P = np.zeros((len(held), 2, 2))
        ix = np.ix_(self._ix, self._ix)
        P[both] = [held[k].filter.P[ix] for k in both.tolist()]
        d, S = p[a] - p[b], P[a] + P[b]
        det = S[:, 0, 0] * S[:, 1, 1] - S[:, 0, 1] * S[:, 1, 0]
        maha = (S[:, 1, 1] * d[:, 0] ** 2 - (S[:, 0, 1] + S[:, 1, 0]) * d[:, 0] * d[:, 1]
                + S[:, 0, 0] * d[:, 1] ** 2) / det  # dᵀ S⁻¹ d of each pair (2×2 inverse in closed form)
        return [(held[i].track_id, held[j].track_id) for i, j in pairs[maha <= CHI2_2_99].tolist()]

    def _searched(self, t_meas: float, live: Sequence[Track], result: object, fixes: Sequence) -> None:
        """What a position-fixing scan tells the identity belief: the pairs of tracks it could not tell apart (with a
        swap probability), and the ground fixes of the detections no confirmed track took (unassigned ones, and those
        tentative tracks took; with a search detection probability). Neither is computed when its setting is 0."""
        cfg = self.identity.config
        if not self.identity.held or (cfg.swap_probability <= 0 and cfg.search_detection_probability <= 0):
            return
        points = []
        if cfg.search_detection_probability > 0:
            points = [xy for _, xy, _ in fixes]
            if result.weights is None:
                tentative = [result.detections[j] for i, j in result.pairs if not live[i].confirmed]
                points += [xy for _, xy, _ in self.fixer.fixes(tentative)]
        unresolved = self._unresolved(live) if cfg.swap_probability > 0 else []
        self.identity.scanned(t_meas, points, unresolved)

    def _updated(self, track: Track, det: MeasurementLike, t_meas: float) -> None:
        track.last_update_t = t_meas
        track.missed = 0
        track.took(det.sensor_id, t_meas, det)
        got = self._step_detections.get(track.track_id)
        if got is None:
            self._step_detections[track.track_id] = [det]
        else:
            got.append(det)

    def _read_classes(self, track: Track, weighted: Sequence[tuple[float, MeasurementLike]],
                      none_weight: float = 0.0) -> None:
        """Class readings of the detections that updated ``track`` (weights: association probabilities;
        :func:`.class_readings.weighted_readings`) into its per-class log-likelihoods, and its evidence into the
        identity belief (:mod:`.identity`)."""
        readings = weighted_readings(track, weighted, none_weight)
        if readings:
            self._absorb(readings, [track])

    def _read_taken(self, pairs: Sequence[tuple[Track, MeasurementLike]]) -> None:
        """:meth:`_read_classes` of each track with the one detection it took whole (a GNN scan; each track once),
        all of the scan's tracks absorbed together (:func:`.class_readings.taken_readings`)."""
        taken = taken_readings(pairs)
        if taken is None:
            for track, det in pairs:
                if getattr(det, "classes", ()):
                    self._read_classes(track, [(1.0, det)])
        elif taken[1]:
            self._absorb(*taken)

    def _absorb(self, by_attr: Readings, tracks: Sequence[Track]) -> None:
        """The readings ``by_attr`` into the tracks' log-likelihoods and the evidence of ``tracks``
        (:func:`.class_readings.absorb`), which the identity belief reads for the confirmed ones in their order."""
        absorb(by_attr, tracks, self.identity.config)
        held = [tr for tr in tracks if tr.confirmed]
        self.identity.read_many([tr.track_id for tr in held], [tr.evidence for tr in held],
                                where=lambda k: self._where(held[k]))

    def _confirmations(self, live: Sequence[Track], hit: set[int], t_meas: float) -> None:
        m, n = self.multi.confirm_m, self.multi.confirm_n
        for track in live:
            if track.confirmed:
                continue
            track.scans += 1
            track.hits += id(track) in hit
            if track.hits >= m:
                track.confirmed = True
                self.confirmations += 1
                est = self._estimate(track)
                self.identity.confirmed(track.track_id, t_meas, est.p_W, est.P[:2, :2], track.evidence)
            elif track.hits + (n - track.scans) < m:
                self.tracks.remove(track)
                self.dropped_tentative += 1

    def _initiate(self, fixes) -> None:
        for track in self.initiator.initiate(fixes):
            if len(self.tracks) >= self.multi.max_tracks:
                self.starts_refused += 1
                continue
            track.track_id = self._next_id
            self._next_id += 1
            self.tracks.append(track)
            self.initiations += 1
            if track.hits >= self.multi.confirm_m:  # M = 2: the starting pair confirms it
                track.confirmed = True
                self.confirmations += 1
                est = self._estimate(track)
                self.identity.confirmed(track.track_id, track.filter.t, est.p_W, est.P[:2, :2], track.evidence)

    def _drop_lost(self, t: float) -> None:
        lost_after = self.config.lost_after_s
        for track in [tr for tr in self.tracks if t - tr.last_update_t > lost_after]:
            self.tracks.remove(track)
            self.dropped_lost += 1
            if track.confirmed:
                self.identity.deleted(track.track_id, *self._where(track))

    def _where(self, track: Track) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        est = self._estimate(track)
        return est.t, est.p_W, est.v_W, est.P[:2, :2]

    def _merge(self) -> None:
        confirmed = [tr for tr in self.tracks if tr.confirmed]
        if len(confirmed) < 2:
            return
        p = self._xy(confirmed)
        close = cKDTree(p).query_pairs(self.multi.merge_distance_m, output_type="ndarray")
        if not len(close):
            return
        gone: set[int] = set()
        for a, b in sorted(map(tuple, close.tolist())):
            ta, tb = confirmed[a], confirmed[b]
            if id(ta) in gone or id(tb) in gone:
                continue
            dv = ta.filter.x[self._iv] - tb.filter.x[self._iv]
            if float(np.hypot(dv[0], dv[1])) >= self.multi.merge_speed_mps or ta.seen_apart_from(tb):
                continue
            keep, drop = (ta, tb) if ta.track_id < tb.track_id else (tb, ta)
            self.identity.merged(keep.track_id, drop.track_id)
            keep.evidence = max(keep.evidence, drop.evidence)
            gone.add(id(drop))
            self.merges += 1
        if gone:
            self.tracks = [tr for tr in self.tracks if id(tr) not in gone]

    # -- helpers -------------------------------------------------------------------------------------------------
    def _track(self, track_id: int | None) -> Track | None:
        if track_id is None:
            return None
        for tr in self.tracks:
            if tr.track_id == track_id:
                return tr
        return None

    def _estimate(self, track: Track) -> TargetEstimate:
        return self._estimates([track])[0]

    def _xy(self, tracks: Sequence[Track]) -> np.ndarray:
        """(N, 2) horizontal positions of the tracks' filters."""
        n = len(self.layout)
        xs = [tr.filter.x for tr in tracks]
        if all(x.shape == (n,) for x in xs):
            return np.array(xs, dtype=float)[:, self._ix_at]
        return np.array([x[self._ix] for x in xs])

    def _estimates(self, tracks: Sequence[Track]) -> list[TargetEstimate]:
        """Every track's estimate at its filter's time: position, velocity and their covariance taken from the
        filter's state, gathered into arrays at once when the filters' states are alike, as they are in one tracker
        (the same numbers either way: the same entries copied)."""
        filters = [tr.filter for tr in tracks]
        xs, Ps, ts = [f.x for f in filters], [f.P for f in filters], [f.t for f in filters]  # each read once
        n = len(self.layout)
        if len(tracks) < 2 or any(x.shape != (n,) for x in xs) or any(P.shape != (n, n) for P in Ps):
            return [TargetEstimate.of_arrays(t, x.take(self._ix_at), x.take(self._iv_at), P.take(self._ipv))
                    for t, x, P in zip(ts, xs, Ps, strict=True)]
        X = np.array(xs, dtype=float)
        P = np.array(Ps, dtype=float).reshape(len(tracks), n * n)
        return TargetEstimate.rows_of(ts, X[:, self._ix_at], X[:, self._iv_at], P[:, self._ipv])


def _associator(multi: MultiTrackerConfig, gate: ChiSquareGate, model: MotionModel, target_height: float,
                gating_filter: Callable[[Filter], Filter] | None, affinity: ClassAffinity | None = None) -> object:
    """The configured associator of a scan's detections to many tracks."""
    from .assignment import GlobalNearestNeighbourAssociator
    from .jpda import JointProbabilisticAssociator

    distance = PredictedNis(model, target_height, gating_filter)
    if multi.associator == "gnn":
        return GlobalNearestNeighbourAssociator(gate, distance, affinity=affinity)
    return JointProbabilisticAssociator(gate, distance, detection_probability=multi.detection_probability,
                                        clutter_density=multi.clutter_density, affinity=affinity)

