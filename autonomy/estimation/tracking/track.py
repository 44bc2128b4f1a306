"""A track: one target hypothesis's filter and the bookkeeping the tracker's parts read and write."""

from __future__ import annotations

from autonomy.estimation.base import Filter

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
    """

    def __init__(self, filter: Filter, last_update_t: float) -> None:
        self.filter = filter
        self.last_update_t = float(last_update_t)
        self.missed = 0

    def __repr__(self) -> str:
        return f"Track(t={self.filter.t:.3f}, last_update_t={self.last_update_t:.3f}, missed={self.missed})"
