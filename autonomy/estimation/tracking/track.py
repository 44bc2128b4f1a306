"""A track: one target hypothesis's filter and the bookkeeping the tracker's parts read and write."""

from __future__ import annotations

from collections import OrderedDict

from autonomy.estimation.base import Filter

RECENT_SCANS = 16
"""How many of a track's last updating scans it remembers (:attr:`Track.recent`)."""

__all__ = ["Track"]


class Track:
    """A confirmed track.

    Parameters
    ----------
    filter : Filter
        The track's state estimator (any filter: EKF, UKF, CKF, SCIF, IMM, a road-network filter).
    last_update_t : float
        Time of the detection that started it (s).

    Attributes
    ----------
    filter : Filter
        The estimator, at its own time ``filter.t`` (s).
    last_update_t : float
        Time of the last scan whose detections updated the track (or that started it), s: what a coasting deleter
        reads.
    missed : int
        Consecutive position-fixing scans whose detections all fell outside the track's gate: what a divergence
        deleter reads.
    track_id : int
        The tracker's id of the track (unique for the tracker's whole run; 0 until the tracker numbers it).
    hits, scans : int
        Position-fixing scans that updated the track, and that it was tried against, since it began (the two fixes
        that started it count in both): what an M-of-N confirmation reads.
    confirmed : bool
        Whether the track passed its confirmation logic (a single-target tracker's tracks are born confirmed).
    evidence : float
        Log-likelihood ratio (the designated target vs a background car) of the class readings that updated the
        track (:func:`~.identity.track_evidence`).
    class_loglik : dict[str, np.ndarray]
        Per attribute, the log-likelihood of those readings for every class.
    unseen : float
        Log-likelihood of the cameras' misses since a camera last updated the track (0 when it just did; see
        :meth:`~.multi.MultiTargetTracker.observe_coverage`).
    recent : OrderedDict[tuple, int]
        The last :data:`RECENT_SCANS` scans that updated the track, ``(sensor id, time) → id`` of the detection it
        took: two tracks updated by different detections of one scan are two cars (a sensor reports a car once per
        scan), which a merge must not join.
    """

    def __init__(self, filter: Filter, last_update_t: float, *, track_id: int = 0, hits: int = 1, scans: int = 1,
                 confirmed: bool = True) -> None:
        self.filter = filter
        self.last_update_t = float(last_update_t)
        self.missed = 0
        self.track_id = int(track_id)
        self.hits = int(hits)
        self.scans = int(scans)
        self.confirmed = bool(confirmed)
        self.evidence = 0.0
        self.class_loglik: dict = {}
        self.unseen = 0.0
        self.recent: OrderedDict = OrderedDict()

    def took(self, sensor_id: object, t_meas: float, detection: object) -> None:
        """Remember that ``detection`` of the scan ``(sensor_id, t_meas)`` updated the track."""
        self.recent[(sensor_id, float(t_meas))] = id(detection)
        while len(self.recent) > RECENT_SCANS:
            self.recent.popitem(last=False)

    def seen_apart_from(self, other: Track) -> bool:
        """Whether a scan both remember updated this track and ``other`` with different detections."""
        a, b = (self.recent, other.recent) if len(self.recent) <= len(other.recent) else (other.recent, self.recent)
        return any(b.get(key, det) != det for key, det in a.items())

    def __repr__(self) -> str:
        return (f"Track(id={self.track_id}, t={self.filter.t:.3f}, last_update_t={self.last_update_t:.3f}, "
                f"missed={self.missed}, hits={self.hits}/{self.scans}, confirmed={self.confirmed})")
