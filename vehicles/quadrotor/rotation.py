"""Vectorised rotation functions over stacks of UAVs. Quaternions are (x, y, z, w) like PyBullet; ``R_WB`` maps body to
world coordinates, ``v_W = R_WB @ v_B``.

The functions are written as a few large numpy operations (constant matrices applied to stacked products) because they
run every physics tick for every UAV, where per-call overhead dominates.
"""

from __future__ import annotations

import numpy as np

__all__ = ["quat_to_rotmat", "yaw_to_quat", "yaw_of", "tilt_of", "cross3", "rotate_T"]


def _quat_products_to_R() -> tuple[np.ndarray, np.ndarray]:
    # Entries of R as linear combinations of the products q_a q_b (a, b in x, y, z, w -> 0..3) plus a constant.
    x, y, z, w = 0, 1, 2, 3
    terms = {
        0: [(-2, y, y), (-2, z, z)], 1: [(2, x, y), (-2, w, z)], 2: [(2, x, z), (2, w, y)],
        3: [(2, x, y), (2, w, z)], 4: [(-2, x, x), (-2, z, z)], 5: [(2, y, z), (-2, w, x)],
        6: [(2, x, z), (-2, w, y)], 7: [(2, y, z), (2, w, x)], 8: [(-2, x, x), (-2, y, y)],
    }
    M = np.zeros((16, 9))
    for k, combo in terms.items():
        for coef, a, b in combo:
            M[4 * a + b, k] += coef
    return M, np.eye(3).reshape(9)


_Q2R, _Q2R_CONST = _quat_products_to_R()

_I1 = np.array([1, 2, 0])
_I2 = np.array([2, 0, 1])


def quat_to_rotmat(q_WB: np.ndarray) -> np.ndarray:
    """Rotation matrices ``R_WB`` (N, 3, 3) from unit quaternions (N, 4) in (x, y, z, w) order.

    .. math::  R = I + 2 w [v]_\\times + 2 [v]_\\times^2, \\quad v = (x, y, z)
    """
    n = q_WB.shape[0]
    products = (q_WB[:, :, None] * q_WB[:, None, :]).reshape(n, 16)
    return (products.dot(_Q2R) + _Q2R_CONST).reshape(n, 3, 3)


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


def rotate_T(R_WB: np.ndarray, v_W: np.ndarray) -> np.ndarray:
    """``R_WB^T v_W`` row-wise: world vectors (N, 3) expressed in the body frame."""
    return np.matmul(v_W[:, None, :], R_WB)[:, 0, :]
