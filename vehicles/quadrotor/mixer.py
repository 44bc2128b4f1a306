"""Motor mixer: collective thrust and body torque -> rotor speed commands, with saturation priorities."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from vehicles.quadrotor.controller import Controller
from vehicles.quadrotor.setpoints import RotorSpeedSetpoint, WrenchSetpoint
from vehicles.quadrotor.stack import AirframeStack
from vehicles.quadrotor.state import FleetState

__all__ = ["MotorMixer"]


@njit(cache=True)
def _saturate(f: np.ndarray, d: np.ndarray, A: np.ndarray, T: float, tx: float, ty: float, tz: float,
              lo: float, hi: float) -> None:
    """Overwrite the infeasible thrusts ``f`` (4,) of one UAV by the prioritised allocation; ``d`` is scratch."""
    # 1. roll/pitch differential thrusts, scaled down only if their spread exceeds the rotor range.
    for j in range(4):
        d[j] = A[j, 1] * tx + A[j, 2] * ty
    d_lo, d_hi = d.min(), d.max()
    span, room = d_hi - d_lo, hi - lo
    scale = room / span if span > room else 1.0
    base = min(max(0.25 * T, lo - d_lo * scale), hi - d_hi * scale)
    # 2. yaw last, clipped to the interval that keeps every rotor in range.
    up, dn = math.inf, -math.inf
    for j in range(4):
        f[j] = base + d[j] * scale
        c = A[j, 3]
        if c > 0:
            up, dn = min(up, (hi - f[j]) / c), max(dn, (lo - f[j]) / c)
        elif c < 0:
            up, dn = min(up, (lo - f[j]) / c), max(dn, (hi - f[j]) / c)
    tau_z = min(max(tz, min(dn, 0.0)), max(up, 0.0))
    for j in range(4):
        f[j] = min(max(f[j] + A[j, 3] * tau_z, lo), hi)


@njit(cache=True)
def _allocate(thrust: np.ndarray, torque_B: np.ndarray, alloc_inv: np.ndarray, f_min: np.ndarray,
              f_max: np.ndarray, k_f: np.ndarray, out: np.ndarray, omega: np.ndarray) -> None:
    """Rotor thrusts ``out`` (N, 4) of :meth:`MotorMixer.allocate` (the priorities in :class:`MotorMixer`) and the
    rotor speeds ``omega = sqrt(f / k_f)`` (N, 4) that give them, written into the given arrays."""
    n = thrust.shape[0]
    f = np.empty(4)
    d = np.empty(4)
    for i in range(n):
        T, tx, ty, tz = thrust[i], torque_B[i, 0], torque_B[i, 1], torque_B[i, 2]
        lo, hi = f_min[i], f_max[i]
        A = alloc_inv[i]
        feasible = True
        for j in range(4):
            f[j] = A[j, 0] * T + A[j, 1] * tx + A[j, 2] * ty + A[j, 3] * tz
            feasible = feasible and lo <= f[j] <= hi
        if not feasible:
            _saturate(f, d, A, T, tx, ty, tz, lo, hi)
        for j in range(4):
            out[i, j] = f[j]
            omega[i, j] = math.sqrt(f[j] / k_f[i])


class MotorMixer(Controller[WrenchSetpoint, RotorSpeedSetpoint]):
    """Allocate ``(T, tau_B)`` to rotor thrusts ``f`` in ``[k_f w_min^2, k_f w_max^2]``; ``w = sqrt(f / k_f)``.

    The X-frame allocation ``[T, tau_x, tau_y, tau_z]^T = A f`` (rows ``1``, ``y_i``, ``-x_i``, ``-s_i k_m/k_f``) is
    inverted exactly when the result is within every rotor's range. Otherwise, in order of priority:

    1. roll/pitch: their differential thrusts ``d = A^{-1}[0, tau_x, tau_y, 0]`` are scaled down only if their spread
       exceeds the rotor range, and the collective ``T/4`` is shifted so every ``T/4 + d_i`` fits (attitude before
       collective thrust);
    2. yaw last: ``tau_z`` is clipped to the interval that keeps every rotor within its range (thrust priority over
       yaw).
    """

    def __init__(self, stack: AirframeStack) -> None:
        s = stack
        self._f_min = s.k_f * s.rotor_speed_min**2
        self._f_max = s.k_f * s.rotor_speed_max**2
        self._k_f = s.k_f
        self._alloc_inv = s.alloc_inv
        self._f = np.zeros((s.n, 4))
        self._out = RotorSpeedSetpoint(omega=np.zeros((s.n, 4)))

    def update(self, setpoint: WrenchSetpoint, state: FleetState | None = None) -> RotorSpeedSetpoint:
        self.allocate(setpoint)
        return self._out

    def allocate(self, setpoint: WrenchSetpoint) -> np.ndarray:
        """Rotor thrusts (N, 4) in newtons, within the rotor range, per the priorities above (the mixer's own array,
        overwritten at the next call, like the rotor speeds of :meth:`update`)."""
        _allocate(setpoint.thrust, setpoint.torque_B, self._alloc_inv, self._f_min, self._f_max, self._k_f, self._f,
                  self._out.omega)
        return self._f
