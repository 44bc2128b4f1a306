"""Camera rigs for replay videos: chase, orbit, top-down map and onboard, moved smoothly.

Each rig turns the scene's state at a frame (:class:`CameraInputs`) into a goal eye and look-at point; a
:class:`CriticalDamper` per point then follows the goal like a critically damped spring with time constant ``tau``::

    e'' = -2 w e' - w^2 e,      e = x - goal,   w = 1 / tau,

integrated exactly over each frame step ``dt`` for a goal held constant during the step::

    e(dt) = (e0 + (v0 + w e0) dt) exp(-w dt),      v(dt) = (v0 - w (v0 + w e0) dt) exp(-w dt).

It never overshoots a step in the goal and never blows up, whatever ``dt``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from simulator.render.projection import CameraView

__all__ = ["CameraInputs", "CameraRig", "ChaseCamera", "CriticalDamper", "OnboardCamera", "OrbitCamera",
           "TopDownCamera", "yaw_of"]

_Z = np.array([0.0, 0.0, 1.0])


def yaw_of(q_WB: np.ndarray) -> float:
    """Heading (rad, counter-clockwise from +x) of the body x axis of attitude ``q_WB`` (x, y, z, w)."""
    x, y, z, w = q_WB
    return float(np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))


class CriticalDamper:
    """A point following a moving goal with critically damped second-order dynamics (time constant ``tau``, s)."""

    def __init__(self, tau: float) -> None:
        if tau < 0:
            raise ValueError(f"CriticalDamper.tau must be >= 0 s, got {tau}")
        self.tau = float(tau)
        self.x: np.ndarray | None = None
        self.v: np.ndarray | None = None

    def update(self, goal: np.ndarray, dt: float) -> np.ndarray:
        """Advance ``dt`` s towards ``goal``; the first call (or ``tau == 0``) jumps onto the goal."""
        goal = np.asarray(goal, dtype=float)
        if self.x is None or self.tau == 0.0:
            self.x, self.v = goal.copy(), np.zeros_like(goal)
            return self.x.copy()
        w = 1.0 / self.tau
        e0, v0 = self.x - goal, self.v
        decay = np.exp(-w * dt)
        b = v0 + w * e0
        self.x = goal + (e0 + b * dt) * decay
        self.v = (v0 - w * b * dt) * decay
        return self.x.copy()


@dataclass(frozen=True)
class CameraInputs:
    """What a camera may follow at one frame: time s, the ridden UAV's pose (p_W m, q_WB), the target's p_W m."""

    t: float
    p_uav_W: np.ndarray
    q_uav_WB: np.ndarray
    p_target_W: np.ndarray


class CameraRig(ABC):
    """A camera that follows the scene; ``view`` smooths the goal of ``goal``.

    Parameters
    ----------
    vfov : float
        Vertical field of view, rad.
    tau : float
        Smoothing time constant, s (0: no smoothing).
    """

    def __init__(self, vfov: float, tau: float) -> None:
        self.vfov = float(vfov)
        self._eye = CriticalDamper(tau)
        self._target = CriticalDamper(tau)

    @abstractmethod
    def goal(self, inputs: CameraInputs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unsmoothed (eye_W, target_W, up_W) for ``inputs``."""

    def view(self, inputs: CameraInputs, dt: float) -> CameraView:
        """The camera at this frame, ``dt`` s after the previous one."""
        eye, target, up = self.goal(inputs)
        eye_s, target_s = self._eye.update(eye, dt), self._target.update(target, dt)
        if np.linalg.norm(np.cross(target_s - eye_s, up)) < 1e-6 * max(1.0, np.linalg.norm(target_s - eye_s)):
            eye_s, target_s = eye, target
        return CameraView(eye_W=eye_s, target_W=target_s, up_W=up, vfov=self.vfov)


