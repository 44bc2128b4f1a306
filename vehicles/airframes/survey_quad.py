"""Survey quadrotor: a 1.85 kg X-frame carrying a radar/camera payload, able to cruise at 15-20 m/s.

Sources and derivations (SI units throughout; rotor speeds in rad/s):

- Mass budget: hub (flight controller, 6S battery, payload) 1.25 kg, four motor + 12 in propeller sets at 0.10 kg,
  four carbon arms at 0.05 kg; total 1.85 kg. Arm length 0.25 m (a 500 mm-class frame).
- Inertia: closed form of :func:`vehicles.quadrotor.inertia.x_frame_inertia` with a 0.20 x 0.20 x 0.10 m hub box;
  gives (0.0198, 0.0198, 0.0375) kg m^2.
- Rotors: 12 x 4.5 in propellers (radius 0.152 m). APC static data give about 4.2 N at 6000 rpm (628 rad/s), hence
  k_f = 4.2 / 628^2 = 1.05e-5 N s^2/rad^2. The torque-to-thrust ratio of such propellers is about 0.015 m,
  hence k_m = 1.6e-7 N m s^2/rad^2.
- Motors: 0.04 s first-order time constant (typical for 12 in propellers on 400-600 kV motors); 1100 rad/s saturation
  gives a thrust-to-weight ratio of 4 * 1.05e-5 * 1100^2 / (1.85 * 9.81) = 2.8. Hover speed 657 rad/s.
- Drag: linear (rotor "H-force" / induced drag) 0.10 N s/m horizontally and 0.15 vertically; quadratic
  0.5 * rho * C_d * A with rho = 1.225 kg/m^3, C_d ~ 1, frontal area ~ 0.033 m^2 -> 0.020 N s^2/m^2 horizontally,
  plan-view area ~ 0.1 m^2 -> 0.06 vertically. At 20 m/s the horizontal drag is ~10 N, trimmed at ~29 deg of tilt;
  the 40 deg tilt limit (37 deg commanded) leaves ~2 m/s^2 of horizontal acceleration at that speed.
- Collision box: flat box spanning the rotor disks, half extents 0.33 x 0.33 x 0.05 m.
- Gains: rate loop crossover ~20 rad/s (phase margin ~50 deg against the 0.04 s motor lag); attitude loop ~7 rad/s;
  velocity loop ~2 rad/s; position loop ~1 rad/s: each loop 3-7 times slower than the one it drives.
"""

from __future__ import annotations

import math

from vehicles.quadrotor.inertia import x_frame_inertia
from vehicles.quadrotor.params import ControllerGains, QuadrotorParams

__all__ = ["PARAMS", "GAINS"]

ARM_LENGTH = 0.25  # m

GAINS = ControllerGains(
    pos_p_xy=1.0, pos_p_z=1.5,
    vel_p_xy=2.0, vel_p_z=3.0, vel_i_xy=0.4, vel_i_z=1.0, vel_i_limit=3.0,
    att_p_rp=7.0, att_p_yaw=2.5,
    rate_p_rp=20.0, rate_p_yaw=8.0,
    max_rate_rp=4.0, max_rate_yaw=1.5,
    tilt_margin=math.radians(3.0),
)

PARAMS = QuadrotorParams(
    name="survey_quad",
    mass=1.85,
    arm_length=ARM_LENGTH,
    inertia=x_frame_inertia(hub_mass=1.25, hub_size=(0.20, 0.20, 0.10), rotor_mass=0.10,
                            arm_length=ARM_LENGTH, arm_mass=0.05),
    k_f=1.05e-5,
    k_m=1.6e-7,
    motor_time_constant=0.04,
    rotor_speed_min=100.0,
    rotor_speed_max=1100.0,
    rotor_radius=0.152,
    drag_linear=(0.10, 0.10, 0.15),
    drag_quadratic=(0.020, 0.020, 0.06),
    body_half_extents=(0.33, 0.33, 0.05),
    tilt_max=math.radians(40.0),
    max_speed=20.0,
    max_climb_rate=5.0,
    max_heading_rate=1.0,
    gains=GAINS,
)
