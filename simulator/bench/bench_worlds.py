"""Benchmarks of world building: procedural town generation, OpenStreetMap import and road queries."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from simulator.bench.registry import BenchRecord, benchmark, median_of, time_call
from worlds.osm import load_osm
from worlds.town import TownConfig, generate_town

HELSINKI = Path(__file__).resolve().parents[2] / "assets" / "maps" / "helsinki.osm.pbf"
TOWN_500 = TownConfig(extent=(1000.0, 1000.0), block_size=100.0, max_buildings=500)
REPEATS = 5
PROJECT_QUERIES = 2000


@benchmark("town_generate", produces=("town_generate_s_500",))
def bench_town_generate() -> list[BenchRecord]:
    """Seconds to generate a 500-building town (10 x 10 blocks, curved arterials), median of 5."""
    seconds = median_of(lambda: time_call(lambda: generate_town(TOWN_500, np.random.default_rng(0))), REPEATS)
    return [BenchRecord(name="town_generate_s_500", value=seconds, unit="s", target=None, better="lower")]


@benchmark("helsinki_import", produces=("helsinki_import_s", "road_project_us", "network_nearest_us"))
def bench_helsinki_import() -> list[BenchRecord]:
    """Seconds to parse the Helsinki extract and build its network and buildings (median of 5); then the cost of one
    ``Road.project`` (target 50 us, the per-tick budget of a driver) and one ``RoadNetwork.nearest`` on it."""
    seconds = median_of(lambda: time_call(lambda: load_osm(HELSINKI)), REPEATS)
    net = load_osm(HELSINKI).network
    rng = np.random.default_rng(0)
    roads = list(net.roads.values())
    picks = [roads[k] for k in rng.integers(len(roads), size=PROJECT_QUERIES)]
    pts = [r.point(rng.uniform(0, r.length), rng.uniform(-4, 4)) for r in picks]

    def per_call(fn) -> float:
        t0 = time.perf_counter()
        for r, p in zip(picks, pts, strict=True):
            fn(r, p)
        return (time.perf_counter() - t0) / PROJECT_QUERIES * 1e6

    project_us = median_of(lambda: per_call(lambda r, p: r.project(p)), REPEATS)
    nearest_us = median_of(lambda: per_call(lambda r, p: net.nearest(p)), REPEATS)
    return [BenchRecord(name="helsinki_import_s", value=seconds, unit="s", target=None, better="lower"),
            BenchRecord(name="road_project_us", value=project_us, unit="us", target=50.0, better="lower"),
            BenchRecord(name="network_nearest_us", value=nearest_us, unit="us", target=None, better="lower")]
