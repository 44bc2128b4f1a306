"""Inner loops, run at the physics rate: attitude control (thrust axis first, then heading) and body-rate control."""

from __future__ import annotations

import numpy as np

from vehicles.quadrotor.controller import Controller
from vehicles.quadrotor.rotation import rotate_T, yaw_of
from vehicles.quadrotor.setpoints import AttitudeSetpoint, RateThrustSetpoint, WrenchSetpoint
from vehicles.quadrotor.stack import AirframeStack
from vehicles.quadrotor.state import FleetState

__all__ = ["AttitudeController", "RateController"]


class AttitudeController(Controller[AttitudeSetpoint, RateThrustSetpoint]):
    """Reduced-attitude (thrust axis) control with the heading corrected separately, and collective thrust.

    The thrust axis ``z = R e_3`` is turned towards the desired force direction ``z_d = F_W / |F_W|`` about their
    common normal, by the angle between them (the shortest rotation, so the tilt never passes outside the cone spanned
    by the current and desired axes); the heading error is corrected about body z with its own, lower gain, and the
    set-point's heading rate is fed forward (no heading lag in a steady turn). With ``F_B = R^T F_W`` (so that
    ``R^T (z \\times z_d) = e_3 \\times F_B / |F_B|``):

    .. math::

        h = \\sqrt{F_{B,x}^2 + F_{B,y}^2}, \\qquad \\theta = \\operatorname{atan2}(h,\\ F_{B,z}), \\qquad
        \\omega_{cmd} = \\mathrm{clip}\\Big(K_{rp}\\, \\theta\\, \\frac{(-F_{B,y},\\ F_{B,x},\\ 0)}{h}
            + K_\\psi\\, \\mathrm{wrap}(\\psi_d - \\psi)\\, e_3 + R^T e_3 \\dot\\psi_d,\\ \\pm\\omega_{max}\\Big),
        \\qquad T = \\max(F_{B,z},\\ 0).

    Decoupling the two errors is what gives the thrust direction priority over yaw: a large heading change (a UAV
    told to face a new direction) cannot tilt the body beyond its commanded tilt, which a single SO(3) error with
    unequal roll/pitch and yaw gains (Lee et al. 2010) can. An exactly inverted body (``z = -z_d``) has no defined
    turning axis and gets no tilt command.
    """

    def __init__(self, stack: AirframeStack) -> None:
        self._k_rp = stack.att_p[:, 0]
        self._k_yaw = stack.att_p[:, 2]
        self._max_rate = stack.max_rate
        self._min_rate = -stack.max_rate

    def update(self, setpoint: AttitudeSetpoint, state: FleetState) -> RateThrustSetpoint:
        R = state.R_WB
        F_B = rotate_T(R, setpoint.F_W)
        fx, fy, fz = F_B[:, 0], F_B[:, 1], F_B[:, 2]
        h = np.hypot(fx, fy)
        scale = self._k_rp * np.arctan2(h, fz) / np.maximum(h, 1e-12)
        e_yaw = np.remainder(setpoint.yaw - yaw_of(R) + np.pi, 2.0 * np.pi) - np.pi
        omega = R[:, 2, :] * setpoint.yaw_rate[:, None]
        omega[:, 0] -= fy * scale
        omega[:, 1] += fx * scale
        omega[:, 2] += self._k_yaw * e_yaw
        omega = np.minimum(np.maximum(omega, self._min_rate), self._max_rate)
        return RateThrustSetpoint(omega_B=omega, thrust=np.maximum(fz, 0.0))


class RateController(Controller[RateThrustSetpoint, WrenchSetpoint]):
    """Proportional body-rate loop with gyroscopic compensation.

    .. math::

        \\tau_B = J K_\\omega (\\omega_{cmd} - \\omega) + \\omega \\times J \\omega, \\qquad
        \\omega \\times J \\omega = \\big((J_z - J_y)\\omega_y\\omega_z,\\ (J_x - J_z)\\omega_z\\omega_x,\\
        (J_y - J_x)\\omega_x\\omega_y\\big)

    for the principal-axis (diagonal) inertia of the airframe.
    """

    _NEXT = np.array([1, 2, 0])
    _PREV = np.array([2, 0, 1])

    def __init__(self, stack: AirframeStack) -> None:
        J = stack.inertia
        self._JK = J * stack.rate_p
        self._gyro = J[:, self._PREV] - J[:, self._NEXT]

    def update(self, setpoint: RateThrustSetpoint, state: FleetState) -> WrenchSetpoint:
        w = state.omega_B
        tau = self._JK * (setpoint.omega_B - w) + self._gyro * w[:, self._NEXT] * w[:, self._PREV]
        return WrenchSetpoint(thrust=setpoint.thrust, torque_B=tau)
