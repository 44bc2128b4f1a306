"""Configuration and messages of the road-following driver."""

from __future__ import annotations

from dataclasses import dataclass

from pydantic import ConfigDict

from worlds.rates import divisor
from worlds.schema import DriverSpec

__all__ = ["DriverConfig", "DriveCommand", "LeaderInfo"]


class DriverConfig(DriverSpec):
    """Behaviour of one driver: the world schema's :class:`worlds.schema.DriverSpec` itself, frozen.

    The settings, their units, defaults and bounds are declared once, in the schema (a world file's
    ``ground_vehicles[i].driver``); this class adds no field, only the driver's tick arithmetic. Build one from a world
    entry with ``DriverConfig(**spec.model_dump())``; a bad value raises a ``pydantic.ValidationError`` (a
    ``ValueError``) naming the field.
    """

    model_config = ConfigDict(frozen=True)

    def ticks_per_update(self, physics_hz: int) -> int:
        """Physics ticks between driver updates; raises if ``rate_hz`` does not divide ``physics_hz``."""
        return divisor(self.rate_hz, physics_hz, "DriverConfig.rate_hz")


@dataclass(frozen=True, kw_only=True)
class LeaderInfo:
    """The nearest car ahead in the same lane.

    Attributes
    ----------
    gap : float
        Bumper-to-bumper distance along the lane (m).
    speed : float
        Its speed along the lane (m/s).
    index : int
        Its index in the fleet.
    """

    gap: float
    speed: float
    index: int = -1


@dataclass(frozen=True, kw_only=True)
class DriveCommand:
    """Driver output, held until the next driver update.

    Attributes
    ----------
    accel : float
        Longitudinal acceleration command (m/s^2); negative brakes.
    steer : float
        Bicycle-model front-wheel steering angle (rad), positive left.
    hold : bool
        Stand still with the brakes on (stopped at a junction or at the end of the route).
    tick : int
        Physics tick of the update that produced it.
    """

    accel: float
    steer: float
    hold: bool = False
    tick: int = 0
