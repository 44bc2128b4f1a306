"""Outer loops, run at ``outer_loop_hz``: velocity -> acceleration -> thrust vector and attitude set-point."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from vehicles.quadrotor.aero import body_drag_B
from vehicles.quadrotor.controller import Controller
from vehicles.quadrotor.params import GRAVITY
from vehicles.quadrotor.rotation import cross3, rotate_T
from vehicles.quadrotor.setpoints import AccelerationSetpoint, AttitudeSetpoint, VelocitySetpoint
from vehicles.quadrotor.stack import AirframeStack
from vehicles.quadrotor.state import FleetState

__all__ = ["VelocityController", "ThrustVectorController", "attitude_from_thrust", "MIN_THRUST_FRACTION",
           "THRUST_HEADROOM"]

_ONES3 = np.ones(3)

MIN_THRUST_FRACTION = 0.2
"""Smallest vertical rotor force the thrust-vector stage commands, as a fraction of the weight (-)."""

THRUST_HEADROOM = 0.85
"""Fraction of the maximum total thrust the thrust-vector stage may use, leaving the rest for attitude control (-)."""


@njit(cache=True)
def _velocity_loop(v_d: np.ndarray, a_ff: np.ndarray, v_W: np.ndarray, R_WB: np.ndarray, integral: np.ndarray,
                   freeze: np.ndarray, vel_p: np.ndarray, ki_dt: np.ndarray, band: np.ndarray, lim: np.ndarray,
                   c_lin: np.ndarray, c_quad: np.ndarray, mass: np.ndarray, a_W: np.ndarray) -> None:
    """Acceleration set-points ``a_W`` (N, 3) of :class:`VelocityController`, written into the given array; updates
    ``integral`` in place."""
    drag_B = body_drag_B(rotate_T(R_WB, v_W), c_lin, c_quad)  # the force drag exerts; the loop cancels it
    for i in range(v_W.shape[0]):
        for j in range(3):
            e = v_d[i, j] - v_W[i, j]
            if abs(e) <= band[i] and not freeze[i]:
                integral[i, j] = min(max(integral[i, j] + ki_dt[i, j] * e, -lim[i]), lim[i])
            a_drag = -(R_WB[i, j, 0] * drag_B[i, 0] + R_WB[i, j, 1] * drag_B[i, 1] + R_WB[i, j, 2] * drag_B[i, 2])
            a_W[i, j] = a_ff[i, j] + vel_p[i, j] * e + integral[i, j] + a_drag / mass[i]


@njit(cache=True)
def _thrust_vector(a_W: np.ndarray, mass: np.ndarray, weight: np.ndarray, f_max: np.ndarray, tan_tilt: np.ndarray,
                   F: np.ndarray, requested: np.ndarray, saturated: np.ndarray) -> None:
    """Desired rotor forces ``F`` (N, 3) of :class:`ThrustVectorController`; fills ``requested`` (N, 2) with the
    unshortened (horizontal, vertical) force and ``saturated`` (N,) with whether it was shortened."""
    for i in range(a_W.shape[0]):
        fx, fy = a_W[i, 0] * mass[i], a_W[i, 1] * mass[i]
        fz = min(max(a_W[i, 2] * mass[i] + weight[i], MIN_THRUST_FRACTION * weight[i]), f_max[i])
        h = math.hypot(fx, fy)
        requested[i, 0], requested[i, 1] = h, fz
        h_max = min(fz * tan_tilt[i], math.sqrt(max(f_max[i] ** 2 - fz**2, 0.0)))
        saturated[i] = h > h_max
        if saturated[i]:
            k = min(h_max / max(h, 1e-12), 1.0)
            fx, fy = fx * k, fy * k
        F[i, 0], F[i, 1], F[i, 2] = fx, fy, fz


class VelocityController(Controller[VelocitySetpoint, AccelerationSetpoint]):
    """PI velocity loop with drag cancellation.

    .. math::

        a_W = a_{ff} + K_p (v_d - v) + \\int K_i (v_d - v)\\,dt + \\frac{1}{m} R_{WB} D(R_{WB}^T v),

    where ``D(v_B) = c_1 v_B + c_2 |v_B| v_B`` (per body axis) is the still-air drag at the measured velocity, so that
    in still air the closed loop is ``dv/dt = a_ff + K_p (v_d - v)`` while the thrust is not saturated; the integral
    takes up the drag of the wind. The integral is clamped to ``vel_i_limit`` per axis; it accumulates an error
    component only while that component is within ``vel_i_band`` and the UAV's thrust vector was not saturated at the
    previous step (conditional integration against wind-up).

    Parameters
    ----------
    stack : AirframeStack
        Gains and drag coefficients per UAV.
    dt : float
        Outer-loop period (s).
    """

    def __init__(self, stack: AirframeStack, dt: float) -> None:
        self._s = stack
        self._dt = dt
        self._integral = np.zeros((stack.n, 3))
        self._ki_dt = stack.vel_i * dt
        self.freeze = np.zeros(stack.n, dtype=bool)
        """(N,) UAVs whose integral is held this step (set by the fleet from the thrust-vector saturation)."""
        self._out = AccelerationSetpoint(a_W=np.zeros((stack.n, 3)), yaw=np.zeros(stack.n), yaw_rate=np.zeros(stack.n))

    def reset(self) -> None:
        self._integral[:] = 0.0

    def update(self, setpoint: VelocitySetpoint, state: FleetState) -> AccelerationSetpoint:
        s, out = self._s, self._out
        _velocity_loop(setpoint.v_W, setpoint.a_ff_W, state.v_W, state.R_WB, self._integral, self.freeze, s.vel_p,
                       self._ki_dt, s.vel_i_band, s.vel_i_limit, s.drag_linear, s.drag_quadratic, s.mass, out.a_W)
        out.yaw, out.yaw_rate = setpoint.yaw, setpoint.yaw_rate
        return out


class ThrustVectorController(Controller[AccelerationSetpoint, AttitudeSetpoint]):
    """Acceleration -> desired rotor force and attitude, with tilt limit and vertical priority.

    ``F = m (a + g e_3)``; the vertical part is kept above ``MIN_THRUST_FRACTION m g``; the horizontal part is
    shortened so the tilt stays within ``tilt_max - tilt_margin`` and the magnitude within
    ``THRUST_HEADROOM * max thrust`` (vertical first). The attitude set-point is the force (its direction is the
    desired thrust axis) and the heading (:func:`attitude_from_thrust` gives the full rotation they define).

    Attributes
    ----------
    saturated : np.ndarray
        (N,) bool, UAVs whose horizontal force was shortened at the last update.
    """

    def __init__(self, stack: AirframeStack) -> None:
        s = stack
        self._s = s
        self._tan_tilt = np.tan(s.tilt_max - s.tilt_margin)
        self._weight = s.mass * GRAVITY
        self._f_max = THRUST_HEADROOM * 4.0 * s.k_f * s.rotor_speed_max**2
        self.saturated = np.zeros(s.n, dtype=bool)
        self._requested = np.zeros((s.n, 2))
        self._out = AttitudeSetpoint(F_W=np.zeros((s.n, 3)), yaw=np.zeros(s.n), yaw_rate=np.zeros(s.n))

    @property
    def tilt_limit(self) -> np.ndarray:
        """(N,) largest commanded tilt (rad)."""
        return np.arctan(self._tan_tilt)

    @property
    def requested_tilt(self) -> np.ndarray:
        """(N,) tilt the unshortened force of the last update would have needed (rad)."""
        return np.arctan2(self._requested[:, 0], self._requested[:, 1])

    def update(self, setpoint: AccelerationSetpoint, state: FleetState) -> AttitudeSetpoint:
        out = self._out
        _thrust_vector(setpoint.a_W, self._s.mass, self._weight, self._f_max, self._tan_tilt, out.F_W,
                       self._requested, self.saturated)
        out.yaw, out.yaw_rate = setpoint.yaw, setpoint.yaw_rate
        return out


def attitude_from_thrust(F_W: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """Desired ``R_WB`` (N, 3, 3) whose z axis is along ``F_W`` (N, 3) and whose body x axis has heading ``yaw`` (N,).

    ``b_3 = F/|F|``, ``b_1 = y_c x b_3 / |y_c x b_3|`` with ``y_c = (-sin psi, cos psi, 0)``, ``b_2 = b_3 x b_1``.
    Since ``b_1`` is orthogonal to ``y_c``, its horizontal projection points exactly along ``psi`` whatever the tilt
    (Lee et al. 2010 project ``(cos psi, sin psi, 0)`` instead, which turns the heading when the body is tilted both
    forward and sideways, as in a fast turn).
    """
    b3 = F_W / np.sqrt(np.square(F_W).dot(_ONES3))[:, None]
    c, s = np.cos(yaw), np.sin(yaw)
    # y_c x b3 = (c b3z, s b3z, -(c b3x + s b3y)); its norm is sqrt(b3z^2 + (c b3x + s b3y)^2).
    along = c * b3[:, 0] + s * b3[:, 1]
    inv = 1.0 / np.hypot(b3[:, 2], along)
    R = np.empty((F_W.shape[0], 3, 3))
    b1 = R[:, :, 0]
    b1[:, 0] = c * b3[:, 2] * inv
    b1[:, 1] = s * b3[:, 2] * inv
    b1[:, 2] = -along * inv
    R[:, :, 1] = cross3(b3, b1)
    R[:, :, 2] = b3
    return R
