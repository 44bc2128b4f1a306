"""Rotation functions over stacks of UAVs. Quaternions are (x, y, z, w) like PyBullet; ``R_WB`` maps body to world
coordinates, ``v_W = R_WB @ v_B``.

:func:`quat_to_rotmat` and :func:`rotate_T` run every physics tick for every UAV, where numpy's per-call overhead on
3-vectors, not the arithmetic, sets the cost: they are compiled loops (numba), callable from Python and from the other
compiled kernels of the flight stack.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["quat_to_rotmat", "yaw_to_quat", "yaw_of", "tilt_of", "cross3", "rotate_T", "rotation_and_body_rates"]

_I1 = np.array([1, 2, 0])
_I2 = np.array([2, 0, 1])


@njit(cache=True)
def _quat_to_rotmat_into(q_WB: np.ndarray, R: np.ndarray) -> None:
    """Write the rotation matrices of the unit quaternions ``q_WB`` (N, 4), (x, y, z, w), into ``R`` (N, 3, 3)."""
    for i in range(q_WB.shape[0]):
        x, y, z, w = q_WB[i, 0], q_WB[i, 1], q_WB[i, 2], q_WB[i, 3]
        R[i, 0, 0] = 1.0 - 2.0 * (y * y + z * z)
        R[i, 0, 1] = 2.0 * (x * y - w * z)
        R[i, 0, 2] = 2.0 * (x * z + w * y)
        R[i, 1, 0] = 2.0 * (x * y + w * z)
        R[i, 1, 1] = 1.0 - 2.0 * (x * x + z * z)
        R[i, 1, 2] = 2.0 * (y * z - w * x)
        R[i, 2, 0] = 2.0 * (x * z - w * y)
        R[i, 2, 1] = 2.0 * (y * z + w * x)
        R[i, 2, 2] = 1.0 - 2.0 * (x * x + y * y)


@njit(cache=True)
def quat_to_rotmat(q_WB: np.ndarray) -> np.ndarray:
    """Rotation matrices ``R_WB`` (N, 3, 3) from unit quaternions (N, 4) in (x, y, z, w) order.

    .. math::  R = I + 2 w [v]_\\times + 2 [v]_\\times^2, \\quad v = (x, y, z)
    """
    R = np.empty((q_WB.shape[0], 3, 3))
    _quat_to_rotmat_into(q_WB, R)
    return R


def yaw_to_quat(yaw: np.ndarray) -> np.ndarray:
    """Quaternions (N, 4) xyzw of pure rotations by ``yaw`` (rad) about world z."""
    yaw = np.asarray(yaw, dtype=float)
    q = np.zeros((yaw.shape[0], 4))
    q[:, 2] = np.sin(0.5 * yaw)
    q[:, 3] = np.cos(0.5 * yaw)
    return q


def yaw_of(R_WB: np.ndarray) -> np.ndarray:
    """Heading (N,) in rad: the azimuth of the body x axis, ``atan2(R[1,0], R[0,0])``."""
    return np.arctan2(R_WB[:, 1, 0], R_WB[:, 0, 0])


def tilt_of(R_WB: np.ndarray) -> np.ndarray:
    """Angle (N,) in rad between body z and world z: ``arccos(R[2,2])``."""
    return np.arccos(np.clip(R_WB[:, 2, 2], -1.0, 1.0))


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (N, 3) stacks (cheaper than ``np.cross`` for small N)."""
    return a.take(_I1, axis=1) * b.take(_I2, axis=1) - a.take(_I2, axis=1) * b.take(_I1, axis=1)


@njit(cache=True)
def _rotate_T_into(R_WB: np.ndarray, v_W: np.ndarray, out: np.ndarray) -> None:
    """Write ``R_WB^T v_W`` row-wise into ``out`` (N, 3)."""
    for i in range(v_W.shape[0]):
        for j in range(3):
            out[i, j] = R_WB[i, 0, j] * v_W[i, 0] + R_WB[i, 1, j] * v_W[i, 1] + R_WB[i, 2, j] * v_W[i, 2]


@njit(cache=True)
def rotate_T(R_WB: np.ndarray, v_W: np.ndarray) -> np.ndarray:
    """``R_WB^T v_W`` row-wise: world vectors (N, 3) expressed in the body frame."""
    out = np.empty((v_W.shape[0], 3))
    _rotate_T_into(R_WB, v_W, out)
    return out


@njit(cache=True)
def rotation_and_body_rates(x: np.ndarray, R_WB: np.ndarray, omega_B: np.ndarray) -> None:
    """Fill ``R_WB`` (N, 3, 3) and ``omega_B`` (N, 3) from rows ``(p_W, q_WB, v_W, omega_W)`` (N, 13) of body states
    as PyBullet reports them (angular velocity in the world frame)."""
    _quat_to_rotmat_into(x[:, 3:7], R_WB)
    _rotate_T_into(R_WB, x[:, 10:13], omega_B)
