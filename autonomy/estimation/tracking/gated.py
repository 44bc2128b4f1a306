"""A single-target estimator among many cars: a multi-target tracker in front picks the target's detections.

A user's estimator written for one target (``step(t, detections) -> TargetEstimate | None``) sees, at each step,
only the detections that updated the track the multi-target tracker takes for the target (:mod:`.multi`); the
tracker does association, confirmation and identity, the user's estimator the filtering. Until the user's estimator
has an estimate, the tracker's is returned.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from autonomy.estimation.measurements import MeasurementLike
from interfaces.state import TargetEstimate, TrackReport

from .multi import MultiTargetTracker

__all__ = ["TargetGatedEstimator"]


class TargetGatedEstimator:
    """Feeds ``inner`` (any single-target estimator) the detections of the target's track of ``tracker``.

    Parameters
    ----------
    inner : object with ``step(t, detections)``
        The single-target estimator.
    tracker : MultiTargetTracker
        Tracks every car and keeps which is the target.
    """

    def __init__(self, inner: Any, tracker: MultiTargetTracker) -> None:
        self.inner = inner
        self.tracker = tracker
        self.forwarded = 0

    def step(self, t: float, detections: Sequence[MeasurementLike]) -> TargetEstimate | None:
        """The tracker's step, then ``inner``'s on the detections that updated the target's track (module
        docstring)."""
        fallback = self.tracker.step(t, detections)
        target = self.tracker.target_track_id
        mine = self.tracker.detections_of(target) if target is not None else []
        self.forwarded += len(mine)
        own = self.inner.step(t, mine)
        return own if own is not None else fallback

    def track_reports(self) -> Sequence[TrackReport]:
        """The tracker's tracks."""
        return self.tracker.track_reports()

    @property
    def target_track_id(self) -> int | None:
        """The tracker's target track."""
        return self.tracker.target_track_id

    def cue(self, t: float, p_W: Any, sigma_m: float) -> None:
        """The hand-off, to the tracker."""
        self.tracker.cue(t, p_W, sigma_m)

    def observe_coverage(self, coverages: Sequence[Any]) -> None:
        """Camera frames' coverage, to the tracker (:meth:`MultiTargetTracker.observe_coverage`)."""
        self.tracker.observe_coverage(coverages)
