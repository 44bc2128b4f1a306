"""Fields of regard: which directions a sensor can see, and uniform sampling of the ground inside them.

A field of regard is all-round or a sector of azimuth x elevation measured in one of three frames:

- ``"world"``: ENU azimuth / elevation;
- ``"heading"``: relative to the body heading (a gimbal that follows yaw and is stabilised in roll and pitch);
- ``"body"``: in the full body frame (a fixed mount that rolls and pitches with the airframe).

Azimuth limits may wrap (``(-3.0, 3.0)`` and ``(3.0, -3.0)`` are different sectors: the second one is the 0.28 rad
sector behind the sensor).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from .measurement import azimuth_elevation
from .scene import yaw_rot

__all__ = ["FieldOfRegard"]


@dataclass(frozen=True, kw_only=True)
class FieldOfRegard:
    """Directions a sensor can see.

    Attributes
    ----------
    frame : {"all_round", "world", "heading", "body"}
        ``"all_round"`` ignores the limits; otherwise the frame in which they are measured.
    azimuth_limits : tuple[float, float]
        (min, max) azimuth, counter-clockwise from the frame's x axis (rad); the sector runs from min
        counter-clockwise to max.
    elevation_limits : tuple[float, float]
        (min, max) elevation above the frame's x-y plane (rad), within [-pi/2, pi/2].
    """

    frame: Literal["all_round", "world", "heading", "body"] = "all_round"
    azimuth_limits: tuple[float, float] = (-np.pi, np.pi)
    elevation_limits: tuple[float, float] = (-np.pi / 2, np.pi / 2)

    def __post_init__(self) -> None:
        if self.frame not in ("all_round", "world", "heading", "body"):
            raise ValueError(f"FieldOfRegard.frame must be all_round|world|heading|body, got {self.frame!r}")
        if not all(np.isfinite(self.azimuth_limits)) or len(self.azimuth_limits) != 2:
            raise ValueError(f"FieldOfRegard.azimuth_limits must be two finite angles (rad), got {self.azimuth_limits}")
        lo, hi = self.elevation_limits
        if not (-np.pi / 2 <= lo < hi <= np.pi / 2):
            raise ValueError(f"FieldOfRegard.elevation_limits must satisfy -pi/2 <= min < max <= pi/2, got {(lo, hi)}")

    def frame_rotation(self, R_WB: np.ndarray) -> np.ndarray:
        """Rotation from the sector frame to the world (3x3)."""
        if self.frame == "body":
            return np.asarray(R_WB)
        if self.frame == "heading":
            return yaw_rot(float(np.arctan2(R_WB[1, 0], R_WB[0, 0])))
        return np.eye(3)

    def contains(self, d_W: np.ndarray, R_WB: np.ndarray) -> np.ndarray:
        """(N,) bool: directions ``d_W`` (N, 3) (sensor to point, world frame) inside the field of regard."""
        d = np.atleast_2d(np.asarray(d_W, dtype=float))
        if self.frame == "all_round":
            return np.ones(len(d), dtype=bool)
        d_F = d @ self.frame_rotation(R_WB)  # rows: R_WF^T d
        az, el = azimuth_elevation(d_F)
        lo, hi = self.azimuth_limits
        width = 2 * np.pi if hi - lo >= 2 * np.pi - 1e-12 else (hi - lo) % (2 * np.pi)
        in_az = (az - lo) % (2 * np.pi) <= width + 1e-12
        return in_az & (el >= self.elevation_limits[0]) & (el <= self.elevation_limits[1])

    def sample_ground(
        self,
        n: int,
        p_W: np.ndarray,
        R_WB: np.ndarray,
        max_range: float,
        ground_z: float,
        rng: np.random.Generator,
        max_batches: int = 200,
    ) -> np.ndarray:
        """``n`` points (n, 3) uniform on the ground plane inside the field of regard and within ``max_range``.

        Points are drawn uniformly on the ground disc of radius ``sqrt(max_range**2 - h**2)`` around the sensor's
        ground point (``h = p_z - ground_z``) and kept if inside the field of regard (rejection sampling, so the
        result is exactly uniform on the visible ground). Returns fewer rows if the visible ground is (nearly) empty.
        """
        h = float(p_W[2] - ground_z)
        rho_max2 = max_range**2 - h**2
        if n <= 0 or rho_max2 <= 0:
            return np.zeros((0, 3))
        rho_max = np.sqrt(rho_max2)
        kept: list[np.ndarray] = []
        count = 0
        batch = max(16, 4 * n)
        for _ in range(max_batches):
            r = rho_max * np.sqrt(rng.uniform(size=batch))
            th = rng.uniform(-np.pi, np.pi, size=batch)
            pts = np.column_stack([p_W[0] + r * np.cos(th), p_W[1] + r * np.sin(th), np.full(batch, ground_z)])
            pts = pts[self.contains(pts - p_W, R_WB)]
            kept.append(pts)
            count += len(pts)
            if count >= n:
                break
        return np.vstack(kept)[:n] if kept else np.zeros((0, 3))
