"""Set-points a guidance law hands to its UAV and the quadrotor's flight controller flies, one set for both sides.

Guidance returns a :data:`Setpoint` (unicycle or velocity); :meth:`vehicles.quadrotor.fleet.QuadrotorFleet.set_command`
accepts any :data:`FlightSetpoint` (those two or a position). The outer loop (:mod:`vehicles.quadrotor.command_shaping`)
turns each into a velocity set-point, then flies it through the cascade velocity -> thrust vector -> attitude -> body
rate -> rotor speeds. Set-points beyond the airframe's envelope are saturated and the saturation is reported as a
``command_saturated`` event.

Frames: world ENU, metres, seconds, radians; yaw and heading counter-clockwise from +x.

Yaw convention: ``yaw=None`` on a :class:`PositionSetpoint` holds the heading the UAV had when the set-point was set;
on a :class:`VelocitySetpoint` it faces the horizontal velocity set-point when that exceeds
:data:`FACE_VELOCITY_MIN_SPEED`, and otherwise holds the heading at the time of the set-point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from interfaces._checks import finite_number, finite_vector

__all__ = ["FACE_VELOCITY_MIN_SPEED", "FlightSetpoint", "PositionSetpoint", "Setpoint", "UnicycleSetpoint",
           "VelocitySetpoint"]

FACE_VELOCITY_MIN_SPEED = 0.5
"""Horizontal speed above which ``VelocitySetpoint(yaw=None)`` faces its velocity (m/s)."""


def _yaw(owner: str, value: object) -> float | None:
    return None if value is None else finite_number(owner, "yaw", value)


@dataclass(frozen=True, kw_only=True)
class UnicycleSetpoint:
    """Horizontal speed, heading rate and altitude, as a fixed-wing-style unicycle would fly them.

    The commanded heading integrates ``heading_rate`` from the UAV's heading at the moment the set-point is set,
    ``psi_c(t) = psi_0 + heading_rate * (t - t_0)``, and the horizontal velocity set-point is
    ``speed * (cos psi_c, sin psi_c)`` with centripetal feed-forward ``speed * heading_rate``; the body faces
    ``psi_c``. Altitude is held by the vertical position loop.

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
            object.__setattr__(self, name, finite_number("UnicycleSetpoint", name, getattr(self, name)))
        if self.speed < 0.0:
            raise ValueError(f"UnicycleSetpoint.speed must be >= 0 m/s, got {self.speed!r}")


@dataclass(frozen=True, kw_only=True)
class VelocitySetpoint:
    """World-frame velocity and optional yaw.

    Attributes
    ----------
    v_W : np.ndarray
        (3,) commanded velocity in the world frame (m/s). The flight controller saturates the horizontal speed at the
        airframe's ``max_speed`` (direction kept) and the vertical speed at its ``max_climb_rate``.
    yaw : float | None
        Commanded yaw (rad); ``None`` faces the horizontal velocity (see the module docstring).
    """

    v_W: np.ndarray
    yaw: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "v_W", finite_vector("VelocitySetpoint", "v_W", self.v_W, (3,)))
        object.__setattr__(self, "yaw", _yaw("VelocitySetpoint", self.yaw))


@dataclass(frozen=True, kw_only=True)
class PositionSetpoint:
    """Hold or fly to a world position.

    Attributes
    ----------
    p_W : np.ndarray
        (3,) target position in the world frame (m).
    yaw : float | None
        Target heading (rad); ``None`` holds the heading at the time of the set-point.
    """

    p_W: np.ndarray
    yaw: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "p_W", finite_vector("PositionSetpoint", "p_W", self.p_W, (3,)))
        object.__setattr__(self, "yaw", _yaw("PositionSetpoint", self.yaw))


Setpoint = UnicycleSetpoint | VelocitySetpoint
"""What a guidance law returns (and the ``commands`` stream records)."""

FlightSetpoint = PositionSetpoint | VelocitySetpoint | UnicycleSetpoint
"""Any set-point a UAV's flight controller accepts."""
