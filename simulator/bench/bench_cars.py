"""Car benchmarks: real-time factor of a fleet of cars driving random walks on a town grid (no UAVs), physics
multibodies and kinematic boxes."""

from __future__ import annotations

import time

import numpy as np
import pybullet as p

from simulator.bench.registry import BenchRecord, benchmark
from vehicles.car.driver_config import DriverConfig
from vehicles.car.fleet import CarFleet
from vehicles.car.params import load_car
from vehicles.car.route import Route
from worlds.roads.network import RoadNetwork

PHYSICS_HZ = 240
SIM_SECONDS = 15.0
REPEATS = 3


def _grid(n: int = 4, spacing: float = 150.0) -> RoadNetwork:
    nodes = {f"{i}_{j}": [i * spacing, j * spacing] for i in range(n) for j in range(n)}
    streets = [{"id": f"h{i}_{j}", "nodes": [f"{i}_{j}", f"{i + 1}_{j}"]} for i in range(n - 1) for j in range(n)]
    streets += [{"id": f"v{i}_{j}", "nodes": [f"{i}_{j}", f"{i}_{j + 1}"]} for i in range(n) for j in range(n - 1)]
    return RoadNetwork.from_spec({"nodes": nodes, "streets": streets})


def _rtf(n_cars: int, seed: int, dynamics: str = "physics") -> float:
    """Simulated seconds per wall second for ``n_cars`` cars of the given ``dynamics`` over ``SIM_SECONDS``
    (PyBullet's default 50 solver iterations; cars spawn 20 m into the first ``n_cars`` roads of a 4 x 4 grid and
    drive random walks)."""
    net = _grid()
    c = p.connect(p.DIRECT)
    try:
        p.setGravity(0, 0, -9.81, physicsClientId=c)
        p.setTimeStep(1.0 / PHYSICS_HZ, physicsClientId=c)
        p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=c), physicsClientId=c)
        starts = [rid for rid in net.roads][:n_cars]
        cars = [load_car("sedan" if i % 3 else "van") for i in range(n_cars)]
        fleet = CarFleet(c, cars, [DriverConfig()] * n_cars,
                         [Route(random_walk=True, start_road=r, start_s=20.0) for r in starts], net, PHYSICS_HZ,
                         np.random.default_rng(seed), dynamics=[dynamics] * n_cars)
        n = int(SIM_SECONDS * PHYSICS_HZ)
        t0 = time.perf_counter()
        for tick in range(1, n + 1):
            fleet.apply_actuation()
            p.stepSimulation(physicsClientId=c)
            fleet.after_step(tick)
        return SIM_SECONDS / (time.perf_counter() - t0)
    finally:
        p.disconnect(c)


@benchmark("cars_rtf", produces=("cars_rtf_10", "cars_tick_ms_10", "cars_kinematic_rtf_10",
                                  "cars_kinematic_tick_ms_10"))
def cars_rtf() -> list[BenchRecord]:
    """Real-time factor of 10 cars (physics at 240 Hz, drivers at 40 Hz), median of 3 runs of 15 simulated s,
    and the matching wall time of one tick (actuation + physics step + drivers); the same for 10 kinematic cars
    (``dynamics: kinematic``), each run alternating with a physics run."""
    phys, kin = [], []
    for seed in range(REPEATS):
        phys.append(_rtf(10, seed))
        kin.append(_rtf(10, seed, "kinematic"))
    out = []
    for label, runs in (("", phys), ("kinematic_", kin)):
        rtf = float(np.median(runs))
        out += [BenchRecord(name=f"cars_{label}rtf_10", value=rtf, unit="x", better="higher"),
                BenchRecord(name=f"cars_{label}tick_ms_10", value=1e3 / (rtf * PHYSICS_HZ), unit="ms", better="lower")]
    return out
