"""Set-points a guidance law hands to a UAV's controllers.

The simulator maps each type onto the quadrotor's own commands (velocity controller, yaw controller, altitude hold).
Frames: world ENU, metres, seconds, radians; yaw and heading counter-clockwise from +x.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["UnicycleSetpoint", "VelocitySetpoint", "Setpoint"]


@dataclass(frozen=True, kw_only=True)
class UnicycleSetpoint:
    """Horizontal speed, heading rate and altitude, as a fixed-wing-style unicycle would fly them.

    Attributes
    ----------
    speed : float
        Commanded horizontal ground speed along the current heading (m/s), >= 0.
    heading_rate : float
        Commanded rate of change of the horizontal course angle (rad/s), counter-clockwise positive.
    altitude : float
        Commanded altitude z in the world frame (m).
    """

    speed: float
    heading_rate: float
    altitude: float

    def __post_init__(self) -> None:
        for name in ("speed", "heading_rate", "altitude"):
            v = getattr(self, name)
            if not np.isfinite(v):
                raise ValueError(f"UnicycleSetpoint.{name} must be finite, got {v}")
            object.__setattr__(self, name, float(v))
        if self.speed < 0.0:
            raise ValueError(f"UnicycleSetpoint.speed must be >= 0 m/s, got {self.speed}")


@dataclass(frozen=True, kw_only=True)
class VelocitySetpoint:
    """World-frame velocity and optional yaw.

    Attributes
    ----------
    v_W : np.ndarray
        (3,) commanded velocity in the world frame (m/s).
    yaw : float | None
        Commanded yaw (rad); ``None`` lets the controller choose (e.g. face the velocity).
    """

    v_W: np.ndarray
    yaw: float | None = None

    def __post_init__(self) -> None:
        v = np.array(self.v_W, dtype=float).reshape(-1)
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise ValueError(f"VelocitySetpoint.v_W must be a finite (3,) array, got {self.v_W!r}")
        v.setflags(write=False)
        object.__setattr__(self, "v_W", v)
        if self.yaw is not None:
            if not np.isfinite(self.yaw):
                raise ValueError(f"VelocitySetpoint.yaw must be finite or None, got {self.yaw}")
            object.__setattr__(self, "yaw", float(self.yaw))


Setpoint = UnicycleSetpoint | VelocitySetpoint
