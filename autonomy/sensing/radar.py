"""Ground-moving-target-indicator (GMTI) radar: range, azimuth, elevation and optionally range rate.

Measurement (``d = p_t - p_s``, ENU, Gaussian noise ``w ~ N(0, R)``, azimuth wrapped to [-pi, pi))::

    z = [|d|, atan2(d_y, d_x), atan2(d_z, hypot(d_x, d_y)) (, d . (v_t - v_s) / |d|)] + w
    R = diag(sigma_range**2, sigma_azimuth**2, sigma_elevation**2 (, sigma_range_rate**2))

A target is detected with probability ``P_d(r)`` when it is inside the field of regard, within ``max_range``, in
line of sight (``SceneQuery.line_of_sight``) and outside the Doppler notch: its own radial ground speed
``|v_t . d / |d||`` must reach ``min_detectable_velocity`` (the platform's motion is compensated, so a stopped
car or one moving tangentially is missed). Detection law (Swerling I, signal-to-noise falling as ``r**-4``)::

    P_d(r) = P_fa ** (1 / (1 + SNR(r))),   SNR(r) = SNR_ref (r_ref / r)**4,   SNR_ref = ln P_fa / ln P_d,ref - 1

so ``P_d(r_ref) = pd_ref``, ``P_d -> 1`` as ``r -> 0`` and ``P_d -> P_fa`` far away. ``pfa`` is the per-cell
false-alarm probability of that law only; false alarms are drawn separately: a Poisson number with mean
``clutter_rate`` per scan, uniform on the ground inside the field of regard and range, each with a range rate
uniform in ``min_detectable_velocity <= |r_dot| <= clutter_range_rate_max``.

With ``classify`` (a :class:`~autonomy.sensing.classify.Classifier` of ``"length"``), every detection also carries
the radar's reading of the car's length class from its range profile (``Detection.classes``), drawn from the
generator :func:`~autonomy.sensing.classify.class_generator` spawns from the scan's, so the other draws of a scan
(and of every later scan) are the same with classification on or off.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from autonomy.estimation.measurements import RadarDetectionModel

from .classify import Classifier, check_classifiers, class_generator, read_classes
from .fov import FieldOfRegard
from .measurement import CLUTTER_ID, Detection, Sensor, SensorOutput, azimuth_elevation, wrap_angle
from .scene import SceneQuery, SensorPose, TargetTruth

__all__ = ["RADAR_ATTRIBUTES", "Radar", "RadarConfig", "swerling1_pd"]

RADAR_ATTRIBUTES: tuple[str, ...] = ("length",)
"""The class attributes a radar may read: the length class, from the target's range profile."""


def swerling1_pd(r: np.ndarray, pd_ref: float, range_ref: float, pfa: float) -> np.ndarray:
    """Detection probability at range ``r`` (m) of the Swerling I ``r**-4`` law (module docstring)."""
    snr_ref = np.log(pfa) / np.log(pd_ref) - 1.0
    r = np.maximum(np.asarray(r, dtype=float), 1e-9)
    snr = snr_ref * (range_ref / r) ** 4
    return pfa ** (1.0 / (1.0 + snr))


