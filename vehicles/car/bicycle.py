"""Kinematic bicycle model of a car: the motion of the kinematic ground vehicles, and drivers tested without physics.

State at the centre of mass, midway between the axles (l_r = L/2):
    beta = atan(l_r tan(delta) / L),  x' = v cos(psi + beta),  y' = v sin(psi + beta),
    psi' = v cos(beta) tan(delta) / L,  v' = a  (0 <= v <= v_max),
with the steering angle following the command at most ``max_steer_rate`` and acceleration clipped to the car's limits
(full braking ``max_decel`` while the command holds the car).
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
        Wheelbase and steering / acceleration / speed limits.
    p_xy : np.ndarray
        Initial centre-of-mass position (2,) (m).
    yaw : float
        Initial heading (rad).
    speed : float
        Initial speed of the centre of mass (m/s).

    Attributes
    ----------
    x, y : float
        Centre-of-mass position (m).
    yaw : float
        Heading of the body x axis (rad), in [-pi, pi).
    speed : float
        Speed of the centre of mass (m/s); its forward component is ``speed cos(beta)``.
    steer : float
        Bicycle steering angle (rad).
    beta : float
        Slip angle of the centre of mass (rad).
    yaw_rate : float
        Yaw rate applied over the last step (rad/s).
    """

    def __init__(self, params: CarParams, p_xy: np.ndarray, yaw: float, speed: float = 0.0) -> None:
        self.params = params
        self.x, self.y = float(p_xy[0]), float(p_xy[1])
        self.yaw = float(yaw)
        self.speed = float(speed)
        self.steer = 0.0
        self.beta = 0.0
        self.yaw_rate = 0.0

    @property
    def p_xy(self) -> np.ndarray:
        """Centre-of-mass position (2,) (m)."""
        return np.array([self.x, self.y])

    def step(self, command: DriveCommand, dt: float) -> None:
        """Advance ``dt`` seconds under ``command``."""
        par = self.params
        target = min(max(command.steer, -par.max_steer), par.max_steer)
        rate = par.max_steer_rate * dt
        self.steer += min(max(target - self.steer, -rate), rate)
        a = -par.max_decel if command.hold else min(max(command.accel, -par.max_decel), par.max_accel)
        tan_d = math.tan(self.steer)
        beta = self.beta = math.atan(0.5 * tan_d)
        self.yaw_rate = self.speed * math.cos(beta) * tan_d / par.wheelbase
        ds = dt * self.speed
        self.x += ds * math.cos(self.yaw + beta)
        self.y += ds * math.sin(self.yaw + beta)
        self.yaw = (self.yaw + dt * self.yaw_rate + math.pi) % (2 * math.pi) - math.pi
        self.speed = min(max(0.0, self.speed + a * dt), par.max_speed)

    def rates(self) -> tuple[float, float, float]:
        """(v_x, v_y) of the centre of mass (m/s) and the yaw rate (rad/s) of the present state."""
        h = self.yaw + self.beta
        yaw_rate = self.speed * math.cos(self.beta) * math.tan(self.steer) / self.params.wheelbase
        return self.speed * math.cos(h), self.speed * math.sin(h), yaw_rate
