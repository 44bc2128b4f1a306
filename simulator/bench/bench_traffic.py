"""Traffic benchmarks: the compiled built-in fleet's cost per car and tick against the per-tick Python drivers it
replaced, and closed-loop real-time factors of the Helsinki worlds with 200 built-in and 1000 SUMO cars.

CPU time of this process (``time.process_time``) is the headline, with the wall-time twin beside it: the work is
single-threaded, and on a shared machine CPU time is what other load disturbs least.
"""

from __future__ import annotations

import statistics
import time

import numpy as np
import pybullet as p

from simulator.bench.bench_cars import _grid
from simulator.bench.registry import BenchRecord, benchmark
from vehicles.car.driver import Driver
from vehicles.car.driver_config import DriverConfig
from vehicles.car.dynamics import KinematicDynamics
from vehicles.car.params import load_car
from vehicles.car.route import Route
from vehicles.car.traffic import find_leaders
from vehicles.car.traffic_fleet import TrafficFleet
from vehicles.car.traffic_source import OtherCars
from worlds.roads.network import RoadNetwork

__all__: list[str] = []

PHYSICS_HZ = 240
CITY_REPEATS = 3
"""Runs of each city world per benchmark, the median reported: single runs swing by ±20 % on a shared machine."""
CARS = 200
REPEATS = 3