@dataclass(frozen=True, kw_only=True)
class RadarConfig:
    """GMTI radar parameters.

    Attributes
    ----------
    sigma_range : float
        Range noise standard deviation (m).
    sigma_azimuth : float
        Azimuth noise standard deviation (rad).
    sigma_elevation : float | None
        Elevation noise standard deviation (rad); ``None``: a 2-D radar reporting (range, azimuth) only (papers 001
        and 002), which needs no range-rate channel.
    sigma_range_rate : float | None
        Range-rate noise standard deviation (m/s); ``None``: range rate is not reported.
    rate_hz : float
        Scans per second (Hz).
    fov : FieldOfRegard
        Field of regard (all-round or a sector).
    max_range : float
        Maximum slant range (m).
    pd_ref : float
        Detection probability at ``range_ref``, in (pfa, 1).
    range_ref : float
        Reference range of ``pd_ref`` (m).
    pfa : float
        Per-cell false-alarm probability in the Swerling I detection law (dimensionless, in (0, pd_ref)).
    min_detectable_velocity : float
        Doppler notch: targets with radial ground speed below this are missed (m/s); 0 disables the notch.
    clutter_rate : float
        Mean number of false alarms per scan (Poisson).
    clutter_range_rate_max : float
        Largest |range rate| given to a false alarm (m/s).
    ground_z : float
        Ground height on which false alarms are spread (m).
    latency_s : float
        Delay from measurement to arrival (s).
    classify : tuple[Classifier, ...]
        Class readings attached to every detection (attributes of :data:`RADAR_ATTRIBUTES`); empty: none, and no
        random number is drawn for them.
    """

    sigma_range: float
    sigma_azimuth: float
    sigma_elevation: float | None = None
    sigma_range_rate: float | None = None
    rate_hz: float = 2.0
    fov: FieldOfRegard = field(default_factory=FieldOfRegard)
    max_range: float = 5000.0
    pd_ref: float = 0.9
    range_ref: float = 2000.0
    pfa: float = 1e-6
    min_detectable_velocity: float = 1.0
    clutter_rate: float = 0.0
    clutter_range_rate_max: float = 30.0
    ground_z: float = 0.0
    latency_s: float = 0.0
    classify: tuple[Classifier, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "classify", check_classifiers("RadarConfig", self.classify, RADAR_ATTRIBUTES))
        for name in ("sigma_range", "sigma_azimuth", "rate_hz", "max_range", "range_ref"):
            if not (getattr(self, name) > 0):
                raise ValueError(f"RadarConfig.{name} must be > 0, got {getattr(self, name)}")
        if self.sigma_elevation is not None and not (self.sigma_elevation > 0):
            raise ValueError(f"RadarConfig.sigma_elevation must be > 0 or None, got {self.sigma_elevation}")
        if self.sigma_elevation is None and self.sigma_range_rate is not None:
            raise ValueError("RadarConfig.sigma_range_rate needs the elevation channel (z = range, azimuth, "
                             "elevation, range rate): give sigma_elevation too")
        if self.sigma_range_rate is not None and not (self.sigma_range_rate > 0):
            raise ValueError(f"RadarConfig.sigma_range_rate must be > 0 or None, got {self.sigma_range_rate}")
        if not (0 < self.pfa < self.pd_ref < 1):
            raise ValueError(f"RadarConfig needs 0 < pfa < pd_ref < 1, got pfa={self.pfa}, pd_ref={self.pd_ref}")
        for name in ("min_detectable_velocity", "clutter_rate", "latency_s"):
            if not (getattr(self, name) >= 0):
                raise ValueError(f"RadarConfig.{name} must be >= 0, got {getattr(self, name)}")
        if not (self.clutter_range_rate_max >= self.min_detectable_velocity):
            raise ValueError(
                "RadarConfig.clutter_range_rate_max must be >= min_detectable_velocity, "
                f"got {self.clutter_range_rate_max}"
            )

    @property
    def R(self) -> np.ndarray:
        """Measurement noise covariance (m^2, rad^2 (, rad^2 (, m^2/s^2)))."""
        s = [self.sigma_range, self.sigma_azimuth]
        if self.sigma_elevation is not None:
            s.append(self.sigma_elevation)
        if self.sigma_range_rate is not None:
            s.append(self.sigma_range_rate)
        return np.diag(np.square(s))

    def pd(self, r: np.ndarray) -> np.ndarray:
        """Detection probability at slant range ``r`` (m), zero beyond ``max_range``."""
        r = np.asarray(r, dtype=float)
        return np.where(r <= self.max_range, swerling1_pd(r, self.pd_ref, self.range_ref, self.pfa), 0.0)


