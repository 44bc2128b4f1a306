"""Position keeping and waypoint following: the simplest guidance laws, for worlds without a target to chase.

Both steer with a saturated proportional velocity law, v = sat(k (p_goal − p), v_max), which the quadrotor's velocity
controller flies. They ignore the target estimate.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from autonomy.guidance.base import Guidance
from interfaces.setpoints import VelocitySetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState

__all__ = ["WaypointConfig", "WaypointGuidance"]


@dataclass(frozen=True, kw_only=True)
class WaypointConfig:
    """Waypoint following.

    Attributes
    ----------
    waypoints : tuple[tuple[float, float, float], ...]
        Positions to visit in order (m, ENU); one waypoint = hold there.
    speed : float
        Maximum commanded speed (m/s), > 0.
    gain : float
        Proportional gain k (1/s), > 0.
    acceptance_radius : float
        Distance at which a waypoint counts as reached (m), > 0.
    loop : bool
        Start again from the first waypoint after the last.
    """

    waypoints: tuple[tuple[float, float, float], ...]
    speed: float = 10.0
    gain: float = 0.8
    acceptance_radius: float = 3.0
    loop: bool = False

    def __post_init__(self) -> None:
        if not self.waypoints:
            raise ValueError("WaypointConfig.waypoints must hold at least one position")
        for name in ("speed", "gain", "acceptance_radius"):
            if not getattr(self, name) > 0:
                raise ValueError(f"WaypointConfig.{name} must be > 0, got {getattr(self, name)}")


class WaypointGuidance(Guidance):
    """Fly to each waypoint in turn, then hold the last one (or loop)."""

    def __init__(self, config: WaypointConfig) -> None:
        super().__init__()
        self.config = config
        self._goals = np.asarray(config.waypoints, dtype=float).reshape(-1, 3)
        self.index = 0

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> VelocitySetpoint:
        self.stats.calls += 1
        cfg = self.config
        goal = self._goals[self.index]
        if np.linalg.norm(goal - own.p_W) < cfg.acceptance_radius and len(self._goals) > 1:
            if self.index + 1 < len(self._goals):
                self.index += 1
            elif cfg.loop:
                self.index = 0
            goal = self._goals[self.index]
        v = cfg.gain * (goal - own.p_W)
        speed = float(np.linalg.norm(v))
        if speed > cfg.speed:
            v *= cfg.speed / speed
        return VelocitySetpoint(v_W=v, yaw=None)
