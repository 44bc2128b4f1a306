"""The total external wrench on each airframe: rotor thrusts and reaction torques plus body drag, in the world frame."""

from __future__ import annotations

import numpy as np
from numba import njit

from vehicles.quadrotor.aero import body_drag_B
from vehicles.quadrotor.rotation import rotate_T

__all__ = ["total_wrench_W"]


@njit(cache=True)
def total_wrench_W(R_WB: np.ndarray, f: np.ndarray, f_nom: np.ndarray, alloc: np.ndarray, v_rel_W: np.ndarray,
                   c_lin: np.ndarray, c_quad: np.ndarray, F_W: np.ndarray, tau_W: np.ndarray,
                   total: np.ndarray) -> None:
    """Force and torque on every UAV about its centre of mass, world frame, and its collective rotor thrust, written
    into ``F_W``, ``tau_W`` and ``total``.

    .. math::

        F_W = R_{WB} \\big( (0, 0, \\textstyle\\sum_i f_i) + F_{d,B}(R_{WB}^T v_{rel,W}) \\big), \\qquad
        \\tau_W = R_{WB}\\, \\big( A_{\\tau_{xy}} f,\\ A_{\\tau_z} f_{nom} \\big)

    The roll and pitch torques come from the thrusts ``f`` the rotors deliver (ground effect included); the reaction
    torque about body z follows rotor speed, so it is taken from the nominal thrusts ``f_nom = k_f w^2`` (the two are
    equal out of ground effect).

    Parameters
    ----------
    R_WB : np.ndarray
        (N, 3, 3) attitudes.
    f, f_nom : np.ndarray
        (N, 4) delivered and nominal rotor thrusts (N).
    alloc : np.ndarray
        (N, 4, 4) allocation ``f -> (T, tau_x, tau_y, tau_z)`` (:class:`~vehicles.quadrotor.stack.AirframeStack`).
    v_rel_W : np.ndarray
        (N, 3) air-relative velocity (m/s).
    c_lin, c_quad : np.ndarray
        (N, 3) drag coefficients (:func:`~vehicles.quadrotor.aero.body_drag_B`).
    F_W, tau_W : np.ndarray
        (N, 3) outputs: force (N) and torque (N m).
    total : np.ndarray
        (N,) output: collective rotor thrust ``sum_i f_i`` (N).
    """
    drag_B = body_drag_B(rotate_T(R_WB, v_rel_W), c_lin, c_quad)
    for i in range(f.shape[0]):
        A = alloc[i]
        T = f[i, 0] + f[i, 1] + f[i, 2] + f[i, 3]
        tx = A[1, 0] * f[i, 0] + A[1, 1] * f[i, 1] + A[1, 2] * f[i, 2] + A[1, 3] * f[i, 3]
        ty = A[2, 0] * f[i, 0] + A[2, 1] * f[i, 1] + A[2, 2] * f[i, 2] + A[2, 3] * f[i, 3]
        tz = A[3, 0] * f_nom[i, 0] + A[3, 1] * f_nom[i, 1] + A[3, 2] * f_nom[i, 2] + A[3, 3] * f_nom[i, 3]
        Fx, Fy, Fz = drag_B[i, 0], drag_B[i, 1], drag_B[i, 2] + T
        for r in range(3):
            F_W[i, r] = R_WB[i, r, 0] * Fx + R_WB[i, r, 1] * Fy + R_WB[i, r, 2] * Fz
            tau_W[i, r] = R_WB[i, r, 0] * tx + R_WB[i, r, 1] * ty + R_WB[i, r, 2] * tz
        total[i] = T
