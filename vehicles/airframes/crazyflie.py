"""Crazyflie 2.x-class micro quadrotor (X configuration), consistent with gym-pybullet-drones' ``cf2x.urdf``.

Sources and derivations (SI units throughout; rotor speeds in rad/s):

- ``cf2x.urdf`` (gym-pybullet-drones): m = 0.027 kg, arm = 0.0397 m, kf = 3.16e-10 N/rpm^2, km = 7.94e-12 N m/rpm^2,
  thrust-to-weight 2.25, propeller radius 2.31348e-2 m, collision cylinder radius 0.06 m, height 0.025 m.
  Coefficients converted to rad/s: (60 / 2 pi)^2 = 91.189, so k_f = 2.8816e-8 N s^2/rad^2 and
  k_m = 7.2404e-10 N m s^2/rad^2. Rotor saturation from the thrust-to-weight ratio:
  omega_max = sqrt(2.25 m g / (4 k_f)) = 2274 rad/s (21 714 rpm); hover 1516 rad/s (14 476 rpm).
- Inertia: closed form of :func:`vehicles.quadrotor.inertia.x_frame_inertia` with a 15 g hub (PCB + battery,
  0.05 x 0.05 x 0.015 m) and four 3 g motor + propeller sets: (1.29e-5, 1.29e-5, 2.52e-5) kg m^2, between the
  URDF's (1.4e-5, 1.4e-5, 2.17e-5) and the system-identified (1.66e-5, 1.67e-5, 2.93e-5) of Foerster (2015).
- Motor time constant 0.015 s (Foerster 2015 step responses of the 7 x 16 mm coreless motors).
- Drag: gym-pybullet-drones' rotor drag 9.1785e-7 (xy) and 10.311e-7 (z) N s/m per rpm of summed rotor speed,
  evaluated at hover (4 x 1516 rad/s): 5.6e-3 and 6.3e-3 N s/m linear; quadratic 0.5 rho C_d A with frontal area
  ~1e-3 m^2 and plan area ~2.5e-3 m^2.
- Envelope: 3 m/s, 1 m/s climb, 2 rad/s heading rate, 30 deg tilt (indoor use).
"""

from __future__ import annotations

import math

from vehicles.quadrotor.inertia import x_frame_inertia
from vehicles.quadrotor.params import ControllerGains, QuadrotorParams

__all__ = ["PARAMS", "GAINS"]

ARM_LENGTH = 0.0397  # m
RPM_TO_RAD_S = 2.0 * math.pi / 60.0

GAINS = ControllerGains(
    pos_p_xy=1.0, pos_p_z=1.5,
    vel_p_xy=2.5, vel_p_z=3.0, vel_i_xy=0.5, vel_i_z=1.0, vel_i_limit=3.0,
    att_p_rp=10.0, att_p_yaw=3.0,
    rate_p_rp=30.0, rate_p_yaw=10.0,
    max_rate_rp=6.0, max_rate_yaw=2.0,
    tilt_margin=math.radians(3.0),
)

PARAMS = QuadrotorParams(
    name="crazyflie",
    mass=0.027,
    arm_length=ARM_LENGTH,
    inertia=x_frame_inertia(hub_mass=0.015, hub_size=(0.05, 0.05, 0.015), rotor_mass=0.003, arm_length=ARM_LENGTH),
    k_f=3.16e-10 / RPM_TO_RAD_S**2,
    k_m=7.94e-12 / RPM_TO_RAD_S**2,
    motor_time_constant=0.015,
    rotor_speed_min=300.0,
    rotor_speed_max=math.sqrt(2.25 * 0.027 * 9.81 / (4.0 * 3.16e-10)) * RPM_TO_RAD_S,
    rotor_radius=2.31348e-2,
    drag_linear=(5.6e-3, 5.6e-3, 6.3e-3),
    drag_quadratic=(6e-4, 6e-4, 1.5e-3),
    body_half_extents=(0.06, 0.06, 0.0125),
    tilt_max=math.radians(30.0),
    max_speed=3.0,
    max_climb_rate=1.0,
    max_heading_rate=2.0,
    gains=GAINS,
)
