"""Motor mixer: collective thrust and body torque -> rotor speed commands, with saturation priorities."""

from __future__ import annotations

import numpy as np

from vehicles.quadrotor.controller import Controller
from vehicles.quadrotor.setpoints import RotorSpeedSetpoint, WrenchSetpoint
from vehicles.quadrotor.stack import AirframeStack, batched_matvec
from vehicles.quadrotor.state import FleetState

__all__ = ["MotorMixer"]


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
        self._s = s
        self._f_min = (s.k_f * s.rotor_speed_min**2)[:, None]
        self._f_max = (s.k_f * s.rotor_speed_max**2)[:, None]
        self._rp = s.shared(s.alloc_inv[:, :, 1:3])  # (N, 4, 2) or (4, 2)
        self._yaw = s.alloc_inv[:, :, 3]  # (N, 4)
        self._k_f = s.k_f[:, None]
        self._alloc_inv = s.shared(s.alloc_inv)
        self._wrench = np.zeros((s.n, 4))

    def update(self, setpoint: WrenchSetpoint, state: FleetState | None = None) -> RotorSpeedSetpoint:
        return RotorSpeedSetpoint(omega=np.sqrt(self.allocate(setpoint) / self._k_f))

    def allocate(self, setpoint: WrenchSetpoint) -> np.ndarray:
        """Rotor thrusts (N, 4) in newtons, within the rotor range, per the priorities above."""
        f_min, f_max = self._f_min, self._f_max
        wrench = self._wrench
        wrench[:, 0] = setpoint.thrust
        wrench[:, 1:] = setpoint.torque_B
        f = batched_matvec(self._alloc_inv, wrench)
        if not np.count_nonzero(f < f_min) and not np.count_nonzero(f > f_max):
            return f
        d = batched_matvec(self._rp, setpoint.torque_B[:, :2])
        d_lo, d_hi = d.min(axis=1, keepdims=True), d.max(axis=1, keepdims=True)
        span = d_hi - d_lo
        room = f_max - f_min
        scale = np.where(span > room, room / np.maximum(span, 1e-300), 1.0)
        d *= scale
        base = np.clip(setpoint.thrust[:, None] / 4.0, f_min - d_lo * scale, f_max - d_hi * scale)
        f = base + d
        c = self._yaw
        with np.errstate(divide="ignore", invalid="ignore"):
            up = np.where(c > 0, (f_max - f) / c, np.where(c < 0, (f_min - f) / c, np.inf))
            dn = np.where(c > 0, (f_min - f) / c, np.where(c < 0, (f_max - f) / c, -np.inf))
        tau_z = np.clip(setpoint.torque_B[:, 2], np.minimum(dn.max(axis=1), 0.0), np.maximum(up.min(axis=1), 0.0))
        f = f + c * tau_z[:, None]
        return np.clip(f, f_min, f_max)
