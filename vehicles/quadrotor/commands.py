"""Typed set-points a UAV's flight controller accepts.

Guidance hands one of these to :meth:`vehicles.quadrotor.fleet.QuadrotorFleet.set_command`. Each is turned into a
velocity set-point by the outer loop (:mod:`vehicles.quadrotor.command_shaping`), then flown through the cascade
velocity -> thrust vector -> attitude -> body rate -> rotor speeds. Set-points beyond the airframe's envelope are
saturated and the saturation is reported as a ``command_saturated`` event.

Yaw convention: ``yaw=None`` on a :class:`PositionCommand` holds the heading the UAV had when the command was set; on a
:class:`VelocityCommand` it faces the horizontal velocity set-point when that exceeds
:data:`FACE_VELOCITY_MIN_SPEED`, and otherwise holds the heading at the time of the command.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["PositionCommand", "VelocityCommand", "UnicycleCommand", "FlightCommand", "FACE_VELOCITY_MIN_SPEED"]

FACE_VELOCITY_MIN_SPEED = 0.5
"""Horizontal speed above which ``VelocityCommand(yaw=None)`` faces its velocity (m/s)."""


def _vec3(owner: str, name: str, value: object) -> np.ndarray:
    arr = np.array(value, dtype=float).reshape(-1)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{owner}.{name} must be 3 finite numbers, got {value!r}")
    arr.setflags(write=False)
    return arr


def _yaw(owner: str, value: float | None) -> float | None:
    if value is None:
        return None
    if not math.isfinite(value):
        raise ValueError(f"{owner}.yaw must be finite (rad) or None, got {value!r}")
    return float(value)


@dataclass(frozen=True, kw_only=True)
class PositionCommand:
    """Hold or fly to a world position.

    Attributes
    ----------
    p_W : np.ndarray
        Target position in the world frame, ENU (m), shape (3,).
    yaw : float | None
        Target heading, counter-clockwise from +x (rad); ``None`` holds the heading at the time of the command.
    """

    p_W: np.ndarray
    yaw: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "p_W", _vec3("PositionCommand", "p_W", self.p_W))
        object.__setattr__(self, "yaw", _yaw("PositionCommand", self.yaw))


@dataclass(frozen=True, kw_only=True)
class VelocityCommand:
    """Fly a world-frame velocity.

    Attributes
    ----------
    v_W : np.ndarray
        Velocity set-point in the world frame, ENU (m/s), shape (3,). Horizontal speed is saturated at the airframe's
        ``max_speed`` (direction kept), vertical speed at ``max_climb_rate``.
    yaw : float | None
        Heading set-point (rad); ``None`` faces the horizontal velocity (see the module docstring).
    """

    v_W: np.ndarray
    yaw: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "v_W", _vec3("VelocityCommand", "v_W", self.v_W))
        object.__setattr__(self, "yaw", _yaw("VelocityCommand", self.yaw))


@dataclass(frozen=True, kw_only=True)
class UnicycleCommand:
    """The unicycle set-point of the guidance laws: horizontal speed, heading rate, altitude.

    The commanded heading integrates ``heading_rate`` from the UAV's heading at the moment the command is set,
    ``psi_c(t) = psi_0 + heading_rate * (t - t_0)``, and the horizontal velocity set-point is
    ``speed * (cos psi_c, sin psi_c)`` with centripetal feed-forward ``speed * heading_rate``; the body faces
    ``psi_c``. Altitude is held by the vertical position loop.

    Attributes
    ----------
    speed : float
        Horizontal speed (m/s), >= 0.
    heading_rate : float
        Heading rate, counter-clockwise positive (rad/s).
    altitude : float
        Altitude above the world origin, z (m).
    """

    speed: float
    heading_rate: float
    altitude: float

    def __post_init__(self) -> None:
        for name in ("speed", "heading_rate", "altitude"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise ValueError(f"UnicycleCommand.{name} must be a finite number, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.speed < 0:
            raise ValueError(f"UnicycleCommand.speed must be >= 0 m/s, got {self.speed!r}")


FlightCommand = PositionCommand | VelocityCommand | UnicycleCommand
"""Any set-point a UAV accepts."""
