"""Kinematic bicycle model of a car, for testing drivers without the physics engine.

State at the centre of mass, midway between the axles (l_r = L/2):
    beta = atan(l_r tan(delta) / L),  x' = v cos(psi + beta),  y' = v sin(psi + beta),
    psi' = v cos(beta) tan(delta) / L,  v' = a  (v >= 0),
with the steering angle following the command at most ``max_steer_rate`` and acceleration clipped to the car's limits.
"""

from __future__ import annotations

import math

import numpy as np

from vehicles.car.driver_config import DriveCommand
from vehicles.car.params import CarParams

__all__ = ["KinematicBicycle"]


class KinematicBicycle:
    """Kinematic bicycle integrated with explicit Euler steps.

    Parameters
    ----------
    params : CarParams
        Wheelbase and steering / acceleration limits.
    p_xy : np.ndarray
        Initial centre-of-mass position (2,) (m).
    yaw : float
        Initial heading (rad).
    speed : float
        Initial speed (m/s).
    """

    def __init__(self, params: CarParams, p_xy: np.ndarray, yaw: float, speed: float = 0.0) -> None:
        self.params = params
        self.p_xy = np.asarray(p_xy, dtype=float).copy()
        self.yaw = float(yaw)
        self.speed = float(speed)
        self.steer = 0.0
        self.yaw_rate = 0.0

    def step(self, command: DriveCommand, dt: float) -> None:
        """Advance ``dt`` seconds under ``command``."""
        par = self.params
        target = float(np.clip(command.steer, -par.max_steer, par.max_steer))
        self.steer += float(np.clip(target - self.steer, -par.max_steer_rate * dt, par.max_steer_rate * dt))
        a = float(np.clip(command.accel, -par.max_decel, par.max_accel))
        if command.hold:
            a = -par.max_decel
        beta = math.atan(0.5 * math.tan(self.steer))
        self.yaw_rate = self.speed * math.cos(beta) * math.tan(self.steer) / par.wheelbase
        self.p_xy += dt * self.speed * np.array([math.cos(self.yaw + beta), math.sin(self.yaw + beta)])
        self.yaw = (self.yaw + dt * self.yaw_rate + math.pi) % (2 * math.pi) - math.pi
        self.speed = max(0.0, self.speed + a * dt)
