"""Outer loops, run at ``outer_loop_hz``: velocity -> acceleration -> thrust vector and attitude set-point."""

from __future__ import annotations

import numpy as np

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
        self._band = stack.vel_i_band[:, None]
        self._lim = stack.vel_i_limit[:, None]
        self.freeze = np.zeros(stack.n, dtype=bool)
        """(N,) UAVs whose integral is held this step (set by the fleet from the thrust-vector saturation)."""

    def _not_frozen_col(self) -> np.ndarray:
        return ~self.freeze[:, None]

    def reset(self) -> None:
        self._integral[:] = 0.0

    def update(self, setpoint: VelocitySetpoint, state: FleetState) -> AccelerationSetpoint:
        s = self._s
        e = setpoint.v_W - state.v_W
        accumulate = (np.abs(e) <= self._band) & self._not_frozen_col()
        self._integral = np.minimum(np.maximum(self._integral + self._ki_dt * e * accumulate, -self._lim), self._lim)
        v_B = rotate_T(state.R_WB, state.v_W)
        drag_B = s.drag_linear * v_B + s.drag_quadratic * np.abs(v_B) * v_B
        a_drag_W = np.matmul(state.R_WB, drag_B[:, :, None])[:, :, 0] / s.mass[:, None]
        a_W = setpoint.a_ff_W + s.vel_p * e + self._integral + a_drag_W
        return AccelerationSetpoint(a_W=a_W, yaw=setpoint.yaw, yaw_rate=setpoint.yaw_rate)


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
        self._f_max2 = self._f_max**2
        self.saturated = np.zeros(s.n, dtype=bool)
        self._requested = np.zeros((s.n, 2))

    @property
    def tilt_limit(self) -> np.ndarray:
        """(N,) largest commanded tilt (rad)."""
        return np.arctan(self._tan_tilt)

    @property
    def requested_tilt(self) -> np.ndarray:
        """(N,) tilt the unshortened force of the last update would have needed (rad)."""
        return np.arctan2(self._requested[:, 0], self._requested[:, 1])

    def update(self, setpoint: AccelerationSetpoint, state: FleetState) -> AttitudeSetpoint:
        F = setpoint.a_W * self._s.mass[:, None]
        F[:, 2] += self._weight
        F[:, 2] = np.minimum(np.maximum(F[:, 2], MIN_THRUST_FRACTION * self._weight), self._f_max)
        h = np.hypot(F[:, 0], F[:, 1])
        self._requested[:, 0], self._requested[:, 1] = h, F[:, 2]
        h_max = np.minimum(F[:, 2] * self._tan_tilt, np.sqrt(np.maximum(self._f_max2 - F[:, 2] ** 2, 0.0)))
        self.saturated = h > h_max
        if self.saturated.any():
            F[:, :2] *= np.minimum(h_max / np.maximum(h, 1e-12), 1.0)[:, None]
        return AttitudeSetpoint(F_W=F, yaw=setpoint.yaw, yaw_rate=setpoint.yaw_rate)


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
