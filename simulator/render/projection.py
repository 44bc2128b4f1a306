"""Pinhole cameras in the OpenGL convention PyBullet uses, and the projection of world points to pixels.

A :class:`CameraView` holds an eye, a look-at point and an up vector in the world frame (ENU, m) and a vertical field
of view. Its view matrix ``V`` (world → camera, camera looking down its -z axis) and projection matrix ``P`` are the
ones ``p.computeViewMatrix`` / ``p.computeProjectionMatrixFOV`` build (the tests check this entry by entry); PyBullet
passes them as 16 floats in column-major order, so ``V = np.reshape(m, (4, 4)).T``.

A world point ``p_W`` maps to clip coordinates ``c = P V [p_W, 1]``, normalised device coordinates ``n = c[:3] / c[3]``
and pixel coordinates (origin at the image's top-left corner, ``u`` right, ``v`` down, a pixel ``(i, j)`` covering
``[i, i+1) x [j, j+1)``)::

    u = (n_x + 1) W / 2,        v = (1 - n_y) H / 2.

For a camera at the origin looking along +x with +z up this is the pinhole model ``u = W/2 - f y / x``,
``v = H/2 - f z / x`` with focal length ``f = H / (2 tan(vfov / 2))`` pixels.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

__all__ = ["CameraView", "look_at", "perspective", "project", "from_gl", "to_gl"]


def look_at(eye_W: np.ndarray, target_W: np.ndarray, up_W: np.ndarray) -> np.ndarray:
    """View matrix (4, 4) taking world points into the camera frame (x right, y up, looking along -z), as gluLookAt.

    ``f = (target - eye)/|.|``, ``s = f × up / |.|``, ``u = s × f``; rows ``[s; u; -f]`` and translation ``-R eye``.
    """
    eye = np.asarray(eye_W, dtype=float)
    f = np.asarray(target_W, dtype=float) - eye
    norm = np.linalg.norm(f)
    if norm == 0.0:
        raise ValueError("look_at: eye and target coincide")
    f = f / norm
    s = np.cross(f, np.asarray(up_W, dtype=float))
    ns = np.linalg.norm(s)
    if ns < 1e-9:
        raise ValueError("look_at: up vector is parallel to the viewing direction")
    s = s / ns
    u = np.cross(s, f)
    V = np.eye(4)
    V[0, :3], V[1, :3], V[2, :3] = s, u, -f
    V[:3, 3] = -V[:3, :3] @ eye
    return V


def perspective(vfov: float, aspect: float, near: float, far: float) -> np.ndarray:
    """OpenGL perspective matrix (4, 4) for a vertical field of view ``vfov`` (rad) and ``aspect`` = width / height."""
    if not 0.0 < vfov < np.pi:
        raise ValueError(f"perspective: vfov must be in (0, pi) rad, got {vfov}")
    if not 0.0 < near < far:
        raise ValueError(f"perspective: need 0 < near < far, got near={near}, far={far}")
    t = 1.0 / np.tan(vfov / 2.0)
    P = np.zeros((4, 4))
    P[0, 0] = t / aspect
    P[1, 1] = t
    P[2, 2] = (far + near) / (near - far)
    P[2, 3] = 2.0 * far * near / (near - far)
    P[3, 2] = -1.0
    return P


def from_gl(m: tuple[float, ...] | list[float]) -> np.ndarray:
    """A (4, 4) matrix from PyBullet's 16 column-major floats."""
    return np.asarray(m, dtype=float).reshape(4, 4).T


def to_gl(M: np.ndarray) -> list[float]:
    """PyBullet's 16 column-major floats from a (4, 4) matrix."""
    return np.asarray(M, dtype=float).T.ravel().tolist()


def project(points_W: np.ndarray, view: np.ndarray, proj: np.ndarray, width: int,
            height: int) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (N, 2) of world points (N, 3) and a mask (N,) of points in front of the camera.

    Points behind the camera (clip ``w <= 0``) get NaN pixels and a False mask; points outside the image but in
    front keep their (out-of-range) pixel coordinates so lines through them still clip correctly.
    """
    pts = np.atleast_2d(np.asarray(points_W, dtype=float))
    homo = np.concatenate([pts, np.ones((len(pts), 1))], axis=1)
    clip = homo @ (proj @ view).T
    w = clip[:, 3]
    front = w > 1e-9
    uv = np.full((len(pts), 2), np.nan)
    ndc = clip[front, :2] / w[front, None]
    uv[front, 0] = (ndc[:, 0] + 1.0) * 0.5 * width
    uv[front, 1] = (1.0 - ndc[:, 1]) * 0.5 * height
    return uv, front


@dataclass(frozen=True, kw_only=True)
class CameraView:
    """Where a camera is and what it sees.

    Attributes
    ----------
    eye_W : np.ndarray
        Camera position in the world frame (3,), m.
    target_W : np.ndarray
        Point the optical axis passes through (3,), m.
    up_W : np.ndarray
        World direction that appears up in the image (3,), not parallel to the optical axis.
    vfov : float
        Vertical field of view, rad, in (0, pi).
    near, far : float
        Clipping distances along the optical axis, m, 0 < near < far.
    """

    eye_W: np.ndarray
    target_W: np.ndarray
    up_W: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    vfov: float = np.deg2rad(50.0)
    near: float = 0.5
    far: float = 5000.0

    def __post_init__(self) -> None:
        for name in ("eye_W", "target_W", "up_W"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"CameraView.{name} must be a finite (3,) vector, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)
        if not 0.0 < self.vfov < np.pi:
            raise ValueError(f"CameraView.vfov must be in (0, pi) rad, got {self.vfov}")
        if not 0.0 < self.near < self.far:
            raise ValueError(f"CameraView.near/far must satisfy 0 < near < far, got {self.near}, {self.far}")

    @cached_property
    def _view(self) -> np.ndarray:
        return look_at(self.eye_W, self.target_W, self.up_W)

    def view_matrix(self) -> np.ndarray:
        """World → camera (4, 4)."""
        return self._view.copy()

    def projection_matrix(self, width: int, height: int) -> np.ndarray:
        """Camera → clip (4, 4) for an image of ``width`` x ``height`` pixels."""
        return perspective(self.vfov, width / height, self.near, self.far)

    def project(self, points_W: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (N, 2) and in-front mask (N,) of world points (N, 3); see :func:`project`."""
        return project(points_W, self._view, self.projection_matrix(width, height), width, height)
