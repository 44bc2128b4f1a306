"""Re-exports, under their former names, of the flight set-points, which live in :mod:`interfaces.setpoints` now."""

from interfaces.setpoints import FACE_VELOCITY_MIN_SPEED
from interfaces.setpoints import FlightSetpoint as FlightCommand
from interfaces.setpoints import PositionSetpoint as PositionCommand
from interfaces.setpoints import UnicycleSetpoint as UnicycleCommand
from interfaces.setpoints import VelocitySetpoint as VelocityCommand

__all__ = ["PositionCommand", "VelocityCommand", "UnicycleCommand", "FlightCommand", "FACE_VELOCITY_MIN_SPEED"]
