"""The composed tracker: an initiator, an associator (with its gate), deleters and the tracks' filters, injected.

Detections arrive in ``t_meas`` order and are grouped into scans (one time and one sensor, or one time and all sensors
with ``stack_scans``); every filter predicts to each scan's own time stamp. Per scan:

1. the coasting deleter drops a track with no update for too long;
2. without a track, the initiator sees the scan (its tracks join the list) and the scan ends;
3. a scan older than the track is skipped (no out-of-sequence processing);
4. the associator picks the track's detections (at most one per sensor); several update the filter once as a
   :class:`~autonomy.estimation.measurements.StackedMeasurement` (paper 003's centralised augmented measurement);
5. a scan that fixes a position but misses the track counts towards the divergence deleter, which drops the track
   and hands the same scan to a reset initiator. Bearing-only scans neither count nor reset the count: a bearing
   fits a wrong track anywhere along its line.

The tracker holds a list of tracks; this policy keeps at most one (the target's). With
:meth:`Tracker.step_information` the updates of the scans taken at the step time are collected as information
instead (:mod:`.information`, consensus teams).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from autonomy.estimation.base import Filter
from autonomy.estimation.measurements import MeasurementLike, StackedMeasurement
from autonomy.estimation.scif import SqrtInformation
from interfaces.state import TargetEstimate

from .associator import NearestNeighbourAssociator
from .deleter import MissedScansDeleter, UpdateTimeDeleter
from .fixes import PositionFixer
from .information import InformationDeferral, TrackInformation
from .initiator import FixConfirmingInitiator
from .track import Track

__all__ = ["Tracker"]


class Tracker:
    """Tracks a ground target with injected parts (module docstring).

    Parameters
    ----------
    layout : tuple[str, ...]
        State layout of the tracks' filters (holds ``x, y, vx, vy``).
    initiator : FixConfirmingInitiator
        Starts tracks (and owns the filter factory).
    associator : NearestNeighbourAssociator
        Picks each track's detections of a scan (and owns the gate).
    coasting : UpdateTimeDeleter
        Drops tracks that went too long without an update.
    divergence : MissedScansDeleter
        Drops tracks that rejected too many position fixes in a row.
    fixer : PositionFixer
        Tells which scans fix a position (the divergence count).
    stack_scans : bool
        One scan per time for all sensors (else one per time and sensor).

    Attributes
    ----------
    tracks : list[Track]
        The live tracks.
    updates, initiations, gated_out, dropped_diverged : int
        Scans that updated a track, tracks started, detections outside every gate, tracks dropped as diverged.
    used_by_sensor : dict[str, int]
        Detections that updated a track, per sensor id.
    """

    def __init__(self, *, layout: tuple[str, ...], initiator: FixConfirmingInitiator,
                 associator: NearestNeighbourAssociator, coasting: UpdateTimeDeleter, divergence: MissedScansDeleter,
                 fixer: PositionFixer, stack_scans: bool) -> None:
        self.layout = tuple(layout)
        self.initiator = initiator
        self.associator = associator
        self.coasting = coasting
        self.divergence = divergence
        self.fixer = fixer
        self.stack_scans = bool(stack_scans)
        self.tracks: list[Track] = []
        self._ix = [self.layout.index("x"), self.layout.index("y")]
        self._iv = [self.layout.index("vx"), self.layout.index("vy")]
        self.gated_out = 0
        self.updates = 0
        self.initiations = 0
        self.used_by_sensor: dict[str, int] = {}
        self.dropped_diverged = 0

    @property
    def filter(self) -> Filter | None:
        """The target track's filter, or None without a track."""
        return self.tracks[0].filter if self.tracks else None

    @property
    def last_update_t(self) -> float:
        """Time of the target track's last update (s), −∞ without a track."""
        return self.tracks[0].last_update_t if self.tracks else -np.inf

    def step(self, t: float, detections: Sequence[MeasurementLike]) -> TargetEstimate | None:
        """Absorb ``detections`` (sorted by ``t_meas``) and return the estimate at ``t`` (s), or None without a
        track."""
        self._absorb(detections, InformationDeferral(None))
        return self.estimate(t)

    def step_information(self, t: float, detections: Sequence[MeasurementLike]) -> TrackInformation | None:
        """Like :meth:`step`, but the gated detections of the scans taken at ``t`` (s) are not applied: the sum of
        their information contributions is returned beside the track's prior at ``t`` (:mod:`.information`). Older
        scans are applied locally first.

        Apply the fused result with :meth:`set_information`, then read it with :meth:`current_estimate`. Needs
        information filters. Returns None without a track (also when the track was dropped as lost).
        """
        contribution = self._absorb(detections, InformationDeferral(t))
        if not self._still_tracked(t):
            return None
        if contribution is None and t > self.filter.t:
            self.filter.predict(t)
        return TrackInformation(t=float(t), prior=self.filter.information_state, contribution=contribution)

    def set_information(self, info: SqrtInformation) -> None:
        """Replace the track's estimate by ``info`` (e.g. the consensus posterior at the time of the last
        :meth:`step_information`)."""
        if self.filter is None:
            raise ValueError("set_information needs a track")
        self.filter.set_information(info)

    def estimate(self, t: float) -> TargetEstimate | None:
        """The track's estimate predicted to ``t`` (s), or None without a track (dropping it if lost by ``t``)."""
        if not self._still_tracked(t):
            return None
        if t > self.filter.t:
            self.filter.predict(t)
        return self.current_estimate()

    def current_estimate(self) -> TargetEstimate | None:
        """The track's estimate at its filter's own time, without the loss check or prediction of :meth:`estimate`
        (e.g. right after :meth:`step_information`, which made both, and :meth:`set_information`); None without a
        track."""
        if self.filter is None:
            return None
        x, P = self.filter.x, self.filter.P
        idx = self._ix + self._iv
        return TargetEstimate(t=self.filter.t, p_W=x[self._ix], v_W=x[self._iv], P=P[np.ix_(idx, idx)])

    def _scans(self, detections: Sequence[MeasurementLike]) -> list[tuple[float, list]]:
        """``(t_meas, detections)`` of each scan, in time order."""
        scans: dict[tuple[float, object], list] = {}
        stack = self.stack_scans
        for d in detections:
            scans.setdefault((d.t_meas, "" if stack else d.sensor_id), []).append(d)
        return [(key[0], dets) for key, dets in sorted(scans.items(), key=lambda kv: kv[0][0])]

    def _absorb(self, detections: Sequence[MeasurementLike], deferral: InformationDeferral) -> SqrtInformation | None:
        """Initiate, gate, update and delete from ``detections``, scan by scan; returns what ``deferral`` collected."""
        for t_meas, scan in self._scans(detections):
            self._drop_coasted(t_meas)
            self._process_scan(t_meas, scan, deferral)
        return deferral.total()

    def _process_scan(self, t_meas: float, scan: Sequence[MeasurementLike], deferral: InformationDeferral) -> None:
        """One scan taken at ``t_meas`` (s), after the coasting deleter: steps 2–5 of the module docstring, the
        single-target policy (a multi-target tracker replaces this with its own)."""
        if not self.tracks:
            deferral.clear()  # made against a track that is gone
            self._initiate(scan)
            return
        track = self.tracks[0]
        if t_meas < track.filter.t:
            return  # out of sequence: older than the track
        (assoc,) = self.associator.associate([track], scan)
        self.gated_out += assoc.gated_out
        chosen = assoc.detections
        if not chosen:
            track.missed += self.fixer.fixes_position(scan)
            if self.divergence.deletes(track, t_meas):  # diverged: start again from these fixes
                self.tracks.remove(track)
                deferral.clear()
                self.dropped_diverged += 1
                self.initiator.reset()
                self._initiate(scan)
            return
        best = chosen[0] if len(chosen) == 1 else StackedMeasurement(parts=tuple(chosen))
        deferral.update(track.filter, best)
        if self.fixer.fixes_position(chosen):
            track.missed = 0
        self.updates += 1
        for d in chosen:
            self.used_by_sensor[d.sensor_id] = self.used_by_sensor.get(d.sensor_id, 0) + 1
        track.last_update_t = t_meas

    def _initiate(self, scan: Sequence[MeasurementLike]) -> None:
        new = self.initiator.initiate(scan)
        self.tracks.extend(new)
        self.initiations += len(new)

    def _drop_coasted(self, t: float) -> None:
        self.tracks = [tr for tr in self.tracks if not self.coasting.deletes(tr, t)]

    def _still_tracked(self, t: float) -> bool:
        """Whether a track remains at ``t`` (s), after dropping those lost by then."""
        self._drop_coasted(t)
        return bool(self.tracks)
