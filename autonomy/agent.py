"""One UAV's onboard software: sensing → estimation → guidance, composed as the world file says.

The agent runs at its own rate. Between its steps, detections arrive (each with the time it was taken and the time it
reaches the agent); at a step the agent hands every detection that has arrived, in the order they were taken, to its
estimator, which predicts to each measurement's own time stamp; then the guidance law turns the estimate into a
set-point.

Users plug in their own estimator or guidance law: anything with the methods of :class:`TargetEstimator` or
:class:`GuidanceLaw` works (no base class needed), named by import path in the world file (``type: plugin``,
``plugin: mypkg.mymodule:MyClass``) or passed in code to :func:`simulator.api.run`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from autonomy.diagnostics import HoldsTracks
from autonomy.fusion.track_fusion import TrackFusion
from autonomy.sensing.coverage import FrameCoverage
from autonomy.sensing.measurement import Detection
from interfaces.setpoints import Setpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState, TrackPicture

__all__ = ["Agent", "AgentOutput", "GuidanceLaw", "TargetEstimator"]


@runtime_checkable
class TargetEstimator(Protocol):
    """What the agent needs from an estimator."""

    def step(self, t: float, detections: Sequence[Detection]) -> TargetEstimate | None:
        """Absorb ``detections`` (arrived by ``t``, sorted by ``t_meas``) and return the estimate valid at ``t`` (s),
        if any."""
        ...


@runtime_checkable
class GuidanceLaw(Protocol):
    """What the agent needs from a guidance law."""

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> Setpoint:
        """Set-point for the UAV at ``t`` (s)."""
        ...


@dataclass(frozen=True)
class AgentOutput:
    """What one agent step produced.

    Attributes
    ----------
    setpoint : Setpoint
        For the UAV's controllers.
    estimate : TargetEstimate | None
        The estimate guidance used: the fused one when the agent fuses, else the local one.
    local_estimate : TargetEstimate | None
        The agent's own estimator output (to share with teammates).
    used_detections : int
        Detections absorbed at this step.
    """

    setpoint: Setpoint
    estimate: TargetEstimate | None
    local_estimate: TargetEstimate | None
    used_detections: int


class Agent:
    """One UAV's autonomy.

    Parameters
    ----------
    uav_id : str
        The UAV's id (from the world file).
    estimator : TargetEstimator
        Target estimator (built-in tracker or a user's class).
    guidance : GuidanceLaw
        Guidance law (built-in or a user's class).
    idle : GuidanceLaw | None
        Flown while there is no target estimate (e.g. hold a search point); None hands ``target=None`` to ``guidance``.
    fusion : TrackFusion | None
        Fuses the local estimate with teammates' shared estimates for guidance; None = no fusion.
    """

    def __init__(self, uav_id: str, estimator: TargetEstimator, guidance: GuidanceLaw,
                 idle: GuidanceLaw | None = None, fusion: TrackFusion | None = None) -> None:
        self.uav_id = uav_id
        self.estimator = estimator
        self.guidance = guidance
        self.idle = idle
        self.fusion = fusion
        self._pending: list[Detection] = []
        self._coverage: list[FrameCoverage] = []
        self.estimate: TargetEstimate | None = None

    def receive(self, detections: Sequence[Detection]) -> None:
        """Queue detections; they are used at the first step at or after their arrival time."""
        self._pending.extend(detections)

    def receive_coverage(self, coverage: FrameCoverage) -> None:
        """Queue a camera frame's coverage; an estimator with ``observe_coverage`` (the multi-target tracker) gets it
        with the detections of its step (:meth:`take_ready`), any other ignores it."""
        self._coverage.append(coverage)

    def step(self, t: float, own: OwnState, teammates: Sequence[TeammateState],
             shared: Sequence[TargetEstimate | TrackPicture] = ()) -> AgentOutput:
        """Run estimation, fusion with the teammates' ``shared`` estimates, and guidance at time ``t`` (s)."""
        ready = self.take_ready(t)
        return self.act(t, own, teammates, self.estimator.step(t, ready), len(ready), shared)

    def take_ready(self, t: float) -> list[Detection]:
        """Detections that have arrived by ``t`` (s), in the order they were taken; they leave the queue. The camera
        coverage that has arrived by ``t`` leaves its queue too, handed to the estimator's ``observe_coverage`` if it
        has one (so it is processed with the detections of the same step).

        For a step whose estimation runs outside the agent (a consensus team): pass the estimate to :meth:`act`.
        """
        ready = sorted((d for d in self._pending if d.t_arrival <= t + 1e-9), key=lambda d: d.t_meas)
        self._pending = [d for d in self._pending if d.t_arrival > t + 1e-9]
        if self._coverage:
            arrived = [c for c in self._coverage if c.t_arrival <= t + 1e-9]
            self._coverage = [c for c in self._coverage if c.t_arrival > t + 1e-9]
            observe = getattr(self.estimator, "observe_coverage", None)
            if observe is not None and arrived:
                observe(arrived)
        return ready

    def act(self, t: float, own: OwnState, teammates: Sequence[TeammateState], local: TargetEstimate | None,
            used_detections: int, shared: Sequence[TargetEstimate | TrackPicture] = ()) -> AgentOutput:
        """Fusion (if any) of ``local`` with ``shared`` and guidance at ``t`` (s), on an estimate already made.

        An estimator that holds many tracks (:class:`~autonomy.diagnostics.HoldsTracks`) fuses its tracks with the
        teammates' track pictures after associating them; ``shared`` estimates of single-target teammates are
        fused as before."""
        pictures = [s for s in shared if isinstance(s, TrackPicture)]
        estimates = [s for s in shared if not isinstance(s, TrackPicture)]
        if self.fusion is None:
            self.estimate = local
        elif isinstance(self.estimator, HoldsTracks):
            self.estimate = self.fusion.fuse_tracks(t, local, self.estimator.track_reports(),
                                                    self.estimator.target_track_id, pictures)
            if pictures and hasattr(self.estimator, "team_target"):
                self.estimator.team_target = self.fusion.team_track_id  # followed from the next step on
        else:
            self.estimate = self.fusion.fuse(t, local, estimates)
        law = self.idle if self.estimate is None and self.idle is not None else self.guidance
        setpoint = law.command(own, self.estimate, teammates, t)
        return AgentOutput(setpoint=setpoint, estimate=self.estimate, local_estimate=local,
                           used_detections=used_detections)
