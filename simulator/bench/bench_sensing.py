"""Sensing benchmarks: radar with line-of-sight raycasts in a 500-building town, and camera render + detection.

The town is a 25 x 20 grid of box buildings (random footprints 14-30 m, heights 8-60 m, 45 m pitch) on a ground
plane, with 10 magenta car boxes driving along the streets and 4 UAVs at 80-120 m. Only the sensor calls are timed
(moving the car bodies is the simulator's cost, not the sensors').
"""

from __future__ import annotations

import time

import numpy as np
import pybullet as p

from autonomy.sensing.camera import CAR_RGBA, Camera, CameraConfig
from autonomy.sensing.radar import Radar, RadarConfig
from autonomy.sensing.scene import SensorPose, TargetTruth
from simulator.bench.registry import BenchRecord, benchmark
from simulator.scene_query import PybulletSceneQuery

PITCH_M = 45.0
GRID = (25, 20)
CAR_HALF = (2.0, 0.9, 0.75)
N_UAV, N_CAR, RATE_HZ = 4, 10, 10


class _Town:
    """A PyBullet client holding the benchmark town, its cars and the scene query."""

    def __init__(self, seed: int = 0):
        rng = np.random.default_rng(seed)
        self.client = p.connect(p.DIRECT)
        cid = self.client
        col = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid)
        nx, ny = GRID
        ext = [nx * PITCH_M, ny * PITCH_M, 0.01]
        vis = p.createVisualShape(
            p.GEOM_BOX,
            halfExtents=ext,
            rgbaColor=[0.4, 0.42, 0.4, 1],
            visualFramePosition=[0, 0, -0.01],
            physicsClientId=cid,
        )
        occluders = {p.createMultiBody(0, col, vis, physicsClientId=cid)}
        for i in range(nx):
            for j in range(ny):
                he = [rng.uniform(7, 15), rng.uniform(7, 15), rng.uniform(4, 30)]
                c = p.createCollisionShape(p.GEOM_BOX, halfExtents=he, physicsClientId=cid)
                v = p.createVisualShape(p.GEOM_BOX, halfExtents=he, rgbaColor=[0.7, 0.68, 0.65, 1], physicsClientId=cid)
                pos = [(i + 0.5) * PITCH_M, (j + 0.5) * PITCH_M, he[2]]
                occluders.add(p.createMultiBody(0, c, v, basePosition=pos, physicsClientId=cid))
        c = p.createCollisionShape(p.GEOM_BOX, halfExtents=CAR_HALF, physicsClientId=cid)
        v = p.createVisualShape(p.GEOM_BOX, halfExtents=CAR_HALF, rgbaColor=list(CAR_RGBA), physicsClientId=cid)
        self.cars = [
            p.createMultiBody(0, c, v, basePosition=[0, 0, CAR_HALF[2]], physicsClientId=cid) for _ in range(N_CAR)
        ]
        self.scene = PybulletSceneQuery(cid, occluders)
        # cars drive east along the streets y = k * pitch; UAVs circle over the middle of the town
        self.street_y = PITCH_M * rng.integers(2, ny - 2, size=N_CAR)
        self.car_x0 = rng.uniform(0.2, 0.8, size=N_CAR) * nx * PITCH_M
        self.centre = np.array([nx * PITCH_M / 2, ny * PITCH_M / 2])

    def truth(self, t: float) -> TargetTruth:
        x = self.car_x0 + 8.0 * t
        pts = np.column_stack([x, self.street_y, np.full(N_CAR, CAR_HALF[2])])
        for body, pt in zip(self.cars, pts, strict=True):
            p.resetBasePositionAndOrientation(body, pt.tolist(), [0, 0, 0, 1], physicsClientId=self.client)
        return TargetTruth(
            ids=np.arange(N_CAR),
            p_W=pts,
            v_W=np.tile([8.0, 0.0, 0.0], (N_CAR, 1)),
            kind=("car",) * N_CAR,
            yaw=np.zeros(N_CAR),
            seg_ids=self.cars,
        )

    def poses(self, t: float, truth: TargetTruth) -> list[SensorPose]:
        out = []
        for k in range(N_UAV):
            ang = 2 * np.pi * k / N_UAV + 0.1 * t
            p_W = np.array([*(self.centre + 150.0 * np.array([np.cos(ang), np.sin(ang)])), 80.0 + 10.0 * k])
            tgt = truth.p_W[k % N_CAR]
            yaw = np.arctan2(tgt[1] - p_W[1], tgt[0] - p_W[0])
            out.append(SensorPose(p_W=p_W, q_WB=[0, 0, np.sin(yaw / 2), np.cos(yaw / 2)], v_W=[10.0, 0.0, 0.0]))
        return out

    def close(self) -> None:
        p.disconnect(self.client)


