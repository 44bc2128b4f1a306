"""Per-UAV airframe parameters and gains stacked into arrays, so a fleet of mixed airframes runs in one pass."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vehicles.quadrotor.params import ROTOR_SPIN, QuadrotorParams, rotor_positions_B

__all__ = ["AirframeStack"]


@dataclass(frozen=True, kw_only=True)
class AirframeStack:
    """Arrays over N UAVs built from their :class:`QuadrotorParams` (units as in that class).

    Attributes
    ----------
    mass : (N,) kg.  inertia : (N, 3) kg m^2.  k_f : (N,) N s^2/rad^2.  k_m : (N,) N m s^2/rad^2.
    motor_time_constant : (N,) s.  rotor_speed_min, rotor_speed_max : (N,) rad/s.  rotor_radius : (N,) m.
    drag_linear : (N, 3) N s/m.  drag_quadratic : (N, 3) N s^2/m^2.  tilt_max : (N,) rad.
    max_speed, max_climb_rate : (N,) m/s.  max_heading_rate : (N,) rad/s.
    pos_p, vel_p : (N, 3) 1/s (x, y share the xy gain).  vel_i : (N, 3) 1/s^2.  vel_i_limit : (N,) m/s^2.
    vel_i_band : (N,) m/s.
    att_p, rate_p : (N, 3) 1/s (roll, pitch, yaw).  max_rate : (N, 3) rad/s.  tilt_margin : (N,) rad.
    rotor_pos_B : (N, 4, 3) rotor hub positions (m).
    alloc : (N, 4, 4) maps rotor thrusts ``f`` to the wrench ``(T, tau_x, tau_y, tau_z)``.
    alloc_inv : (N, 4, 4) maps the wrench ``(T, tau_x, tau_y, tau_z)`` to rotor thrusts ``f``.
    torque_map : (N, 3, 4) maps rotor thrusts to body torque: rows ``y_i``, ``-x_i``, ``-s_i k_m / k_f``.
    """

    mass: np.ndarray
    inertia: np.ndarray
    k_f: np.ndarray
    k_m: np.ndarray
    motor_time_constant: np.ndarray
    rotor_speed_min: np.ndarray
    rotor_speed_max: np.ndarray
    rotor_radius: np.ndarray
    drag_linear: np.ndarray
    drag_quadratic: np.ndarray
    tilt_max: np.ndarray
    max_speed: np.ndarray
    max_climb_rate: np.ndarray
    max_heading_rate: np.ndarray
    pos_p: np.ndarray
    vel_p: np.ndarray
    vel_i: np.ndarray
    vel_i_limit: np.ndarray
    vel_i_band: np.ndarray
    att_p: np.ndarray
    rate_p: np.ndarray
    max_rate: np.ndarray
    tilt_margin: np.ndarray
    rotor_pos_B: np.ndarray
    alloc: np.ndarray
    alloc_inv: np.ndarray
    torque_map: np.ndarray

    @property
    def n(self) -> int:
        """Number of UAVs."""
        return int(self.mass.shape[0])

    @classmethod
    def from_params(cls, airframes: Sequence[QuadrotorParams]) -> AirframeStack:
        """Stack ``airframes`` (one per UAV, in fleet order)."""
        if len(airframes) == 0:
            raise ValueError("airframes must hold at least one QuadrotorParams")

        def col(get) -> np.ndarray:
            return np.array([get(a) for a in airframes], dtype=float)

        rotor_pos = np.stack([rotor_positions_B(a.arm_length) for a in airframes])
        torque_map = np.stack([
            np.stack([r[:, 1], -r[:, 0], -ROTOR_SPIN * a.yaw_moment_ratio])
            for a, r in zip(airframes, rotor_pos, strict=True)
        ])
        alloc = np.concatenate([np.ones((len(airframes), 1, 4)), torque_map], axis=1)
        g = [a.gains for a in airframes]
        return cls(
            mass=col(lambda a: a.mass),
            inertia=col(lambda a: a.inertia),
            k_f=col(lambda a: a.k_f),
            k_m=col(lambda a: a.k_m),
            motor_time_constant=col(lambda a: a.motor_time_constant),
            rotor_speed_min=col(lambda a: a.rotor_speed_min),
            rotor_speed_max=col(lambda a: a.rotor_speed_max),
            rotor_radius=col(lambda a: a.rotor_radius),
            drag_linear=col(lambda a: a.drag_linear),
            drag_quadratic=col(lambda a: a.drag_quadratic),
            tilt_max=col(lambda a: a.tilt_max),
            max_speed=col(lambda a: a.max_speed),
            max_climb_rate=col(lambda a: a.max_climb_rate),
            max_heading_rate=col(lambda a: a.max_heading_rate),
            pos_p=np.array([(k.pos_p_xy, k.pos_p_xy, k.pos_p_z) for k in g]),
            vel_p=np.array([(k.vel_p_xy, k.vel_p_xy, k.vel_p_z) for k in g]),
            vel_i=np.array([(k.vel_i_xy, k.vel_i_xy, k.vel_i_z) for k in g]),
            vel_i_limit=np.array([k.vel_i_limit for k in g]),
            vel_i_band=np.array([k.vel_i_band for k in g]),
            att_p=np.array([(k.att_p_rp, k.att_p_rp, k.att_p_yaw) for k in g]),
            rate_p=np.array([(k.rate_p_rp, k.rate_p_rp, k.rate_p_yaw) for k in g]),
            max_rate=np.array([(k.max_rate_rp, k.max_rate_rp, k.max_rate_yaw) for k in g]),
            tilt_margin=np.array([k.tilt_margin for k in g]),
            rotor_pos_B=rotor_pos,
            alloc=alloc,
            alloc_inv=np.linalg.inv(alloc),
            torque_map=torque_map,
        )
