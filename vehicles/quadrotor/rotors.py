"""Rotor actuators: first-order motor lag with speed saturation, thrust ``k_f w^2`` and reaction torque ``k_m w^2``."""

from __future__ import annotations

import numpy as np

from vehicles.quadrotor.stack import AirframeStack

__all__ = ["RotorBank"]


class RotorBank:
    """The 4 N rotors of a fleet.

    The lag ``dw/dt = (w_cmd - w) / tau_m`` is integrated exactly over one physics step (command held constant):

    .. math::  w_{k+1} = w_k + (1 - e^{-\\Delta t/\\tau_m}) (w_{cmd} - w_k),

    then clipped to ``[0, w_max]``.

    Parameters
    ----------
    stack : AirframeStack
        Rotor coefficients per UAV.
    dt : float
        Physics step (s).
    omega0 : np.ndarray
        (N, 4) initial rotor speeds (rad/s), also the initial commands.
    """

    def __init__(self, stack: AirframeStack, dt: float, omega0: np.ndarray) -> None:
        self._alpha = (1.0 - np.exp(-dt / stack.motor_time_constant))[:, None]
        self._w_max = stack.rotor_speed_max[:, None]
        self._k_f = stack.k_f[:, None]
        self.omega = np.array(omega0, dtype=float)
        """(N, 4) rotor speeds (rad/s)."""
        self.omega_cmd = self.omega.copy()
        """(N, 4) rotor speed commands from the mixer (rad/s)."""

    def step(self) -> np.ndarray:
        """Advance the motor lag by one physics step; return the nominal (out-of-ground-effect) thrusts (N, 4) in N."""
        w = self.omega
        w += self._alpha * (self.omega_cmd - w)
        np.minimum(np.maximum(w, 0.0, out=w), self._w_max, out=w)
        return self._k_f * (w * w)