def _sensing_time(
    town: _Town, sensors: list, rng: np.random.Generator, sim_seconds: float = 1.0
) -> tuple[float, float]:
    """(wall, process CPU) seconds spent in ``measure`` over ``sim_seconds`` of 10 Hz scans by every UAV.

    The CPU figure is what one unloaded core would take; the wall figure includes whatever else shares the machine.
    """
    wall = cpu = 0.0
    for k in range(int(sim_seconds * RATE_HZ)):
        t = k / RATE_HZ
        truth = town.truth(t)
        for sensor, pose in zip(sensors, town.poses(t, truth), strict=True):
            c0, w0 = time.process_time(), time.perf_counter()
            sensor.measure(t, pose, truth, town.scene, rng)
            wall += time.perf_counter() - w0
            cpu += time.process_time() - c0
    return wall, cpu


def _medians(fn, repeats: int) -> tuple[float, float]:
    runs = [fn() for _ in range(repeats)]
    return float(np.median([r[0] for r in runs])), float(np.median([r[1] for r in runs]))


@benchmark("sensing_radar", produces=("radar_cost_fraction_4x10_town", "radar_cost_fraction_4x10_town_cpu"))
def radar_cost() -> list[BenchRecord]:
    """Radar (4 UAVs x 10 cars, 10 Hz, clutter, line of sight in a 500-building town): wall s per simulated s."""
    town = _Town()
    try:
        cfg = RadarConfig(
            sigma_range=5.0,
            sigma_azimuth=0.01,
            sigma_elevation=0.01,
            sigma_range_rate=0.5,
            rate_hz=RATE_HZ,
            max_range=3000.0,
            clutter_rate=2.0,
        )
        radars = [Radar(cfg, sensor_id=f"uav{k}/radar") for k in range(N_UAV)]
        rng = np.random.default_rng(0)
        sim_s = 2.0
        wall, cpu = _medians(lambda: _sensing_time(town, radars, rng, sim_s), repeats=7)
    finally:
        town.close()
    return [
        BenchRecord(name="radar_cost_fraction_4x10_town", value=wall / sim_s, unit="x", target=0.05, better="lower"),
        BenchRecord(name="radar_cost_fraction_4x10_town_cpu", value=cpu / sim_s, unit="x", target=0.05, better="lower"),
    ]


@benchmark("sensing_camera", produces=("camera_rtf_4uav_160x120", "camera_rtf_4uav_160x120_cpu"))
def camera_rtf() -> list[BenchRecord]:
    """Camera 160x120 at 10 Hz on 4 UAVs with colour detection (TinyRenderer) in the town: real-time factor."""
    town = _Town()
    try:
        cams = [
            Camera(CameraConfig(width=160, height=120, rate_hz=RATE_HZ), sensor_id=f"uav{k}/cam") for k in range(N_UAV)
        ]
        rng = np.random.default_rng(0)
        wall, cpu = _medians(lambda: _sensing_time(town, cams, rng, 1.0), repeats=5)
    finally:
        town.close()
    return [
        BenchRecord(name="camera_rtf_4uav_160x120", value=1.0 / wall, unit="x", target=1.0, better="higher"),
        BenchRecord(name="camera_rtf_4uav_160x120_cpu", value=1.0 / cpu, unit="x", target=1.0, better="higher"),
    ]
