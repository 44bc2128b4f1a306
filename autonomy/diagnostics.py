"""What the simulator may read from an estimator or a guidance law besides their main method: small typed protocols.

A component shows a diagnostic by implementing the protocol (the built-in ones do; a user's class may); the simulator
checks with ``isinstance`` and reads nothing else, so a component that lacks one is simply not asked.

- :class:`PlansPath`: a guidance law that plans over a horizon shares the path with its teammates
  (``TeammateState.plan_p_W``) and the time step between its points (``plan_dt``);
- :class:`KeepsSolverStats`: a guidance law's solver counters and solve times (``metrics.json``);
- :class:`HoldsRoad`: the road a road-constrained estimator holds the target on (the ``estimates`` stream's ``road``);
- :class:`CountsSensorUse`: the detections that updated an estimator's track, per sensor id (``measurement_sharing``);
- :class:`DecidesSearch`: the last decision of a set-membership search law (the ``search`` stream);
- :class:`HoldsTracks`: the tracks of a multi-target estimator and which one is the target (the ``tracks`` stream,
  the identity metrics, the team's track association).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    from autonomy.guidance.search.planner import SearchDecision
    from interfaces.state import TrackReport

__all__ = ["CountsSensorUse", "DecidesSearch", "HoldsRoad", "HoldsTracks", "KeepsSolverStats", "PlansPath",
           "SolverSummary"]


@runtime_checkable
class PlansPath(Protocol):
    """A guidance law that plans a path over a horizon."""

    def planned_path(self) -> np.ndarray | None:
        """(K, 2) or (K, 3) positions (m) planned at ``t + plan_step_s() · (k + 1)``, or None without a plan."""
        ...

    def plan_step_s(self) -> float:
        """Time between the planned points (s), > 0."""
        ...


@runtime_checkable
class SolverSummary(Protocol):
    """Solver counters as a flat mapping (``solves``, ``failures``, ``solve_ms_p50`` ...;
    :meth:`autonomy.guidance.base.GuidanceStats.summary`)."""

    def summary(self) -> Mapping[str, float]:
        ...


@runtime_checkable
class KeepsSolverStats(Protocol):
    """A guidance law with solver statistics (every :class:`autonomy.guidance.base.Guidance`)."""

    stats: SolverSummary


@runtime_checkable
class HoldsRoad(Protocol):
    """An estimator that may hold its target on a road of the map."""

    def road_held(self) -> str:
        """Id of the road the target is held on; "" off the map or without a track."""
        ...


@runtime_checkable
class CountsSensorUse(Protocol):
    """An estimator that counts the detections that updated its track, by sensor id."""

    used_by_sensor: Mapping[str, int]


@runtime_checkable
class DecidesSearch(Protocol):
    """A set-membership search law: its last decision (None before the first)."""

    last_decision: SearchDecision | None


@runtime_checkable
class HoldsTracks(Protocol):
    """A multi-target estimator: its tracks after its last step, and which of them it takes for the target."""

    def track_reports(self) -> Sequence[TrackReport]:
        """Every live track (tentative ones too, with ``confirmed`` False) after the last step, at that step's time."""
        ...

    @property
    def target_track_id(self) -> int | None:
        """Id of the track the estimator takes for the designated target (its estimate is the one ``step``
        returned), or None when no track is believed to be the target."""
        ...
