"""Set-membership search benchmarks (Ibenenthal et al.): one team step and a whole decoy mission.

The scenario is the paper's section V (:class:`~simulator.kinematic.search_mission.MissionConfig` defaults): a
500 m x 500 m area, 5 random cuboid obstacles 30-70 m wide and 100 m tall, 2 targets and 2 decoys at 5 km/h,
4 UAVs at 100 m and 60 km/h with the 45 deg box sensor, T = 1 s.

- ``search_step_ms``: one step of the whole team (4 estimators: predict, correct, fuse; the sequential search MPC of
  4 UAVs; the box sensors and the target motion), after a 40-step warm-up so the sets have realistic shapes;
  median over steps of the CPU time per step.
- ``search_decoys_mission_s``: CPU time of one 400-step mission (the paper's MATLAB took 2700 s), one run (a second
  one would not fit the one-minute budget of a benchmark); the same run gives ``search_mission_guarantee_pct``
  (checks of a true target inside ``X U Xbar``, must be 100), ``search_mission_xbar_final`` and
  ``search_mission_x_final`` (team-mean ``phi / phi(X_s)`` at step 400).

CPU time of this process (``time.process_time``) is reported: the work is single-threaded, and on a shared machine
wall time mostly measures waiting for a core.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from simulator.bench.registry import BenchRecord, benchmark
from simulator.kinematic.search_mission import MissionConfig, SearchMission, line_of_sight_graph

WARMUP_STEPS = 40
TIMED_STEPS = 30
MISSION_STEPS = 400


@benchmark("search_step", produces=("search_step_ms",))
def bench_search_step() -> list[BenchRecord]:
    mission = SearchMission(MissionConfig(steps=WARMUP_STEPS + TIMED_STEPS), np.random.default_rng(7))
    links = line_of_sight_graph(mission.uav_xy, mission.obstacles)
    for _ in range(WARMUP_STEPS):
        links = mission.step(links)
    times = []
    for _ in range(TIMED_STEPS):
        t0 = time.process_time()
        links = mission.step(links)
        times.append(time.process_time() - t0)
    return [BenchRecord(name="search_step_ms", value=1e3 * statistics.median(times), unit="ms", better="lower")]


@benchmark("search_decoys_mission", produces=("search_decoys_mission_s", "search_mission_guarantee_pct",
                                                "search_mission_xbar_final", "search_mission_x_final"))
def bench_search_mission() -> list[BenchRecord]:
    mission = SearchMission(MissionConfig(steps=MISSION_STEPS), np.random.default_rng(1))
    t0 = time.process_time()
    res = mission.run()
    cpu = time.process_time() - t0
    return [
        BenchRecord(name="search_decoys_mission_s", value=cpu, unit="s", target=60.0, better="lower"),
        BenchRecord(name="search_mission_guarantee_pct", value=100.0 * res.guarantee_rate, unit="%", target=100.0,
                    better="higher"),
        BenchRecord(name="search_mission_xbar_final", value=float(res.area_Xbar[-1].mean()), unit="x",
                    better="lower"),
        BenchRecord(name="search_mission_x_final", value=float(res.area_X[-1].mean()), unit="x", better="lower"),
    ]
