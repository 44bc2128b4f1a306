"""Benchmarks of the simulator core: static scene build time and closed-loop real-time factor of whole worlds."""

from __future__ import annotations

import json
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from simulator.bench.registry import BenchRecord, benchmark, median_of

__all__: list[str] = []


def _scene_build_s(buildings: list, network: object | None) -> float:
    from simulator.scene import Scene, SceneConfig
    from worlds.roads.mesh import road_surface_mesh

    t0 = time.perf_counter()
    scene = Scene.create(SceneConfig())
    scene.add_buildings(buildings)
    if network is not None:
        scene.add_road_surface(road_surface_mesh(network))
    dt = time.perf_counter() - t0
    scene.close()
    return dt


@benchmark("scene_build", produces=("scene_build_s_town500", "scene_build_s_helsinki", "scene_step_ms_town500"))
def bench_scene_build() -> list[BenchRecord]:
    """PyBullet scene build (buildings + road surface) for a 500-building town and the Helsinki extract."""
    from simulator.scene import Scene, SceneConfig
    from worlds.geometry import Building

    rng = np.random.default_rng(0)
    blds = [Building.cuboid((40.0 * (i % 25), 40.0 * (i // 25)), (20.0, 15.0, float(rng.uniform(8, 40))),
                            float(rng.uniform(0, np.pi))) for i in range(500)]
    records = [BenchRecord(name="scene_build_s_town500", value=median_of(lambda: _scene_build_s(blds, None)),
                           unit="s", target=2.0, better="lower")]
    scene = Scene.create(SceneConfig())
    scene.add_buildings(blds)
    t0 = time.perf_counter()
    for _ in range(2400):
        scene.step()
    records.append(BenchRecord(name="scene_step_ms_town500", value=(time.perf_counter() - t0) / 2400 * 1e3,
                               unit="ms", better="lower"))
    scene.close()
    try:
        from worlds.build import resolve_map_path
        from worlds.osm import load_osm

        town = load_osm(resolve_map_path("helsinki.osm.pbf", Path(".")))
        records.append(BenchRecord(name="scene_build_s_helsinki",
                                   value=median_of(lambda: _scene_build_s(list(town.buildings), town.network), 3),
                                   unit="s", target=2.0, better="lower"))
    except (ImportError, FileNotFoundError):
        pass
    return records


def _world_rtf(name: str, duration: float | None = None, overrides: tuple[str, ...] = ()) -> tuple[float, float, float]:
    """(real-time factor of the whole run, of its loop alone: simulated time over the wall time after setup, and the
    bound its autonomy alone sets: simulated time over the wall time of the agents' phase) of a run of the shipped
    world ``name`` (its own duration unless ``duration``)."""
    from simulator.api import run

    with tempfile.TemporaryDirectory() as tmp:
        result = run(name, duration=duration, overrides=overrides, out_dir=tmp, plots=False)
        if result.status != "completed":
            raise RuntimeError(f"{name} did not complete: {result.error}")
        m = result.metrics
        phases = m["wall_time_breakdown_s"]
        loop = m["wall_time_s"] - phases["setup"]
        autonomy = phases.get("autonomy", 0.0)
        return (float(m["real_time_factor"]), float(m["sim_time_s"] / loop),
                float(m["sim_time_s"] / autonomy) if autonomy > 0 else math.inf)


def _median_rtf(name: str, repeats: int = 3, **kw) -> tuple[float, ...]:
    runs = [_world_rtf(name, **kw) for _ in range(repeats)]
    return tuple(statistics.median(r[k] for r in runs) for k in range(len(runs[0])))


def _paired_rtf(name: str, overrides: tuple[str, ...], variant: tuple[str, ...],
                repeats: int = 3) -> tuple[tuple[float, ...], tuple[float, ...], float]:
    """Runs of the shipped world ``name`` with ``overrides`` alternating with runs that add the ``variant``
    overrides (``repeats`` of each, so both see the same load of a shared machine): the medians of each figure of
    :func:`_world_rtf` for each, and the median over the pairs of the variant's real-time factor over the
    reference's."""
    ref, var = [], []
    for _ in range(repeats):
        ref.append(_world_rtf(name, overrides=overrides))
        var.append(_world_rtf(name, overrides=overrides + variant))
    med = statistics.median
    return (tuple(med(r[k] for r in ref) for k in range(len(ref[0]))),
            tuple(med(r[k] for r in var) for k in range(len(var[0]))),
            med(v[0] / r[0] for r, v in zip(ref, var, strict=True)))


def _radar_only(world: str) -> tuple[str, ...]:
    """Overrides that keep only each UAV's first sensor (its radar) in the shipped world ``world``."""
    from worlds.loader import load_world

    loaded = load_world(world)
    out = []
    for i, uav in enumerate(loaded.raw.get("uavs", [])):
        radar = [s for s in uav.get("sensors", []) if s.get("type") == "radar"][:1]
        out.append(f"uavs[{i}].sensors=" + json.dumps(radar))
    return tuple(out)


def _kinematic_cars(world: str) -> tuple[str, ...]:
    """Overrides that make every ground vehicle of the shipped world ``world`` kinematic."""
    from worlds.loader import load_world

    n = len(load_world(world).world.ground_vehicles)
    return tuple(f"ground_vehicles[{i}].dynamics=kinematic" for i in range(n))


def _world_records(prefix: str, target: float | None, physics: tuple[float, ...], kinematic: tuple[float, ...],
                   speedup: float) -> list[BenchRecord]:
    """The records of one world run with its physics cars and with kinematic cars (see :func:`bench_world_rtf`)."""
    return [BenchRecord(name=f"{prefix}_rtf", value=physics[0], unit="x", target=target, better="higher"),
            BenchRecord(name=f"{prefix}_loop_rtf", value=physics[1], unit="x", better="higher"),
            BenchRecord(name=f"{prefix}_autonomy_bound_rtf", value=physics[2], unit="x", better="higher"),
            BenchRecord(name=f"{prefix}_kinematic_rtf", value=kinematic[0], unit="x", target=target, better="higher"),
            BenchRecord(name=f"{prefix}_kinematic_loop_rtf", value=kinematic[1], unit="x", better="higher"),
            BenchRecord(name=f"{prefix}_kinematic_speedup", value=speedup, unit="x", better="higher")]


@benchmark("world_rtf", produces=tuple(f"{w}_{k}" for w in ("road_standoff", "helsinki_chase")
                                       for k in ("rtf", "loop_rtf", "autonomy_bound_rtf", "kinematic_rtf",
                                                 "kinematic_loop_rtf", "kinematic_speedup")) + ("demo_rtf",))
def bench_world_rtf() -> list[BenchRecord]:
    """Closed-loop real-time factors of shipped worlds run for their own duration (median of 3 runs each): the demo
    world (2 quadrotors, 1 car, radars, EKF, vector-field guidance; 60 s), paper 002's ``road_standoff`` (2
    quadrotors, 1 car in a town, radars, EKF, fusion, NMPC at 2 Hz; 120 s) and ``helsinki_chase`` without its
    cameras (3 quadrotors, radars, ECUKF on the city's roads, covariance intersection, NMPC among the buildings, a
    building-blocked radio; 120 s). No absolute targets: they were retired for ratios to the physics floor measured
    in the same call (``bench_floor``: ``*_floor_ratio``). ``*_loop_rtf``: the same runs without their setup (world,
    solvers and scene: ≈ 1-1.5 s per run with warm caches; ``wall_time_breakdown_s`` of the metrics says where the
    rest goes). ``*_autonomy_bound_rtf``: the simulated time over the wall time of the agents' phase alone
    (estimation, fusion, guidance, the radio messages they send): the real-time factor the world could reach if its
    physics, vehicles, sensors and records cost nothing; a target above it cannot be met without a cheaper autonomy.

    ``*_kinematic_*``: the same two worlds with every ground vehicle kinematic (``ground_vehicles[i].dynamics:
    kinematic``: a kinematic bicycle carrying a box instead of the multibody car), each run alternating with a run
    of the shipped world so both see the same load; ``*_kinematic_speedup`` is the median over those pairs of the
    kinematic run's real-time factor over the physics run's."""
    demo = _median_rtf("demo")[0]
    out = [BenchRecord(name="demo_rtf", value=demo, unit="x", better="higher")]
    for world, target, overrides in (("road_standoff", None, ()),
                                     ("helsinki_chase", None, _radar_only("helsinki_chase"))):
        out += _world_records(world, target, *_paired_rtf(world, overrides, _kinematic_cars(world)))
    return out


_CAMPAIGN_RUNS = 4


@benchmark("campaign_road_standoff", produces=("road_standoff_campaign_100_runs_min", "campaign_run_overhead_ratio"))
def bench_campaign() -> list[BenchRecord]:
    """Wall time of a 100-run ``road_standoff`` campaign on this machine's cores, extrapolated from a campaign of
    ``_CAMPAIGN_RUNS`` full-length runs (120 s simulated each) on the local process pool: its wall time per round of
    runs (ceil(runs / workers) rounds) times the ceil(100 / workers) rounds of 100 runs. Measuring all 100 takes
    ≈ 20–40 min here: run ``skytrack campaign road_standoff --runs 100`` for the real figure.

    ``campaign_run_overhead_ratio`` is the campaign's wall time over its runs' mean wall time times the rounds:
    ≈ 1 when the pool keeps both cores busy (process start-up, imports and journaling are small).
    """
    import os

    from simulator.campaign.config import CampaignConfig
    from simulator.campaign.runner import run_campaign

    workers = os.cpu_count() or 1
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        res = run_campaign(CampaignConfig(world="road_standoff", runs=_CAMPAIGN_RUNS, out_dir=Path(tmp),
                                          workers=workers))
        wall = time.perf_counter() - t0
    failed = [r for r in res.reports if r.status != "completed"]
    if failed:
        raise RuntimeError(f"{len(failed)} campaign runs did not complete: {failed[0].error}")
    run_walls = [r.wall_time_s for r in res.reports]
    waves = math.ceil(_CAMPAIGN_RUNS / workers)  # rounds of runs the pool needed; 100 runs need ceil(100 / workers)
    ideal = sum(run_walls) / _CAMPAIGN_RUNS * waves
    return [BenchRecord(name="road_standoff_campaign_100_runs_min", value=wall / waves * math.ceil(100 / workers) / 60,
                        unit="min", better="lower"),
            BenchRecord(name="campaign_run_overhead_ratio", value=wall / ideal, unit="x", better="lower")]


@benchmark("traffic_rtf", produces=("road_standoff_traffic_rtf", "road_standoff_traffic_alone_rtf",
                                    "road_standoff_traffic_autonomy_share",
                                    "road_standoff_traffic_alone_autonomy_share", "traffic_autonomy_share_growth",
                                    "traffic_autonomy_cost_ratio", "traffic_rtf_ratio"))
def bench_traffic_rtf() -> list[BenchRecord]:
    """``road_standoff_traffic`` as shipped (24 kinematic traffic cars; 60 s) alternating with the same world without
    its traffic (the same UAVs, sensors and multi-target tracker), 3 runs each, so both see the same load of a shared
    machine: their real-time factors, the autonomy's share of each run's loop (the agents' phase: tracking, identity,
    track association and fusion, NMPC) and the median over the pairs of the traffic run's share over the other's
    (target: below 2, the autonomy's share less than doubles from no traffic to 24 cars), of the agents' wall time per
    simulated second (``traffic_autonomy_cost_ratio``: what tracking 25 cars costs over tracking one) and of the
    real-time factor. ``road_standoff_rtf`` (``world_rtf``) is the paper's world without traffic, for comparison."""
    from simulator.reproduce.paper_002_traffic import _world_overrides

    alone = _world_overrides("alone")
    ref, var = [], []
    for _ in range(3):
        ref.append(_world_rtf("road_standoff_traffic", duration=60.0, overrides=alone))
        var.append(_world_rtf("road_standoff_traffic", duration=60.0))
    med = statistics.median
    share = lambda r: r[1] / r[2]  # noqa: E731 - the loop's wall time over the autonomy's: autonomy / loop
    return [
        BenchRecord(name="road_standoff_traffic_rtf", value=med(v[0] for v in var), unit="x", better="higher"),
        BenchRecord(name="road_standoff_traffic_alone_rtf", value=med(r[0] for r in ref), unit="x", better="higher"),
        BenchRecord(name="road_standoff_traffic_autonomy_share", value=med(share(v) for v in var), unit="",
                    better="lower"),
        BenchRecord(name="road_standoff_traffic_alone_autonomy_share", value=med(share(r) for r in ref), unit="",
                    better="lower"),
        BenchRecord(name="traffic_autonomy_share_growth",
                    value=med(share(v) / share(r) for r, v in zip(ref, var, strict=True)), unit="x", target=2.0,
                    better="lower"),
        BenchRecord(name="traffic_autonomy_cost_ratio",  # the agents' wall time per simulated second, over alone's
                    value=med(r[2] / v[2] for r, v in zip(ref, var, strict=True)), unit="x", better="lower"),
        BenchRecord(name="traffic_rtf_ratio", value=med(v[0] / r[0] for r, v in zip(ref, var, strict=True)),
                    unit="x", better="higher"),
    ]
