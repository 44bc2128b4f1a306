"""Independent estimation: each UAV tracks with its own sensors, optionally fusing the estimates its teammates share.

- :class:`IndependentTeam` (fusion method ``none``): nothing is shared but the UAVs' states;
- :class:`TrackFusionTeam` (``convex``, ``covariance_intersection``; paper 002): every UAV's local estimate goes to
  its teammates, and each member fuses the ones that have arrived with its own for guidance
  (:class:`autonomy.fusion.track_fusion.TrackFusion`, the agent's ``fusion``);
- :class:`MeasurementSharingTeam` (``measurements``; paper 003): the teammates' detections go to each member's
  tracker (:mod:`autonomy.fusion.measurement_sharing`).
"""

from __future__ import annotations

from autonomy.team.base import TeamProtocol

__all__ = ["IndependentTeam", "MeasurementSharingTeam", "TrackFusionTeam"]


class IndependentTeam(TeamProtocol):
    """Each member estimates alone and shares only its state."""


class TrackFusionTeam(TeamProtocol):
    """Each member shares its local estimate and fuses the teammates' with its own (module docstring)."""

    shares_estimates = True


class MeasurementSharingTeam(TeamProtocol):
    """Each member takes its teammates' detections into its own tracker (module docstring)."""

    takes_detections = True
