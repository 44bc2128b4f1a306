"""Re-exports of the guidance set-points, which live in :mod:`interfaces.setpoints` now."""

from interfaces.setpoints import Setpoint, UnicycleSetpoint, VelocitySetpoint

__all__ = ["UnicycleSetpoint", "VelocitySetpoint", "Setpoint"]