def _drivers(net: RoadNetwork, n: int, seed: int, cfg: DriverConfig) -> tuple[list[Driver], list]:
    roads = list(net.roads)
    params = [load_car("sedan" if i % 3 else "van") for i in range(n)]
    routes = [Route(random_walk=True, start_road=roads[i % len(roads)], start_s=20.0 + 50.0 * (i // len(roads)))
              for i in range(n)]
    gens = np.random.default_rng(seed).spawn(n)
    return [Driver(config=cfg, params=par, route=rt, network=net, rng=g, physics_hz=PHYSICS_HZ)
            for par, rt, g in zip(params, routes, gens, strict=True)], params


def _compiled_us(seed: int, seconds: float, warmup: float = 2.0) -> float:
    """CPU microseconds per car and physics tick of the compiled fleet (drivers at 20 Hz), after ``warmup`` s."""
    net, c = _grid(12, 150.0), p.connect(p.DIRECT)
    try:
        drivers, params = _drivers(net, CARS, seed, DriverConfig(rate_hz=20))
        fleet = TrafficFleet(c, drivers, params, [f"t{i}" for i in range(CARS)], PHYSICS_HZ)
        w = int(warmup * PHYSICS_HZ)
        for tick in range(1, w + 1):
            fleet.advance(tick, OtherCars.none())
        n = int(seconds * PHYSICS_HZ)
        t0 = time.process_time()
        for tick in range(w + 1, w + n + 1):
            fleet.advance(tick, OtherCars.none())
        return (time.process_time() - t0) / (n * CARS) * 1e6
    finally:
        p.disconnect(c)


def _python_us(seed: int, seconds: float) -> float:
    """The same cars as the per-tick Python drivers and kinematic bodies that the compiled fleet replaced (the
    reference, measured in the same call)."""
    net, c = _grid(12, 150.0), p.connect(p.DIRECT)
    try:
        drivers, params = _drivers(net, CARS, seed, DriverConfig(rate_hz=20))
        dyn = [KinematicDynamics(c, par, *d.spawn_pose(), PHYSICS_HZ) for d, par in zip(drivers, params, strict=True)]
        lengths = [par.length for par in params]
        every = drivers[0].config.ticks_per_update(PHYSICS_HZ)
        n = int(seconds * PHYSICS_HZ)
        t0 = time.process_time()
        for tick in range(1, n + 1):
            for d, car in zip(drivers, dyn, strict=True):
                car.actuate(d.command)
            if tick % every == 0:
                rows = np.array([car.state_row() for car in dyn])
                yaw = 2 * np.arctan2(rows[:, 5], rows[:, 6])
                speed = rows[:, 7] * np.cos(yaw) + rows[:, 8] * np.sin(yaw)
                leaders = find_leaders(drivers, rows[:, :2], yaw, speed, lengths)
                for i, d in enumerate(drivers):
                    d.update(rows[i, :2], float(yaw[i]), float(speed[i]), tick, leaders[i], float(rows[i, 12]))
        return (time.process_time() - t0) / (n * CARS) * 1e6
    finally:
        p.disconnect(c)


@benchmark("traffic_car_tick", produces=("traffic_car_tick_us", "traffic_car_tick_us_python",
                                         "traffic_car_tick_speedup"))
def bench_traffic_car_tick() -> list[BenchRecord]:
    """CPU microseconds per traffic car per physics tick: 200 kinematic cars on random walks over a 12 x 12 grid of
    150 m blocks (stops, turns, car following), drivers at 20 Hz, the compiled fleet (median of 3 runs of 20 s after
    2 s) against the per-tick Python drivers it replaced (median of 3 runs of 5 s, same cars and seeds)."""
    fast = statistics.median(_compiled_us(s, 20.0) for s in range(REPEATS))
    slow = statistics.median(_python_us(s, 5.0) for s in range(REPEATS))
    return [BenchRecord(name="traffic_car_tick_us", value=fast, unit="us", target=1.0, better="lower"),
            BenchRecord(name="traffic_car_tick_us_python", value=slow, unit="us", better="lower"),
            BenchRecord(name="traffic_car_tick_speedup", value=slow / fast, unit="x", better="higher")]


def _world_rtf(world: str, seconds: float) -> tuple[float, float, float]:
    """Median (CPU, wall, autonomy-free wall) real-time factor of :data:`CITY_REPEATS` runs of ``seconds`` of a
    shipped world, each from its first tick to the end of its run directory (setup and plots left out;
    :func:`simulator.bench.scaling.loop_rtf`); the third is each run's :func:`~simulator.bench.scaling.ceiling_rtf`
    with the agents' phase (estimation, fusion, guidance and their messages) free."""
    import yaml

    from simulator.bench.scaling import ceiling_rtf, loop_rtf
    from worlds.loader import shipped_worlds

    raw = yaml.safe_load(shipped_worlds()[world].read_text(encoding="utf-8"))
    raw["sim"]["duration_s"] = seconds
    rows = [loop_rtf(raw) for _ in range(CITY_REPEATS)]
    return (statistics.median(r["cpu_rtf"] for r in rows), statistics.median(r["rtf"] for r in rows),
            statistics.median(ceiling_rtf(r) for r in rows))


@benchmark("city_traffic", produces=("city_traffic_cpu_rtf_200cars", "city_traffic_rtf_200cars",
                                     "city_traffic_rtf_200cars_autonomy_free", "city_traffic_sumo_cpu_rtf_1000cars",
                                     "city_traffic_sumo_rtf_1000cars", "city_traffic_sumo_rtf_1000cars_autonomy_free"))
def bench_city_traffic() -> list[BenchRecord]:
    """Closed-loop real-time factor (CPU time, setup and plots left out; wall twin beside it; the median of
    :data:`CITY_REPEATS` runs) of helsinki_traffic_builtin (three radar UAVs with EKF and vector field tracking a
    physics car among 200 built-in traffic cars, 30 s) and of helsinki_traffic (the same among 1000 SUMO vehicles,
    20 s; left out when SUMO is not installed). Beside each, ``*_autonomy_free``: the wall real-time factor the same
    runs would have had with the agents' phase costing nothing, a ceiling measured in the same runs: no speed-up of
    the tracking, fusion and guidance alone can bring a world above it."""
    cpu, wall, free = _world_rtf("helsinki_traffic_builtin", 30.0)
    out = [BenchRecord(name="city_traffic_cpu_rtf_200cars", value=cpu, unit="x", target=5.0, better="higher"),
           BenchRecord(name="city_traffic_rtf_200cars", value=wall, unit="x", better="higher"),
           BenchRecord(name="city_traffic_rtf_200cars_autonomy_free", value=free, unit="x", better="higher")]
    from vehicles.sumo import sumo_available

    if sumo_available():
        cpu, wall, free = _world_rtf("helsinki_traffic", 20.0)
        out += [BenchRecord(name="city_traffic_sumo_cpu_rtf_1000cars", value=cpu, unit="x", target=2.0,
                            better="higher"),
                BenchRecord(name="city_traffic_sumo_rtf_1000cars", value=wall, unit="x", better="higher"),
                BenchRecord(name="city_traffic_sumo_rtf_1000cars_autonomy_free", value=free, unit="x",
                            better="higher")]
    return out
