"""Large panel van (a Mercedes-Benz Sprinter / Ford Transit class vehicle, 3.5 t class, part loaded).

Sources (rounded; SI units):
- mass 3000 kg (kerb ~ 2.2 t, gross 3.5 t), wheelbase 3.67 m, track 1.72 m, length 5.93 m, width 2.02 m,
  height 2.60 m: Mercedes-Benz Sprinter (W907) 3.5 t standard-wheelbase data sheet.
- tyre 235/65 R16C: rolling radius 0.36 m; wheel + tyre + hub ~ 32 kg.
- CoG height 0.90 m (part loaded): Heydinger et al., SAE 1999-01-1336 (light trucks and vans 0.7-1.0 m).
- max road-wheel steering 33 deg (turning circle ~ 13.6 m), steering rate 0.5 rad/s at the road wheels.
- drive torque at the wheels ~ 360 N m x 4.4 x 3.9 ~ 6200 N m (5500 N m used); brake torque to lock on dry
  asphalt mu m g r ~ 0.9 x 3000 x 9.81 x 0.36 ~ 9500 N m (9000 N m used).
- acceleration up to 2.0 m/s^2, service braking up to 6 m/s^2; top speed 160 km/h.
- dry asphalt tyre friction 0.85 (commercial tyres); rolling resistance coefficient 0.012 -> 0.004 m.
"""

import math

from vehicles.car.params import CarParams

PARAMS = CarParams(
    name="van",
    mass=3000.0,
    wheelbase=3.67,
    track=1.72,
    length=5.93,
    width=2.02,
    height=2.60,
    ground_clearance=0.18,
    wheel_radius=0.36,
    wheel_mass=32.0,
    cog_height=0.90,
    max_steer=math.radians(33.0),
    max_steer_rate=0.5,
    max_drive_torque=5500.0,
    max_brake_torque=9000.0,
    max_accel=2.0,
    max_decel=6.0,
    max_speed=44.0,
    tyre_friction=0.85,
    rolling_friction=0.004,
)
