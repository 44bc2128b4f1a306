"""When a track is dropped: after coasting too long without an update, or after rejecting too many fixes in a row."""

from __future__ import annotations

from .track import Track

__all__ = ["MissedScansDeleter", "UpdateTimeDeleter"]


class UpdateTimeDeleter:
    """Drops a track that has gone more than ``lost_after_s`` (s, > 0) without an update."""

    def __init__(self, lost_after_s: float) -> None:
        if not lost_after_s > 0:
            raise ValueError(f"UpdateTimeDeleter.lost_after_s must be > 0 s, got {lost_after_s!r}")
        self.lost_after_s = float(lost_after_s)

    def deletes(self, track: Track, t: float) -> bool:
        """Whether ``track`` is lost at ``t`` (s): ``t − last_update_t > lost_after_s``."""
        return t - track.last_update_t > self.lost_after_s


class MissedScansDeleter:
    """Drops a track whose last ``max_missed_scans`` (>= 1) position-fixing scans all fell outside its gate: a track
    that rejects every fix it is shown has diverged (a bad two-point velocity, a track started on clutter)."""

    def __init__(self, max_missed_scans: int) -> None:
        if int(max_missed_scans) != max_missed_scans or max_missed_scans < 1:
            raise ValueError(f"MissedScansDeleter.max_missed_scans must be an integer >= 1, got {max_missed_scans!r}")
        self.max_missed_scans = int(max_missed_scans)

    def deletes(self, track: Track, t: float) -> bool:
        """Whether ``track`` has diverged (``t``, s, is not used: the count is of scans)."""
        return track.missed >= self.max_missed_scans
