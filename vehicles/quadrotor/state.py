"""Kinematic and actuator state of a fleet of quadrotors, stacked over UAVs (leading axis N)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FleetState"]


@dataclass(frozen=True, kw_only=True, slots=True)
class FleetState:
    """State of every UAV after the last physics step.

    Attributes
    ----------
    p_W : np.ndarray
        (N, 3) centre-of-mass positions, world ENU (m).
    q_WB : np.ndarray
        (N, 4) body-to-world attitude quaternions (x, y, z, w).
    R_WB : np.ndarray
        (N, 3, 3) body-to-world rotation matrices (same attitude as ``q_WB``).
    v_W : np.ndarray
        (N, 3) velocities, world frame (m/s).
    omega_B : np.ndarray
        (N, 3) angular velocities, body frame FLU (rad/s).
    rotor_speed : np.ndarray
        (N, 4) rotor speeds (rad/s).
    thrust : np.ndarray
        (N, 4) rotor thrusts applied in the last step, ground effect included (N).
    """

    p_W: np.ndarray
    q_WB: np.ndarray
    R_WB: np.ndarray
    v_W: np.ndarray
    omega_B: np.ndarray
    rotor_speed: np.ndarray
    thrust: np.ndarray
