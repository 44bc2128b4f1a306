"""Quadrotor airframe parameters and controller gains.

Rotor layout (X frame, body frame FLU): rotor ``i`` sits at azimuth ``theta_i = pi/4 + i*pi/2`` (front-left, rear-left,
rear-right, front-right) at distance ``arm_length`` from the centre of mass, in the plane of the centre of mass. Rotor
speeds are in rad/s (SI), so per-rotor thrust and reaction torque are

.. math::

    f_i = k_f \\omega_i^2, \\qquad \\tau_{z,i} = -s_i k_m \\omega_i^2,

with ``s_i = +1`` for a rotor spinning counter-clockwise seen from above (+z): its drag torque on the body is
about -z. Spins alternate ``(-1, +1, -1, +1)`` so that diagonal rotors share a direction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

__all__ = ["ControllerGains", "QuadrotorParams", "GRAVITY", "ROTOR_SPIN", "rotor_positions_B"]

GRAVITY = 9.81
"""Gravitational acceleration used for envelope checks (m/s^2); the physics client is set up with the same value."""

ROTOR_SPIN = np.array([-1.0, 1.0, -1.0, 1.0])
"""Spin direction ``s_i`` of rotors 0..3 (+1 = counter-clockwise seen from above)."""


def rotor_positions_B(arm_length: float) -> np.ndarray:
    """Rotor hub positions in the body frame (m), shape (4, 3), X layout with rotor 0 front-left."""
    theta = math.pi / 4 + np.arange(4) * math.pi / 2
    return np.stack([arm_length * np.cos(theta), arm_length * np.sin(theta), np.zeros(4)], axis=1)


def _positive(obj: object, *names: str) -> None:
    for name in names:
        value = getattr(obj, name)
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{type(obj).__name__}.{name} must be a finite number > 0, got {value!r}")


@dataclass(frozen=True, kw_only=True)
class ControllerGains:
    """Gains of the cascaded flight controller (position -> velocity -> thrust vector -> attitude -> rate -> mixer).

    Attributes
    ----------
    pos_p_xy : float
        Horizontal position gain, velocity set-point per metre of error (1/s).
    pos_p_z : float
        Vertical position gain (1/s); also holds altitude under a unicycle command.
    vel_p_xy : float
        Horizontal velocity gain, acceleration per m/s of error (1/s).
    vel_p_z : float
        Vertical velocity gain (1/s).
    vel_i_xy : float
        Horizontal velocity integral gain (1/s^2).
    vel_i_z : float
        Vertical velocity integral gain (1/s^2).
    vel_i_limit : float
        Bound on each component of the integral term (m/s^2).
    vel_i_band : float
        The integral accumulates a velocity-error component only while its magnitude is below this band (m/s), so
        large transients (steps, climbs) do not wind it up.
    att_p_rp : float
        Roll/pitch attitude gain, body-rate set-point per radian of error (1/s).
    att_p_yaw : float
        Yaw attitude gain (1/s); lower than roll/pitch so yaw yields to the thrust direction.
    rate_p_rp : float
        Roll/pitch rate gain, angular acceleration per rad/s of error (1/s).
    rate_p_yaw : float
        Yaw rate gain (1/s).
    max_rate_rp : float
        Bound on roll/pitch body-rate set-points (rad/s).
    max_rate_yaw : float
        Bound on the yaw body-rate set-point (rad/s).
    tilt_margin : float
        The thrust-vector stage commands at most ``tilt_max - tilt_margin`` so attitude transients stay inside the
        airframe's tilt limit (rad), >= 0.
    """

    pos_p_xy: float
    pos_p_z: float
    vel_p_xy: float
    vel_p_z: float
    vel_i_xy: float
    vel_i_z: float
    vel_i_limit: float
    att_p_rp: float
    att_p_yaw: float
    rate_p_rp: float
    rate_p_yaw: float
    max_rate_rp: float
    max_rate_yaw: float
    vel_i_band: float = 1.0
    tilt_margin: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"ControllerGains.{f.name} must be a finite number >= 0, got {value!r}")
        _positive(self, "pos_p_xy", "pos_p_z", "vel_p_xy", "vel_p_z", "vel_i_band", "att_p_rp", "att_p_yaw",
                  "rate_p_rp", "rate_p_yaw", "max_rate_rp", "max_rate_yaw")
        if self.att_p_rp >= self.rate_p_rp:
            raise ValueError(f"ControllerGains.att_p_rp ({self.att_p_rp}) must be below rate_p_rp ({self.rate_p_rp}): "
                             "the attitude loop must be slower than the rate loop it drives")


@dataclass(frozen=True, kw_only=True)
class QuadrotorParams:
    """Physical parameters, flight envelope and controller gains of one quadrotor airframe.

    Attributes
    ----------
    name : str
        Airframe name, e.g. ``"survey_quad"``.
    mass : float
        Total take-off mass (kg).
    arm_length : float
        Distance from the centre of mass to each rotor hub (m).
    inertia : tuple[float, float, float]
        Principal moments of inertia about body x, y, z (kg m^2); must satisfy the triangle inequalities.
    k_f : float
        Rotor thrust coefficient, ``f = k_f omega^2`` (N s^2 / rad^2).
    k_m : float
        Rotor drag-torque coefficient, ``tau = k_m omega^2`` (N m s^2 / rad^2).
    motor_time_constant : float
        First-order motor lag ``d omega / dt = (omega_cmd - omega) / tau_m`` (s).
    rotor_speed_min : float
        Lowest rotor speed the controller commands in flight (rad/s), >= 0.
    rotor_speed_max : float
        Rotor speed saturation (rad/s).
    rotor_radius : float
        Propeller radius (m); used by ground effect and downwash.
    drag_linear : tuple[float, float, float]
        Linear body drag ``-c1 * v_B`` per body axis (N s / m).
    drag_quadratic : tuple[float, float, float]
        Quadratic body drag ``-c2 * |v_B| * v_B`` per body axis (N s^2 / m^2).
    body_half_extents : tuple[float, float, float]
        Half extents of the collision box (m).
    tilt_max : float
        Largest tilt of the body z axis from world z that the controller commands (rad), in (0, pi/2).
    max_speed : float
        Largest horizontal speed set-point (m/s).
    max_climb_rate : float
        Largest vertical speed set-point, up or down (m/s).
    max_heading_rate : float
        Largest heading-rate set-point (rad/s).
    gains : ControllerGains
        Flight-controller gains for this airframe.
    """

    name: str
    mass: float
    arm_length: float
    inertia: tuple[float, float, float]
    k_f: float
    k_m: float
    motor_time_constant: float
    rotor_speed_min: float
    rotor_speed_max: float
    rotor_radius: float
    drag_linear: tuple[float, float, float]
    drag_quadratic: tuple[float, float, float]
    body_half_extents: tuple[float, float, float]
    tilt_max: float
    max_speed: float
    max_climb_rate: float
    max_heading_rate: float
    gains: ControllerGains

    MIN_THRUST_TO_WEIGHT = 1.2
    """Smallest accepted ratio of maximum total thrust to weight (-)."""

    def __post_init__(self) -> None:
        if not self.name:
            raise ValueError("QuadrotorParams.name must be a non-empty string")
        _positive(self, "mass", "arm_length", "k_f", "k_m", "motor_time_constant", "rotor_speed_max",
                  "rotor_radius", "tilt_max", "max_speed", "max_climb_rate", "max_heading_rate")
        for name in ("inertia", "drag_linear", "drag_quadratic", "body_half_extents"):
            arr = np.asarray(getattr(self, name), dtype=float)
            if arr.shape != (3,) or not np.all(np.isfinite(arr)):
                raise ValueError(f"QuadrotorParams.{name} must be 3 finite numbers, got {getattr(self, name)!r}")
            if name in ("inertia", "body_half_extents") and np.any(arr <= 0):
                raise ValueError(f"QuadrotorParams.{name} must be > 0 on every axis, got {getattr(self, name)!r}")
            if name.startswith("drag") and np.any(arr < 0):
                raise ValueError(f"QuadrotorParams.{name} must be >= 0 on every axis, got {getattr(self, name)!r}")
        ixx, iyy, izz = self.inertia
        if ixx + iyy < izz or iyy + izz < ixx or izz + ixx < iyy:
            raise ValueError(f"QuadrotorParams.inertia {self.inertia!r} violates the triangle inequality of a "
                             "rigid body")
        if not (0 <= self.rotor_speed_min < self.rotor_speed_max):
            raise ValueError(f"QuadrotorParams.rotor_speed_min must be in [0, rotor_speed_max={self.rotor_speed_max}), "
                             f"got {self.rotor_speed_min!r}")
        if not (self.tilt_max < math.pi / 2):
            raise ValueError(f"QuadrotorParams.tilt_max must be below pi/2 rad, got {self.tilt_max!r}")
        if self.gains.tilt_margin >= self.tilt_max:
            raise ValueError(f"ControllerGains.tilt_margin ({self.gains.tilt_margin}) must be below "
                             f"QuadrotorParams.tilt_max ({self.tilt_max})")
        if self.thrust_to_weight < self.MIN_THRUST_TO_WEIGHT:
            raise ValueError(f"QuadrotorParams.rotor_speed_max={self.rotor_speed_max} gives thrust-to-weight "
                             f"{self.thrust_to_weight:.3f} < {self.MIN_THRUST_TO_WEIGHT} (check mass, k_f)")
        if self.hover_rotor_speed <= self.rotor_speed_min:
            raise ValueError(f"QuadrotorParams.rotor_speed_min={self.rotor_speed_min} is above the hover rotor speed "
                             f"{self.hover_rotor_speed:.1f} rad/s")
        if self.rotor_radius >= self.arm_length / math.sqrt(2.0):
            raise ValueError(f"QuadrotorParams.rotor_radius={self.rotor_radius} m makes neighbouring propellers "
                             f"overlap (arm_length={self.arm_length} m)")

    @property
    def weight(self) -> float:
        """``m g`` (N)."""
        return self.mass * GRAVITY

    @property
    def max_total_thrust(self) -> float:
        """``4 k_f omega_max^2`` (N)."""
        return 4.0 * self.k_f * self.rotor_speed_max**2

    @property
    def thrust_to_weight(self) -> float:
        """Maximum total thrust over weight (-)."""
        return self.max_total_thrust / self.weight

    @property
    def hover_rotor_speed(self) -> float:
        """``sqrt(m g / (4 k_f))`` (rad/s)."""
        return math.sqrt(self.weight / (4.0 * self.k_f))

    @property
    def yaw_moment_ratio(self) -> float:
        """``k_m / k_f`` (m): reaction torque per newton of thrust."""
        return self.k_m / self.k_f
