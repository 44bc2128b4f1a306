"""Bearings-only sensor (passive direction finding).

For each target inside the field of regard, within ``max_range`` and in line of sight, with probability ``pd``::

    z = [atan2(d_y, d_x) (, atan2(d_z, hypot(d_x, d_y)))] + w,   w ~ N(0, R),   d = p_t - p_s (ENU)
    R = diag(sigma_azimuth**2 (, sigma_elevation**2))

The azimuth is wrapped to [-pi, pi). No false alarms.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from autonomy.estimation.measurements import BearingDetectionModel

from .fov import FieldOfRegard
from .measurement import Detection, Sensor, SensorOutput, azimuth_elevation, wrap_angle
from .scene import SceneQuery, SensorPose, TargetTruth

__all__ = ["BearingConfig", "BearingSensor"]


@dataclass(frozen=True, kw_only=True)
class BearingConfig:
    """Bearing sensor parameters.

    Attributes
    ----------
    sigma_azimuth : float
        Azimuth noise standard deviation (rad).
    sigma_elevation : float | None
        Elevation noise standard deviation (rad); ``None``: azimuth only.
    rate_hz : float
        Scans per second (Hz).
    fov : FieldOfRegard
        Field of regard.
    max_range : float
        Maximum range (m).
    pd : float
        Detection probability of a visible target, in (0, 1].
    latency_s : float
        Delay from measurement to arrival (s).
    """

    sigma_azimuth: float
    sigma_elevation: float | None = None
    rate_hz: float = 10.0
    fov: FieldOfRegard = field(default_factory=FieldOfRegard)
    max_range: float = 3000.0
    pd: float = 1.0
    latency_s: float = 0.0

    def __post_init__(self) -> None:
        for name in ("sigma_azimuth", "rate_hz", "max_range"):
            if not (getattr(self, name) > 0):
                raise ValueError(f"BearingConfig.{name} must be > 0, got {getattr(self, name)}")
        if self.sigma_elevation is not None and not (self.sigma_elevation > 0):
            raise ValueError(f"BearingConfig.sigma_elevation must be > 0 or None, got {self.sigma_elevation}")
        if not (0 < self.pd <= 1):
            raise ValueError(f"BearingConfig.pd must be in (0, 1], got {self.pd}")
        if not (self.latency_s >= 0):
            raise ValueError(f"BearingConfig.latency_s must be >= 0, got {self.latency_s}")

    @property
    def R(self) -> np.ndarray:
        """Noise covariance (rad^2)."""
        s = [self.sigma_azimuth] + ([self.sigma_elevation] if self.sigma_elevation is not None else [])
        return np.diag(np.square(s))


class BearingSensor(Sensor):
    """Bearings-only sensor (module docstring)."""

    def __init__(self, config: BearingConfig, sensor_id: str = "bearing"):
        self.config = config
        self.sensor_id = sensor_id
        self.rate_hz = config.rate_hz
        self.latency_s = config.latency_s
        self.model = BearingDetectionModel(dim=config.R.shape[0], name="bearing")

    def measure(
        self, tick_time_s: float, pose: SensorPose, targets: TargetTruth, scene: SceneQuery, rng: np.random.Generator
    ) -> SensorOutput:
        cfg = self.config
        d = targets.p_W - pose.p_W
        mask = (np.linalg.norm(d, axis=1) <= cfg.max_range) & cfg.fov.contains(d, pose.R_WB)
        if np.any(mask):
            idx = np.flatnonzero(mask)
            los = np.asarray(scene.line_of_sight(np.repeat(pose.p_W[None, :], idx.size, axis=0), targets.p_W[idx]))
            mask[idx[~los]] = False
        hit = mask & (rng.uniform(size=len(targets)) < cfg.pd)
        az, el = azimuth_elevation(d[hit]) if np.any(hit) else (np.zeros(0), np.zeros(0))
        z_true = np.column_stack([az, el]) if cfg.sigma_elevation is not None else az[:, None]
        R = cfg.R
        z = z_true + rng.standard_normal(z_true.shape) * np.sqrt(np.diag(R))
        z[:, 0] = wrap_angle(z[:, 0])
        ids = targets.ids[hit]
        order = rng.permutation(len(ids))
        dets = tuple(
            Detection(
                z=z[i],
                R=R,
                t_meas=tick_time_s,
                t_arrival=tick_time_s + cfg.latency_s,
                sensor_id=self.sensor_id,
                p_sensor_W=pose.p_W,
                model=self.model,
            )
            for i in order
        )
        return SensorOutput(detections=dets, truth_ids=ids[order])