class Radar(Sensor):
    """GMTI radar model (module docstring).

    Parameters
    ----------
    config : RadarConfig
        Parameters.
    sensor_id : str
        Name carried by every detection.
    """

    def __init__(self, config: RadarConfig, sensor_id: str = "radar"):
        self.config = config
        self.sensor_id = sensor_id
        self.rate_hz = config.rate_hz
        self.latency_s = config.latency_s
        self.model = RadarDetectionModel(dim=config.R.shape[0])

    def detectable(self, pose: SensorPose, targets: TargetTruth, scene: SceneQuery) -> tuple[np.ndarray, np.ndarray]:
        """Which targets could be detected (geometry, notch, line of sight) and their detection probability.

        Returns ``(mask (M,) bool, pd (M,))``; ``pd`` is zero where ``mask`` is False.
        """
        mask, pd = self._in_view(pose, targets)
        self._drop_hidden(mask, pose, targets, scene)
        return mask, np.where(mask, pd, 0.0)

    def _in_view(self, pose: SensorPose, targets: TargetTruth) -> tuple[np.ndarray, np.ndarray]:
        """(M,) which targets lie in range and field of view and move fast enough radially, and (M,) every target's
        detection probability at its range; no line of sight yet."""
        cfg = self.config
        if len(targets) == 0:
            return np.zeros(0, dtype=bool), np.zeros(0)
        d = targets.p_W - pose.p_W
        r = np.linalg.norm(d, axis=1)
        u = d / np.maximum(r, 1e-9)[:, None]
        radial_ground_speed = np.abs(np.sum(targets.v_W * u, axis=1))
        mask = (
            (r <= cfg.max_range) & cfg.fov.contains(d, pose.R_WB) & (radial_ground_speed >= cfg.min_detectable_velocity)
        )
        return mask, cfg.pd(r)

    @staticmethod
    def _drop_hidden(mask: np.ndarray, pose: SensorPose, targets: TargetTruth, scene: SceneQuery) -> None:
        """Clear ``mask`` (in place) where a building or another body hides the target from the sensor; rays are cast
        only for the targets ``mask`` holds."""
        if np.any(mask):
            idx = np.flatnonzero(mask)
            los = scene.line_of_sight(np.repeat(pose.p_W[None, :], idx.size, axis=0), targets.p_W[idx])
            mask[idx[~np.asarray(los, dtype=bool)]] = False

    def _ideal(self, pose: SensorPose, p_W: np.ndarray, v_W: np.ndarray) -> np.ndarray:
        d = p_W - pose.p_W
        r = np.linalg.norm(d, axis=1)
        az, el = azimuth_elevation(d)
        cols = [r, az] if self.config.sigma_elevation is None else [r, az, el]
        if self.config.sigma_range_rate is not None:
            cols.append(np.sum(d * (v_W - pose.v_W), axis=1) / np.maximum(r, 1e-9))
        return np.column_stack(cols)

    def measure(
        self, tick_time_s: float, pose: SensorPose, targets: TargetTruth, scene: SceneQuery, rng: np.random.Generator
    ) -> SensorOutput:
        cfg = self.config
        # a target is detected where it is in view, its draw falls below its pd, and nothing hides it: the rays are
        # cast only for those the first two leave (the draws are those of detectable's mask and pd, the same hits)
        hit, pd = self._in_view(pose, targets)
        hit &= rng.uniform(size=len(targets)) < pd
        self._drop_hidden(hit, pose, targets, scene)
        z_true = self._ideal(pose, targets.p_W[hit], targets.v_W[hit]) if np.any(hit) else np.zeros((0, cfg.R.shape[0]))
        ids = list(targets.ids[hit])

        n_fa = int(rng.poisson(cfg.clutter_rate)) if cfg.clutter_rate > 0 else 0
        if n_fa:
            pts = cfg.fov.sample_ground(n_fa, pose.p_W, pose.R_WB, cfg.max_range, cfg.ground_z, rng)
            z_fa = self._ideal(pose, pts, np.zeros_like(pts))
            if cfg.sigma_range_rate is not None:
                mag = rng.uniform(cfg.min_detectable_velocity, cfg.clutter_range_rate_max, size=len(pts))
                z_fa[:, 3] = mag * rng.choice([-1.0, 1.0], size=len(pts))
            z_true = np.vstack([z_true, z_fa])
            ids += [CLUTTER_ID] * len(pts)

        n = len(z_true)
        R = cfg.R
        z = z_true + rng.standard_normal((n, R.shape[0])) * np.sqrt(np.diag(R))
        if n:
            z[:, 1] = wrap_angle(z[:, 1])
        order = rng.permutation(n)
        truth_ids = np.asarray(ids, dtype=int)[order] if n else np.zeros(0, int)
        classes = read_classes(cfg.classify, truth_ids, targets, class_generator(rng)) if cfg.classify and n \
            else [()] * n
        t_arr = tick_time_s + cfg.latency_s
        dets = tuple(
            Detection(
                z=z[i],
                R=R,
                t_meas=tick_time_s,
                t_arrival=t_arr,
                sensor_id=self.sensor_id,
                p_sensor_W=pose.p_W,
                model=self.model,
                classes=classes[k],
            )
            for k, i in enumerate(order)
        )
        return SensorOutput(detections=dets, truth_ids=truth_ids)
