"""Mid-size sedan (a VW Passat / Toyota Camry class car).

Sources (rounded; SI units):
- mass 1500 kg, wheelbase 2.79 m, track 1.58 m, length 4.77 m, width 1.83 m, height 1.47 m: VW Passat B8 and
  Toyota Camry XV70 manufacturer data sheets (kerb weight 1.4-1.6 t).
- tyre 215/55 R17: rolling radius 0.32 m; wheel + tyre + hub ~ 22 kg.
- CoG height 0.55 m: Heydinger et al., "Measured vehicle inertial parameters - NHTSA's data through November 1998",
  SAE 1999-01-1336 (passenger cars 0.50-0.58 m).
- max road-wheel steering 35 deg (turning circle ~ 11 m), steering rate ~ 0.6 rad/s at the road wheels
  (about 500 deg/s at the hand wheel with a 15:1 ratio, an emergency manoeuvre).
- drive torque at the wheels 250 N m x 1st gear 3.6 x final drive 3.5 ~ 3150 N m; brakes able to lock the wheels on dry
  asphalt: mu m g r ~ 0.9 x 1500 x 9.81 x 0.32 ~ 4240 N m (4800 N m used).
- 0-100 km/h in ~ 9 s: mean 3.1 m/s^2 (3.0 used); service braking up to 7 m/s^2 (full stop ~ 9 m/s^2).
- dry asphalt tyre friction 0.9 (Pacejka, Tire and Vehicle Dynamics, 3rd ed., ch. 1); rolling resistance
  coefficient 0.01 -> rolling friction 0.01 x r ~ 0.003 m.
"""

import math

from vehicles.car.params import CarParams

PARAMS = CarParams(
    name="sedan",
    mass=1500.0,
    wheelbase=2.79,
    track=1.58,
    length=4.77,
    width=1.83,
    height=1.47,
    ground_clearance=0.15,
    wheel_radius=0.32,
    wheel_mass=22.0,
    cog_height=0.55,
    max_steer=math.radians(35.0),
    max_steer_rate=0.6,
    max_drive_torque=3150.0,
    max_brake_torque=4800.0,
    max_accel=3.0,
    max_decel=7.0,
    max_speed=55.0,
    tyre_friction=0.9,
    rolling_friction=0.003,
)
