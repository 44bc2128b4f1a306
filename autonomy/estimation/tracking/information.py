"""A track's share of a consensus step (HCMCI, base-station fusion): information collected instead of applied.

In a consensus team the gated detections of the scans taken at the step time are not applied to the track: their
information contributions, each made against the track's prior at that time, are summed
(``S_I = tria([S_I,1, S_I,2, …])``, ``i = i_1 + i_2 + …``) and returned with that prior; the team's consensus result
then replaces the track's estimate. Scans older than the step time are applied locally first: a contribution
``(S_I, i)`` is information about the state at the scan's own time, and adds exactly to a prior only at that time
(there is no exact way to move it to a later prior through the process noise).
"""

from __future__ import annotations

from dataclasses import dataclass

from autonomy.estimation.base import TIME_TOLERANCE, Filter
from autonomy.estimation.measurements import MeasurementLike
from autonomy.estimation.scif import SqrtInformation, add_information

__all__ = ["InformationDeferral", "TrackInformation"]


@dataclass(frozen=True)
class TrackInformation:
    """A track's share of one consensus step at time ``t`` (s).

    Attributes
    ----------
    t : float
        Step time, s; both quantities hold at it.
    prior : SqrtInformation
        The track predicted to ``t`` (after any older scans were applied locally): ``(S_h⁻, ĥ⁻)``.
    contribution : SqrtInformation | None
        Information ``(S_I, i)`` of the gated detections of the scans taken at ``t`` (one per scan, summed); None if
        there was none.
    """

    t: float
    prior: SqrtInformation
    contribution: SqrtInformation | None


class InformationDeferral:
    """Applies a track's updates, except those of the scans taken at ``defer_at`` (s; None: none), whose information
    contributions it collects instead (module docstring)."""

    def __init__(self, defer_at: float | None) -> None:
        self.defer_at = defer_at
        self._parts: list[SqrtInformation] = []

    def update(self, filter: Filter, meas: MeasurementLike) -> None:
        """Update ``filter`` with ``meas``, or keep its contribution if ``meas`` was taken at ``defer_at``."""
        if self.defer_at is not None and abs(meas.t_meas - self.defer_at) <= TIME_TOLERANCE:
            self._parts.append(filter.information(meas)[0])
        else:
            filter.update(meas)

    def clear(self) -> None:
        """Forget the contributions (made against a track that is gone)."""
        self._parts = []

    def total(self) -> SqrtInformation | None:
        """The sum of the collected contributions, or None if there is none."""
        if not self._parts:
            return None
        if len(self._parts) == 1:
            return self._parts[0]
        return add_information(*self._parts)
