"""The set-membership estimator as one UAV's estimator in the run loop: scans in, sets out.

A bounded-error scan is two things: the ground region ``F`` the sensor observed (footprint less the building
shadows) and the box detections inside it. The region carries information even with no detection (no target is in
``F``), so it reaches the tracker on its own channel, :meth:`SetMembershipTracker.observe`; the detections come
through :meth:`SetMembershipTracker.step` like any estimator's (the box detections' model,
:class:`~autonomy.estimation.measurements.PositionDetectionModel`, with their error bound). The Gaussian trackers'
other parts (initiation, gating, association, deletion: :mod:`autonomy.estimation.tracking`) have no counterpart
here: the sets hold every target consistent with the scans, so nothing is started, gated or dropped.

At a step, every scan that has arrived is applied in the order it was taken: predict to the scan's time, correct
with its region and the detections taken then (regions of one time from several sensors are united). A scan older
than the sets cannot be applied (the sets cannot be predicted backwards); it is dropped and counted in
:attr:`SetMembershipTracker.late_scans`. Then the sets are predicted to the step's time.

:meth:`SetMembershipTracker.step` returns ``None``: the sets replace a point estimate (paper 004 tracks an unknown
number of unlabelled targets). The team's set fusion and the search guidance read
:attr:`SetMembershipTracker.estimator`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from shapely.geometry.base import BaseGeometry

from autonomy.estimation.base import TIME_TOLERANCE
from autonomy.sensing.measurement import Detection

from . import polygons as pg
from .estimator import SetMembershipConfig, SetMembershipEstimator

__all__ = ["ObservedRegion", "SetMembershipTracker"]

_SAME_TIME = TIME_TOLERANCE  # s: scans stamped within this of each other are one scan (as in the trackers)


@dataclass(frozen=True, kw_only=True)
class ObservedRegion:
    """The ground region one scan observed.

    Attributes
    ----------
    t_meas : float
        When the scan was taken (s).
    t_arrival : float
        When it reaches the estimator (s).
    region : BaseGeometry
        Observed ground region (m, world frame).
    """

    t_meas: float
    t_arrival: float
    region: BaseGeometry


class SetMembershipTracker:
    """Set-membership estimation of one UAV from its scans (module docstring).

    Parameters
    ----------
    config : SetMembershipConfig
        Estimator parameters.
    free_area : BaseGeometry
        ``X_s``: the search area less the building footprints (m).
    owner : int
        Index of the UAV (orders the team's set fusion).
    t0 : float
        Start time (s).
    """

    def __init__(self, config: SetMembershipConfig, free_area: BaseGeometry, owner: int, t0: float = 0.0) -> None:
        self.estimator = SetMembershipEstimator(config, free_area, t0, owner=owner)
        self._regions: list[ObservedRegion] = []
        self.scans = 0
        self.late_scans = 0

    def observe(self, scan: ObservedRegion) -> None:
        """Queue a scan's observed region; it is applied at the first step at or after its arrival."""
        self._regions.append(scan)

    def step(self, t: float, detections: Sequence[Detection]) -> None:
        """Apply the scans that have arrived by ``t`` (s) with their ``detections``, then predict to ``t``."""
        ready = [r for r in self._regions if r.t_arrival <= t + _SAME_TIME]
        self._regions = [r for r in self._regions if r.t_arrival > t + _SAME_TIME]
        dets = list(detections)
        times = sorted({r.t_meas for r in ready})
        unmatched = [d for d in dets if not any(abs(d.t_meas - s) <= _SAME_TIME for s in times)]
        if unmatched:
            raise ValueError(f"box detections taken at t={unmatched[0].t_meas} s arrived without the region their "
                             "scan observed")
        est = self.estimator
        for s in times:
            region = pg.union_all([r.region for r in ready if abs(r.t_meas - s) <= _SAME_TIME])
            mine = [d for d in dets if abs(d.t_meas - s) <= _SAME_TIME]
            if s < est.estimate.t - _SAME_TIME:
                self.late_scans += 1
                continue
            est.predict(max(s, est.estimate.t))
            est.update(region, mine)
            self.scans += 1
        est.predict(max(float(t), est.estimate.t))
        return None
