"""Set-points passed down the flight-control cascade, stacked over the UAVs of a fleet (leading axis N).

Each controller turns one of these into the next::

    VelocitySetpoint --VelocityController--> AccelerationSetpoint --ThrustVectorController--> AttitudeSetpoint
    --AttitudeController--> RateThrustSetpoint --RateController--> WrenchSetpoint --MotorMixer--> RotorSpeedSetpoint

They are plain containers (slotted, not frozen, and without validation, to keep the per-tick cost low); shapes are
stated per field. Stages never modify a set-point they receive. Each stage owns the set-point it returns and overwrites
its arrays at its next update (the cascade runs every physics tick, where allocating fresh arrays would cost more than
the arithmetic): copy what you want to keep.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["VelocitySetpoint", "AccelerationSetpoint", "AttitudeSetpoint", "RateThrustSetpoint", "WrenchSetpoint",
           "RotorSpeedSetpoint"]


@dataclass(slots=True)
class VelocitySetpoint:
    """``v_W`` (N, 3) velocity (m/s), ``a_ff_W`` (N, 3) feed-forward acceleration (m/s^2), ``yaw`` (N,) heading (rad),
    ``yaw_rate`` (N,) feed-forward heading rate (rad/s)."""

    v_W: np.ndarray
    a_ff_W: np.ndarray
    yaw: np.ndarray
    yaw_rate: np.ndarray


@dataclass(slots=True)
class AccelerationSetpoint:
    """``a_W`` (N, 3) desired acceleration excluding gravity (m/s^2), ``yaw`` (N,) heading (rad), ``yaw_rate`` (N,)
    feed-forward heading rate (rad/s)."""

    a_W: np.ndarray
    yaw: np.ndarray
    yaw_rate: np.ndarray


@dataclass(slots=True)
class AttitudeSetpoint:
    """Desired attitude as thrust axis plus heading, with the thrust: ``F_W`` (N, 3) desired total rotor force in the
    world frame (N), whose direction is the desired body z axis; ``yaw`` (N,) heading of the body x axis (rad);
    ``yaw_rate`` (N,) feed-forward rotation rate about world z (rad/s)."""

    F_W: np.ndarray
    yaw: np.ndarray
    yaw_rate: np.ndarray


@dataclass(slots=True)
class RateThrustSetpoint:
    """``omega_B`` (N, 3) body-rate set-point (rad/s), ``thrust`` (N,) collective thrust (N)."""

    omega_B: np.ndarray
    thrust: np.ndarray


@dataclass(slots=True)
class WrenchSetpoint:
    """``thrust`` (N,) collective thrust (N), ``torque_B`` (N, 3) body torque (N m)."""

    thrust: np.ndarray
    torque_B: np.ndarray


@dataclass(slots=True)
class RotorSpeedSetpoint:
    """``omega`` (N, 4) rotor speed commands (rad/s)."""

    omega: np.ndarray
