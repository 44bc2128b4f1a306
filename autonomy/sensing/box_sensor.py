"""Bounded-error nadir sensor of set-membership search (Ibenenthal et al.).

The sensor looks straight down with a square footprint of full opening angle ``opening_angle`` per axis: at height
``h`` above the ground it covers ``|x_F| <= h tan(opening_angle / 2)``, ``|y_F| <= h tan(opening_angle / 2)`` in the
footprint frame ``F`` (aligned with the world axes or with the heading). A ground point is *observed* when it is
in the footprint and no building hides it; the observed region is

    F = footprint \\ union of building shadows,

a shadow being the central projection, from the sensor onto the ground plane, of the building's faces (a building
as tall as the sensor casts an unbounded shadow, truncated far outside the footprint). The buildings are the known
map, so the region is exact and available to the estimator.

Every target whose ground position lies in ``F`` (boundary included) is detected, except a decoy seen from outside
its visibility cone (angle between ``p_sensor - p_decoy`` and the cone axis above its half aperture). Each detection
is ``z = p_xy + w`` with ``w`` uniform in ``[-noise_bound, noise_bound]^2``, so the truth is guaranteed to lie in the
box ``[z - noise_bound, z + noise_bound]``. No identities, no false alarms.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from autonomy.estimation.measurements import PositionDetectionModel
from worlds.geometry import Building

from .measurement import Detection, Sensor, SensorOutput
from .scene import SceneQuery, SensorPose, TargetTruth

__all__ = ["BoxSensor", "BoxSensorConfig", "building_shadow", "footprint_polygon"]


@dataclass(frozen=True, kw_only=True)
class BoxSensorConfig:
    """Bounded-error sensor parameters.

    Attributes
    ----------
    opening_angle : float
        Full opening angle of the square footprint per axis (rad), in (0, pi).
    noise_bound : float
        Half-width of the bounded position error per axis (m), > 0.
    footprint_frame : {"heading", "world"}
        Whether the footprint square turns with the heading or stays aligned with the world axes.
    ground_z : float
        Ground height (m).
    rate_hz : float
        Scans per second (Hz).
    latency_s : float
        Delay from measurement to arrival (s).
    """

    opening_angle: float = np.pi / 4
    noise_bound: float = 5.0
    footprint_frame: Literal["heading", "world"] = "heading"
    ground_z: float = 0.0
    rate_hz: float = 1.0
    latency_s: float = 0.0

    def __post_init__(self) -> None:
        if not (0 < self.opening_angle < np.pi):
            raise ValueError(f"BoxSensorConfig.opening_angle must be in (0, pi) rad, got {self.opening_angle}")
        if not (self.noise_bound > 0):
            raise ValueError(f"BoxSensorConfig.noise_bound must be > 0 m, got {self.noise_bound}")
        if self.footprint_frame not in ("heading", "world"):
            raise ValueError(f"BoxSensorConfig.footprint_frame must be heading|world, got {self.footprint_frame!r}")
        if not (self.rate_hz > 0):
            raise ValueError(f"BoxSensorConfig.rate_hz must be > 0, got {self.rate_hz}")
        if not (self.latency_s >= 0):
            raise ValueError(f"BoxSensorConfig.latency_s must be >= 0, got {self.latency_s}")


def footprint_polygon(p_W: np.ndarray, yaw: float, opening_angle: float, ground_z: float) -> shapely.Polygon:
    """Square ground footprint of a nadir sensor at ``p_W`` (m) turned by ``yaw`` (rad)."""
    h = float(p_W[2] - ground_z)
    if h <= 0:
        return shapely.Polygon()
    a = h * np.tan(opening_angle / 2)
    c, s = np.cos(yaw), np.sin(yaw)
    corners = np.array([[-a, -a], [a, -a], [a, a], [-a, a]]) @ np.array([[c, s], [-s, c]])
    return shapely.Polygon(corners + p_W[:2])


def _project_ring(ring_xy: np.ndarray, z: float, s: np.ndarray, ground_z: float, far: float) -> np.ndarray:
    """Central projection from ``s`` of points ``ring_xy`` at height ``z`` onto the ground plane."""
    hs = s[2] - ground_z
    if z < s[2] - 1e-9:
        k = hs / (s[2] - z)
        return s[:2] + k * (ring_xy - s[:2])
    d = ring_xy - s[:2]
    n = np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)
    return s[:2] + (np.linalg.norm(d, axis=1, keepdims=True) + far) * d / n


def _is_convex(ring_xy: np.ndarray) -> bool:
    """Whether the closed ring (n, 2) (not repeating its first vertex) turns the same way at every vertex."""
    d = np.roll(ring_xy, -1, axis=0) - ring_xy
    turn = d[:, 0] * np.roll(d[:, 1], -1) - d[:, 1] * np.roll(d[:, 0], -1)
    return bool(np.all(turn >= 0) or np.all(turn <= 0))


def building_shadow(building: Building, s_W: np.ndarray, ground_z: float, far: float) -> BaseGeometry:
    """Ground region hidden from a point sensor at ``s_W`` by a prism building.

    Union of the central projections of the footprint rings at ``base_z`` and ``top_z`` and of every side face;
    a ring at or above the sensor is pushed ``far`` metres beyond its vertices (an unbounded shadow truncated).
    The building's own footprint is included. For a convex footprint the prism is convex, so is its shadow, and the
    union is the convex hull of the footprint and the two projected rings: computed as such, because GEOS's union of
    the sliver side faces a nearly edge-on wall projects to can come out wrong (a union smaller than one of its parts
    was seen with GEOS 3.14).
    """
    fp = np.asarray(building.footprint)
    base = _project_ring(fp, max(building.base_z, ground_z), s_W, ground_z, far)
    top = _project_ring(fp, building.top_z, s_W, ground_z, far)
    if _is_convex(fp):
        return shapely.MultiPoint(np.vstack([fp, base, top])).convex_hull
    parts = [shapely.Polygon(fp), shapely.Polygon(base)]
    if building.top_z < s_W[2] - 1e-9:
        parts.append(shapely.Polygon(top))
    nxt = np.roll(np.arange(len(fp)), -1)
    quads = [
        shapely.MultiPoint([base[i], base[j], top[j], top[i]]).convex_hull
        for i, j in zip(range(len(fp)), nxt, strict=True)
    ]
    return shapely.union_all([p.buffer(0) for p in parts] + quads)


class BoxSensor(Sensor):
    """Bounded-error nadir sensor (module docstring).

    Parameters
    ----------
    config : BoxSensorConfig
        Parameters.
    buildings : Sequence[Building]
        The known obstacles that cast shadows.
    sensor_id : str
        Name carried by every detection.
    """

    def __init__(self, config: BoxSensorConfig, buildings: Sequence[Building] = (), sensor_id: str = "box"):
        self.config = config
        self.buildings = tuple(buildings)
        self.sensor_id = sensor_id
        self.rate_hz = config.rate_hz
        self.latency_s = config.latency_s
        self.model = PositionDetectionModel(dim=2)
        self._building_polys = shapely.STRtree([shapely.Polygon(b.footprint) for b in self.buildings])

    def observed_region(self, pose: SensorPose) -> BaseGeometry:
        """Ground region observed from ``pose``: the footprint minus the building shadows (shapely geometry)."""
        cfg = self.config
        yaw = pose.yaw if cfg.footprint_frame == "heading" else 0.0
        fp = footprint_polygon(pose.p_W, yaw, cfg.opening_angle, cfg.ground_z)
        if fp.is_empty or not self.buildings:
            return fp
        far = 4.0 * (fp.length + 1.0)
        # a sight line to a footprint point projects into the (convex) footprint, so only buildings over it can hide it
        near = self._building_polys.query(fp)
        shadows = [building_shadow(self.buildings[i], pose.p_W, cfg.ground_z, far) for i in near]
        return fp.difference(shapely.union_all(shadows)) if shadows else fp

    def measure(
        self, tick_time_s: float, pose: SensorPose, targets: TargetTruth, scene: SceneQuery, rng: np.random.Generator
    ) -> SensorOutput:
        """Detections of the targets inside the observed region; ``extras["observed_region"]`` holds the region.

        ``scene`` is not consulted: with prism buildings on flat ground the known map gives the observed region
        exactly (the tests check it against exact line of sight), and detection must agree with that region for
        the set-membership guarantee to hold.
        """
        cfg = self.config
        region = self.observed_region(pose)
        m = len(targets)
        seen = shapely.intersects_xy(region, targets.p_W[:, 0], targets.p_W[:, 1]) if m else np.zeros(0, bool)
        seen = np.asarray(seen, dtype=bool)
        if targets.cone_axis_W is not None and m:
            d = pose.p_W - targets.p_W
            cosang = np.sum(d * targets.cone_axis_W, axis=1) / np.maximum(np.linalg.norm(d, axis=1), 1e-9)
            in_cone = cosang >= np.cos(targets.cone_half_angle)
            is_decoy = np.array([k == "decoy" for k in targets.kind])
            seen &= ~is_decoy | in_cone
        b = cfg.noise_bound
        idx = np.flatnonzero(seen)
        z = targets.p_W[idx, :2] + rng.uniform(-b, b, size=(idx.size, 2))
        order = rng.permutation(idx.size)
        R = np.eye(2) * b**2 / 3.0
        bound = np.array([b, b])
        dets = tuple(
            Detection(
                z=z[i],
                R=R,
                t_meas=tick_time_s,
                t_arrival=tick_time_s + cfg.latency_s,
                sensor_id=self.sensor_id,
                p_sensor_W=pose.p_W,
                model=self.model,
                bound=bound,
            )
            for i in order
        )
        return SensorOutput(detections=dets, truth_ids=targets.ids[idx][order], extras={"observed_region": region})
