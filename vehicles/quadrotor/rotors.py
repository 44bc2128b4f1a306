"""Rotor actuators: first-order motor lag with speed saturation, thrust ``k_f w^2`` and reaction torque ``k_m w^2``."""

from __future__ import annotations

import numpy as np
from numba import njit

from vehicles.quadrotor.stack import AirframeStack

__all__ = ["RotorBank"]


@njit(cache=True)
def _lag_step(w: np.ndarray, w_cmd: np.ndarray, alpha: np.ndarray, w_max: np.ndarray, k_f: np.ndarray,
              thrust: np.ndarray) -> None:
    """Advance ``w`` (N, 4) in place by one exact first-order lag step, clip to ``[0, w_max]``; ``thrust = k_f w^2``."""
    for i in range(w.shape[0]):
        for j in range(4):
            x = w[i, j] + alpha[i] * (w_cmd[i, j] - w[i, j])
            x = min(max(x, 0.0), w_max[i])
            w[i, j] = x
            thrust[i, j] = k_f[i] * (x * x)


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
        self._alpha = 1.0 - np.exp(-dt / stack.motor_time_constant)
        self._w_max = stack.rotor_speed_max
        self._k_f = stack.k_f
        self.omega = np.array(omega0, dtype=float)
        """(N, 4) rotor speeds (rad/s)."""
        self.omega_cmd = self.omega.copy()
        """(N, 4) rotor speed commands from the mixer (rad/s)."""
        self._thrust = np.empty_like(self.omega)

    def step(self) -> np.ndarray:
        """Advance the motor lag by one physics step; return the nominal (out-of-ground-effect) thrusts (N, 4) in N.

        The returned array is the bank's own and is overwritten by the next step: copy it to keep it."""
        _lag_step(self.omega, self.omega_cmd, self._alpha, self._w_max, self._k_f, self._thrust)
        return self._thrust
