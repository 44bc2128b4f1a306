"""Inner loops, run at the physics rate: attitude control (thrust axis first, then heading) and body-rate control."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from vehicles.quadrotor.controller import Controller
from vehicles.quadrotor.setpoints import AttitudeSetpoint, RateThrustSetpoint, WrenchSetpoint
from vehicles.quadrotor.stack import AirframeStack
from vehicles.quadrotor.state import FleetState

__all__ = ["AttitudeController", "RateController"]


@njit(cache=True)
def _attitude_rates(R: np.ndarray, F_W: np.ndarray, yaw_d: np.ndarray, yaw_rate_d: np.ndarray, k_rp: np.ndarray,
                    k_yaw: np.ndarray, max_rate: np.ndarray, omega: np.ndarray, thrust: np.ndarray) -> None:
    """Body-rate commands ``omega`` (N, 3) and collective thrusts ``thrust`` (N,) of :class:`AttitudeController` (its
    equations), written into the given arrays."""
    for i in range(R.shape[0]):
        F0, F1, F2 = F_W[i, 0], F_W[i, 1], F_W[i, 2]
        fx = R[i, 0, 0] * F0 + R[i, 1, 0] * F1 + R[i, 2, 0] * F2
        fy = R[i, 0, 1] * F0 + R[i, 1, 1] * F1 + R[i, 2, 1] * F2
        fz = R[i, 0, 2] * F0 + R[i, 1, 2] * F1 + R[i, 2, 2] * F2
        h = math.hypot(fx, fy)
        scale = k_rp[i] * math.atan2(h, fz) / max(h, 1e-12)
        e_yaw = (yaw_d[i] - math.atan2(R[i, 1, 0], R[i, 0, 0]) + math.pi) % (2.0 * math.pi) - math.pi
        r = yaw_rate_d[i]
        w = (R[i, 2, 0] * r - fy * scale, R[i, 2, 1] * r + fx * scale, R[i, 2, 2] * r + k_yaw[i] * e_yaw)
        for j in range(3):
            omega[i, j] = min(max(w[j], -max_rate[i, j]), max_rate[i, j])
        thrust[i] = max(fz, 0.0)


@njit(cache=True)
def _rate_torques(omega_cmd: np.ndarray, omega: np.ndarray, JK: np.ndarray, J: np.ndarray, tau: np.ndarray) -> None:
    """Body torques ``tau`` (N, 3) of :class:`RateController` (its equation), written into the given array."""
    for i in range(omega.shape[0]):
        wx, wy, wz = omega[i, 0], omega[i, 1], omega[i, 2]
        Jx, Jy, Jz = J[i, 0], J[i, 1], J[i, 2]
        tau[i, 0] = JK[i, 0] * (omega_cmd[i, 0] - wx) + (Jz - Jy) * wy * wz
        tau[i, 1] = JK[i, 1] * (omega_cmd[i, 1] - wy) + (Jx - Jz) * wz * wx
        tau[i, 2] = JK[i, 2] * (omega_cmd[i, 2] - wz) + (Jy - Jx) * wx * wy


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
        self._k_rp = np.ascontiguousarray(stack.att_p[:, 0])
        self._k_yaw = np.ascontiguousarray(stack.att_p[:, 2])
        self._max_rate = stack.max_rate
        self._out = RateThrustSetpoint(omega_B=np.zeros((stack.n, 3)), thrust=np.zeros(stack.n))

    def update(self, setpoint: AttitudeSetpoint, state: FleetState) -> RateThrustSetpoint:
        out = self._out
        _attitude_rates(state.R_WB, setpoint.F_W, setpoint.yaw, setpoint.yaw_rate, self._k_rp, self._k_yaw,
                        self._max_rate, out.omega_B, out.thrust)
        return out


class RateController(Controller[RateThrustSetpoint, WrenchSetpoint]):
    """Proportional body-rate loop with gyroscopic compensation.

    .. math::

        \\tau_B = J K_\\omega (\\omega_{cmd} - \\omega) + \\omega \\times J \\omega, \\qquad
        \\omega \\times J \\omega = \\big((J_z - J_y)\\omega_y\\omega_z,\\ (J_x - J_z)\\omega_z\\omega_x,\\
        (J_y - J_x)\\omega_x\\omega_y\\big)

    for the principal-axis (diagonal) inertia of the airframe.
    """

    def __init__(self, stack: AirframeStack) -> None:
        self._J = stack.inertia
        self._JK = stack.inertia * stack.rate_p
        self._out = WrenchSetpoint(thrust=np.zeros(stack.n), torque_B=np.zeros((stack.n, 3)))

    def update(self, setpoint: RateThrustSetpoint, state: FleetState) -> WrenchSetpoint:
        out = self._out
        _rate_torques(setpoint.omega_B, state.omega_B, self._JK, self._J, out.torque_B)
        out.thrust = setpoint.thrust
        return out