class ChaseCamera(CameraRig):
    """Behind and above the UAV, on the far side from the target, looking at the target.

    ``eye = p_uav - back d + up z``, ``d`` the horizontal unit vector from the UAV to the target.
    """

    def __init__(self, vfov: float, tau: float, back_m: float, up_m: float) -> None:
        super().__init__(vfov, tau)
        self.back_m, self.up_m = float(back_m), float(up_m)

    def goal(self, inputs: CameraInputs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        d = inputs.p_target_W - inputs.p_uav_W
        d[2] = 0.0
        n = np.linalg.norm(d)
        d = d / n if n > 1e-6 else np.array([np.cos(yaw_of(inputs.q_uav_WB)), np.sin(yaw_of(inputs.q_uav_WB)), 0.0])
        eye = inputs.p_uav_W - self.back_m * d + self.up_m * _Z
        return eye, inputs.p_target_W.astype(float), _Z


class OrbitCamera(CameraRig):
    """Circling the target: ``eye = p_t + [R cos(2 pi t / T), R sin(2 pi t / T), h]``, looking at the target."""

    def __init__(self, vfov: float, tau: float, radius_m: float, height_m: float, period_s: float) -> None:
        super().__init__(vfov, tau)
        self.radius_m, self.height_m, self.period_s = float(radius_m), float(height_m), float(period_s)

    def goal(self, inputs: CameraInputs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        a = 2.0 * np.pi * inputs.t / self.period_s
        eye = inputs.p_target_W + np.array([self.radius_m * np.cos(a), self.radius_m * np.sin(a), self.height_m])
        return eye, inputs.p_target_W.astype(float), _Z


class TopDownCamera(CameraRig):
    """Straight down, north up: a map of ``bounds`` (xmin, xmax, ymin, ymax) m, or of a square around the target.

    The height that fits a ground width ``sx`` and height ``sy`` in an image of ``aspect`` = width / height is
    ``h = max(sy / 2, sx / (2 aspect)) / tan(vfov / 2)``.
    """

    def __init__(self, vfov: float, tau: float, aspect: float, bounds: tuple[float, float, float, float] | None,
                 span_m: float) -> None:
        super().__init__(vfov, tau)
        self.aspect, self.bounds, self.span_m = float(aspect), bounds, float(span_m)

    def _height(self, sx: float, sy: float) -> float:
        return max(sy / 2.0, sx / (2.0 * self.aspect)) / np.tan(self.vfov / 2.0)

    def goal(self, inputs: CameraInputs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self.bounds is None:
            c = np.array([inputs.p_target_W[0], inputs.p_target_W[1], 0.0])
            h = self._height(self.span_m, self.span_m)
        else:
            x0, x1, y0, y1 = self.bounds
            c = np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])
            h = self._height(x1 - x0, y1 - y0)
        return c + h * _Z, c, np.array([0.0, 1.0, 0.0])


class OnboardCamera(CameraRig):
    """The UAV's own view from just ahead of the body.

    With ``track`` the gimbal points at the target (a tracking payload); otherwise it looks along the heading,
    pitched ``pitch`` rad below the horizon.
    """

    def __init__(self, vfov: float, tau: float, pitch: float, ahead_m: float, track: bool = True) -> None:
        super().__init__(vfov, tau)
        self._eye = CriticalDamper(0.0)  # rigidly mounted: a lagging eye would fall behind the airframe
        self.pitch, self.ahead_m, self.track = float(pitch), float(ahead_m), bool(track)

    def goal(self, inputs: CameraInputs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        psi = yaw_of(inputs.q_uav_WB)
        if self.track:
            d = inputs.p_target_W - inputs.p_uav_W
            if np.hypot(d[0], d[1]) > 1e-6:
                psi = float(np.arctan2(d[1], d[0]))
        h = np.array([np.cos(psi), np.sin(psi), 0.0])
        eye = inputs.p_uav_W + self.ahead_m * h
        if self.track:
            return eye, inputs.p_target_W.astype(float), _Z
        fwd = np.cos(self.pitch) * h - np.sin(self.pitch) * _Z
        return eye, eye + 100.0 * fwd, _Z
