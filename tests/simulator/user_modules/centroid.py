"""A user's own estimator and guidance law, written against the documented protocols only (no skytrack base class).

``CentroidEstimator`` averages the ground fixes of the radar detections of the last ``window_s`` seconds — crude, but
enough to show that what a user writes is driven by the simulator and checked against physics ground truth.
``CircleGuidance`` flies a fixed circle with velocity set-points.
"""

from __future__ import annotations

import numpy as np

from interfaces.setpoints import VelocitySetpoint
from interfaces.state import TargetEstimate


def radar_fix(d, target_height: float) -> np.ndarray:
    """The ground position (x, y) of a radar detection's range and azimuth on the plane ``z = target_height``."""
    rng, az = d.z[0], d.z[1]
    dz = target_height - d.p_sensor_W[2]
    rho = np.sqrt(max(rng ** 2 - dz ** 2, 0.0))
    return d.p_sensor_W[:2] + rho * np.array([np.cos(az), np.sin(az)])


class CentroidEstimator:
    def __init__(self, window_s: float = 2.0, target_height: float = 0.0) -> None:
        self.window_s = window_s
        self.target_height = target_height
        self.fixes: list[tuple[float, np.ndarray]] = []
        self.calls = 0

    def step(self, t, detections):
        self.calls += 1
        for d in detections:
            if d.kind == "radar":
                self.fixes.append((d.t_meas, radar_fix(d, self.target_height)))
        self.fixes = [(tm, p) for tm, p in self.fixes if t - tm <= self.window_s]
        if not self.fixes:
            return None
        pts = np.array([p for _, p in self.fixes])
        return TargetEstimate(t=t, p_W=np.median(pts, axis=0), v_W=np.zeros(2))


class CircleGuidance:
    def __init__(self, centre=(0.0, 0.0), radius: float = 80.0, speed: float = 8.0, altitude: float = 50.0) -> None:
        self.centre = np.asarray(centre, dtype=float)
        self.radius, self.speed, self.altitude = radius, speed, altitude

    def command(self, own, target, teammates, t):
        r = own.p_W[:2] - self.centre
        d = np.linalg.norm(r) + 1e-9
        tangent = np.array([-r[1], r[0]]) / d
        radial = -(d - self.radius) / d * r * 0.3
        v = self.speed * tangent + radial
        vz = 0.8 * (self.altitude - own.p_W[2])
        return VelocitySetpoint(v_W=np.array([v[0], v[1], vz]), yaw=None)
