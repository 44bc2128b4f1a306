"""Road constraints outside the physics loop: the same estimators on synthetic or recorded radar detections.

In the physics campaigns of paper 002 everything moves together: each column's UAVs fly on their own estimates, so
their radars see the car from other places, and the town's junctions and stops, the 150 m standoff and the motion
model all act at once. The experiments here take the estimators alone, fused as the agents fuse them (state-vector
fusion, each UAV with the latest estimate its teammate shared), on the same detections for every estimator:

- :func:`single_road_case`: the paper's conditions as far as they are known: a car doing stop-and-go along one curved
  two-way road with no junction, seen by the two radars of the paper from its 500 m standoff, 180° apart, orbiting at
  40 m/s;
- :func:`town_truth` + :func:`synthetic_scans`: the car trajectories recorded in the physics runs (the town, its
  junctions and stops) seen by those same synthetic radars, with the road filters on the whole town or only on the
  car's route (:func:`route_network`: the paper assigns the car to the segments of its road; junctions are its
  future work);
- :func:`recorded_case`: the physics runs' own detections (150 m standoff, the UAVs as flown), replayed.

:func:`fused_errors` runs one estimator type on a case and returns the errors the run metrics would give (mean
horizontal error of each UAV's fused estimate at its agent steps). Replaying a recorded run with the estimator it
flew reproduces that run's fused-error metrics exactly (``tests/simulator/test_road_replay.py``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["ESTIMATORS", "PAPER_FILTERS", "PAPER_RADARS", "curve_case", "curve_network",
           "SCAN_DT", "STOP_AND_GO", "ReplayCase", "ReplayJob", "car_accel_rms", "drive",
           "car_route", "fused_errors", "recorded_case", "route_network", "run_job", "sine_network",
           "single_road_case", "speeds", "synthetic_scans", "town_truth"]

PAPER_RADARS = ((20.0, math.radians(7.0)), (30.0, math.radians(5.0)))
"""Paper 002's two GMTI radars: (σ range m, σ azimuth rad), 2 Hz."""

STOP_AND_GO = ((0.0, 12.0), (20.0, 6.0), (35.0, 11.0), (60.0, 0.0), (78.0, 10.0), (105.0, 4.0), (115.0, 12.0))
"""(time s, target speed m/s) of the single-road car: slowing, a stop of about 7 s (target 0 from 60 s to 78 s, braking
from 11 m/s at 1 m/s²) and starts."""

SCAN_DT = 0.5
"""Radar period and agent step (s): the paper's T."""


@dataclass
class ReplayCase:
    """Detections and truth for a team of UAVs tracking one car.

    Attributes
    ----------
    network : RoadNetwork
        The road map the constrained estimators use.
    times : list[np.ndarray]
        Per UAV, its agent step times (s).
    scans : list[dict[float, list]]
        Per UAV, the detections handed to it at each step time.
    truth : np.ndarray
        (len(times[0]), 2) car position at the step times (m); the UAVs step at the same times.
    estimator : Callable[[str, int, dict], Any]
        ``estimator(type, uav index, params)``: a fresh estimator of that type for that UAV, with ``params``
        replacing fields of its tracker configuration (e.g. ``singer_sigma_a``).
    fusion : Callable[[int], Any]
        ``fusion(uav index)``: a fresh track-fusion object of that UAV.
    accel_rms : float
        RMS over time (stops included) of the car's acceleration along its heading over the case (m/s²).
    """

    network: Any
    times: list[np.ndarray]
    scans: list[dict[float, list]]
    truth: np.ndarray
    estimator: Callable[[str, int, dict], Any]
    fusion: Callable[[int], Any]
    accel_rms: float = float("nan")


# ----------------------------------------------------------------------------------------------- synthetic traffic
def speeds(t_end: float, dt: float, schedule: tuple[tuple[float, float], ...], a_max: float = 1.0) -> np.ndarray:
    """Speed (m/s) every ``dt`` s, moving toward the scheduled target speed at most ``a_max`` m/s²."""
    v = np.empty(int(round(t_end / dt)) + 1)
    v[0] = schedule[0][1]
    for i in range(len(v) - 1):
        target = [vt for ts, vt in schedule if ts <= i * dt][-1]
        v[i + 1] = v[i] + np.clip(target - v[i], -a_max * dt, a_max * dt)
    return v


def drive(roads: list, t_end: float, schedule: tuple[tuple[float, float], ...], dt: float = SCAN_DT,
          substeps: int = 20) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """A kinematic car in lane 0 along consecutive ``roads`` at the speed ``schedule``: times every ``dt`` s,
    positions (M, 2) m and road ids."""
    h = dt / substeps
    v = speeds(t_end, h, schedule)
    k, s = 0, 0.0
    ts, ps, ids = [], [], []
    for i in range(len(v)):
        if i % substeps == 0:
            ts.append(i * h)
            ps.append(roads[k].point(s, roads[k].lane_offset(0)))
            ids.append(roads[k].id)
        s += v[i] * h
        while s > roads[k].length and k + 1 < len(roads):
            s -= roads[k].length
            k += 1
    return np.array(ts), np.array(ps), ids


def sine_network() -> Any:
    """A curved two-way street: vertices every 20 m on a 150 m-amplitude, 700 m-wavelength sine (radius >= 80 m)."""
    from worlds.roads.network import RoadNetwork

    x = np.arange(0.0, 1500.0 + 1e-9, 20.0)
    y = 150.0 * np.sin(2 * np.pi * x / 700.0)
    return RoadNetwork.from_spec({"nodes": {"a": [0.0, 0.0], "b": [x[-1], y[-1]]},
                                  "streets": [{"id": "s", "nodes": ["a", "b"], "via": np.c_[x, y][1:-1].tolist()}]})


def synthetic_scans(ts: np.ndarray, ps: np.ndarray, rng: np.random.Generator, *, standoff: float = 500.0,
                    speed: float = 40.0, altitude: float = 100.0,
                    radars: tuple[tuple[float, float], ...] = PAPER_RADARS) -> list[dict[float, list]]:
    """Per radar, its (slant range, azimuth) measurements of the car at ``ps`` (M, 2) m at times ``ts`` (s), from a
    sensor circling the car at ``standoff`` m and ``speed`` m/s, ``altitude`` m up, the radars 180° apart."""
    from autonomy.estimation.measurements import Measurement

    out: list[dict[float, list]] = [{} for _ in radars]
    omega = speed / standoff
    for t, p in zip(ts, ps, strict=True):
        for j, (sr, sa) in enumerate(radars):
            phase = omega * t + 2.0 * np.pi * j / len(radars)
            p_s = np.array([p[0] + standoff * np.cos(phase), p[1] + standoff * np.sin(phase), altitude])
            d = np.array([p[0], p[1], 0.0]) - p_s
            z = np.array([np.linalg.norm(d), np.arctan2(d[1], d[0])]) + rng.normal(size=2) * [sr, sa]
            out[j][float(t)] = [Measurement(z=z, R=np.diag([sr**2, sa**2]), t_meas=float(t), sensor_id=j,
                                            p_sensor_W=p_s)]
    return out


def _paper_estimator(network: Any) -> Callable[[str, int, dict], Any]:
    """Paper 002's estimators (Table I's Singer model; road filters on ``network``) by type, as the world builds
    them: ``maekf`` / ``ecukf`` with the road filters' defaults (our additions), ``maekf_paper`` / ``ecukf_paper``
    with the paper's filters (:data:`simulator.reproduce.paper_002_configs.PAPER_ROAD`)."""
    from dataclasses import replace

    from autonomy.estimation.road.config import RoadFilterConfig
    from autonomy.estimation.road.tracker import RoadConstrainedTracker, RoadTrackerConfig
    from autonomy.estimation.tracker import SingleTargetTracker
    from simulator.builders.common import config_from
    from simulator.builders.estimators import ROAD_FALLBACK_FILTER
    from simulator.reproduce.paper_002_configs import PAPER_ROAD

    def make(kind: str, index: int, params: dict) -> Any:
        base = replace(RoadTrackerConfig().tracker, **params)
        variant, _, paper = kind.partition("_")
        if variant in ROAD_FALLBACK_FILTER:
            road = config_from(RoadFilterConfig, PAPER_ROAD if paper else {}, variant=variant)
            return RoadConstrainedTracker(RoadTrackerConfig(
                tracker=replace(base, filter=ROAD_FALLBACK_FILTER[variant]), road=road), network)
        return SingleTargetTracker(replace(base, filter=kind))

    return make


def _convex_fusion(index: int) -> Any:
    from autonomy.fusion.track_fusion import TrackFusion, TrackFusionConfig

    return TrackFusion(TrackFusionConfig(method="convex"))


def curve_network(seed: int) -> Any:
    """A seeded curved one-way arterial (the evaluation scenes; :func:`sine_network` is the tuning and unit-test
    fixture): vertices every 10 m over 2 km along x on a sum of three sines (wavelengths 300–900 m, random phases),
    scaled so that ``Σ A_k (2π/λ_k)² = 1/60`` m⁻¹ (radius >= 60 m) with amplitudes of at most 200 m in all."""
    from worlds.roads.network import RoadNetwork

    rng = np.random.default_rng([seed, 2002])
    lam = rng.uniform(300.0, 900.0, 3)
    amp = rng.uniform(0.3, 1.0, 3)
    phase = rng.uniform(0.0, 2 * np.pi, 3)
    amp *= min((1.0 / 60.0) / float(np.sum(amp * (2 * np.pi / lam) ** 2)), 200.0 / float(np.sum(amp)))
    x = np.arange(0.0, 2000.0 + 1e-9, 10.0)
    y = np.sum(amp[:, None] * np.sin(2 * np.pi * x[None] / lam[:, None] + phase[:, None]), axis=0)
    return RoadNetwork.from_spec({"nodes": {"a": [0.0, float(y[0])], "b": [x[-1], float(y[-1])]},
                                  "streets": [{"id": "s", "nodes": ["a", "b"], "via": np.c_[x, y][1:-1].tolist(),
                                               "two_way": False}]})


def curve_case(seed: int, duration: float = 150.0) -> ReplayCase:
    """The single-road car (:data:`STOP_AND_GO`) on :func:`curve_network` ``(seed)``, the paper's radars at 500 m
    (noise from ``seed`` too, another stream)."""
    net = curve_network(seed)
    substeps = 20
    ts, ps, _ = drive([net.roads["s.f"]], duration, STOP_AND_GO, substeps=substeps)
    scans = synthetic_scans(ts, ps, np.random.default_rng([seed, 1]))
    h = SCAN_DT / substeps
    accel = np.diff(speeds(duration, h, STOP_AND_GO)) / h
    return ReplayCase(network=net, times=[ts, ts], scans=scans, truth=ps, estimator=_paper_estimator(net),
                      fusion=_convex_fusion, accel_rms=float(np.sqrt(np.mean(accel**2))))


def single_road_case(seed: int, duration: float = 150.0) -> ReplayCase:
    """The paper's conditions: the single-road car (:data:`STOP_AND_GO` on :func:`sine_network`) and the paper's
    radars at 500 m (module docstring); radar noise from ``seed``."""
    net = sine_network()
    substeps = 20
    ts, ps, _ = drive([net.roads["s.f"]], duration, STOP_AND_GO, substeps=substeps)
    scans = synthetic_scans(ts, ps, np.random.default_rng(seed))
    h = SCAN_DT / substeps
    accel = np.diff(speeds(duration, h, STOP_AND_GO)) / h  # along-track: the car follows the road at these speeds
    return ReplayCase(network=net, times=[ts, ts], scans=scans, truth=ps, estimator=_paper_estimator(net),
                      fusion=_convex_fusion, accel_rms=float(np.sqrt(np.mean(accel**2))))


# ------------------------------------------------------------------------------------------------- recorded runs
def _load_world(run_dir: Path, kind: str | None = None, params: dict | None = None) -> Any:
    """The run's resolved world, with every UAV's estimator set to ``kind`` and ``params`` added to its params."""
    from worlds.loader import load_world

    world = load_world(run_dir / "world.yaml").world
    if kind is None and not params:
        return world
    sets = []
    for i in range(len(world.uavs)):
        if kind is not None:
            sets.append(f"uavs[{i}].autonomy.estimator.type={kind}")
        sets += [f"uavs[{i}].autonomy.estimator.params.{k}={v!r}" for k, v in (params or {}).items()]
    return load_world(run_dir / "world.yaml", sets).world


def _network(run_dir: Path, world: Any) -> Any:
    import json

    from simulator.seeding import RunSeeds
    from worlds.build import build_geometry

    seed = json.loads((run_dir / "run.json").read_text())["seed"]
    return build_geometry(world, run_dir / "world.yaml", RunSeeds(seed).generator("world/town")).network


def _agent_times(run_dir: Path, n_uavs: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per UAV, its agent step ticks and times, from the estimates stream."""
    from simulator.runrecord import load_stream

    e = load_stream(run_dir / "timeseries" / "estimates")
    return ([e["tick"][e["uav"] == i] for i in range(n_uavs)], [e["t"][e["uav"] == i] for i in range(n_uavs)])


def _car_truth(run_dir: Path, ticks: np.ndarray, vehicle: int = 0) -> np.ndarray:
    """The car's recorded positions (M, 2) m at ``ticks``."""
    from simulator.runrecord import load_stream

    v = load_stream(run_dir / "timeseries" / "vehicle_truth")
    own = v["vehicle"] == vehicle
    row = {int(k): j for j, k in enumerate(v["tick"][own])}
    xy = np.c_[v["x"][own], v["y"][own]]
    return xy[[row[int(k)] for k in ticks]]


def town_truth(run_dir: str | Path) -> tuple[Any, np.ndarray, np.ndarray, float]:
    """(network, step times s, car positions (M, 2) m, RMS along-track acceleration m/s²) of a recorded
    ``road_standoff`` run, at its first UAV's agent steps."""
    run_dir = Path(run_dir)
    world = _load_world(run_dir)
    ticks, times = _agent_times(run_dir, len(world.uavs))
    return _network(run_dir, world), times[0], _car_truth(run_dir, ticks[0]), car_accel_rms(run_dir)


def car_route(run_dir: str | Path, vehicle: int = 0) -> list[str]:
    """The roads the car recorded in ``run_dir`` drove on, in order (each once)."""
    from simulator.runrecord import load_stream

    v = load_stream(Path(run_dir) / "timeseries" / "vehicle_truth")
    out: list[str] = []
    for rid in v["road"][v["vehicle"] == vehicle]:
        rid = str(rid)
        if rid and rid not in out:
            out.append(rid)
    return out


def route_network(network: Any, route: list[str]) -> Any:
    """The part of ``network`` a filter that knows the car's ``route`` needs: the route's roads and their twins (so
    the direction is still the filter's to find), so that every road on it has its next one as its only successor
    unless the route passes a junction twice."""
    from worlds.roads.network import RoadNetwork

    ids = set(route) | {network.roads[r].twin for r in route if network.roads[r].twin is not None}
    roads = [network.roads[r] for r in sorted(ids)]
    nodes = {n: network.nodes[n] for r in roads for n in (r.start_node, r.end_node)}
    return RoadNetwork(roads, nodes)


def recorded_case(run_dir: str | Path) -> ReplayCase:
    """The detections of a recorded run, handed to each UAV at the agent step they reached it in the run."""
    from autonomy.fusion.track_fusion import TrackFusion, TrackFusionConfig
    from autonomy.sensing.measurement import Detection
    from simulator.registry import build_estimator, build_sensor
    from simulator.runrecord import load_stream

    run_dir = Path(run_dir)
    world = _load_world(run_dir)
    network = _network(run_dir, world)
    n = len(world.uavs)
    ticks, times = _agent_times(run_dir, n)
    d = load_stream(run_dir / "timeseries" / "detections")
    u = load_stream(run_dir / "timeseries" / "uav_truth")
    pose = {(int(k), int(i)): np.array([x, y, z]) for k, i, x, y, z in zip(u["tick"], u["uav"], u["x"], u["y"],
                                                                             u["z"], strict=True)}
    noise: dict[str, np.ndarray] = {}
    scans: list[dict[float, list]] = [{float(t): [] for t in times[i]} for i in range(n)]
    for j in range(len(d["tick"])):
        i, name = int(d["uav"][j]), str(d["sensor"][j])
        if name not in noise:
            k = int(name.rsplit("radar", 1)[1])
            noise[name] = build_sensor(world.uavs[i].sensors[k], name).config.R
        R = noise[name]
        z = np.array([d[f"z{c}"][j] for c in range(R.shape[0])])
        det = Detection(z=z, R=R, t_meas=float(d["t_meas"][j]), t_arrival=float(d["t_arrival"][j]),
                        sensor_id=name, p_sensor_W=pose[(int(d["tick"][j]), i)], kind=str(d["kind"][j]))
        at = int(np.searchsorted(times[i], det.t_arrival - 1e-9))  # the first step at or after its arrival
        if at < len(times[i]):
            scans[i][float(times[i][at])].append(det)

    def make(kind: str, index: int, params: dict) -> Any:
        return build_estimator(_load_world(run_dir, kind, params).uavs[index], index, network)

    def fusion(index: int) -> Any:
        f = world.uavs[index].autonomy.fusion
        return TrackFusion(TrackFusionConfig(method=f.method, max_age_s=f.max_age_s, q=f.q,
                                                   switch_margin=f.switch_margin))

    return ReplayCase(network=network, times=times, scans=scans, truth=_car_truth(run_dir, ticks[0]), estimator=make,
                      fusion=fusion, accel_rms=car_accel_rms(run_dir))


# -------------------------------------------------------------------------------------------------------- replay
def fused_errors(case: ReplayCase, kind: str, tracker_params: dict | None = None) -> dict[str, np.ndarray]:
    """Run estimator ``kind`` on every UAV of ``case`` and fuse as the agents do (they step in index order; each
    fuses its own estimate with the latest one every teammate shared: this step's from the UAVs before it, the last
    step's from those after it).

    ``tracker_params`` replaces fields of the tracker configuration (e.g. ``singer_sigma_a``).

    Returns ``local`` and ``fused``: (n_uavs,) mean horizontal error (m) of each UAV's own and fused estimates over
    its steps with an estimate, as the run metrics count them.
    """
    n = len(case.times)
    if any(len(t) != len(case.times[0]) for t in case.times):
        raise ValueError("fused_errors: the UAVs must step at the same times")
    trackers = [case.estimator(kind, i, dict(tracker_params or {})) for i in range(n)]
    fusions = [case.fusion(i) for i in range(n)]
    shared: list[Any] = [None] * n
    err_local: list[list[float]] = [[] for _ in range(n)]
    err_fused: list[list[float]] = [[] for _ in range(n)]
    for k, p_true in enumerate(case.truth):
        for i in range(n):
            t = float(case.times[i][k])
            own = trackers[i].step(t, case.scans[i].get(t, []))
            fused = fusions[i].fuse(t, own, [e for j, e in enumerate(shared) if j != i and e is not None])
            shared[i] = own
            if own is not None:
                err_local[i].append(float(np.linalg.norm(own.p_W[:2] - p_true)))
            if fused is not None:
                err_fused[i].append(float(np.linalg.norm(fused.p_W[:2] - p_true)))
    mean = lambda e: np.array([np.mean(x) if x else np.nan for x in e])  # noqa: E731
    return {"local": mean(err_local), "fused": mean(err_fused)}


# ---------------------------------------------------------------------------------------------------- experiments
ESTIMATORS = ("ekf", "maekf", "ecukf")
"""The estimator types every experiment compares: the unconstrained EKF and the two road-constrained filters."""

PAPER_FILTERS = ("ekf", "maekf_paper", "ecukf_paper", "maekf", "ecukf")
"""The paper's road filters beside ours (``filters`` of a :class:`ReplayJob`)."""


@dataclass(frozen=True)
class ReplayJob:
    """One run of an experiment: ``case`` is ``"single_road"`` (``seed`` draws the radar noise), ``"town_paper"``
    (the car of ``run_dir`` seen by the paper's radars, noise from ``seed``), ``"town_paper_route"`` (the same, the
    road filters on the car's route only: :func:`route_network`) or ``"recorded"`` (the detections of
    ``run_dir``; with ``sigma_a`` also every estimator with that Singer σa, m/s²); ``duration`` (s) of the single-road
    drive."""

    case: str
    seed: int
    run_dir: str | None = None
    sigma_a: float | None = None
    duration: float = 150.0
    filters: tuple[str, ...] = ESTIMATORS


def run_job(job: ReplayJob) -> dict[str, Any]:
    """Mean fused error (m, over the UAVs) per estimator of :data:`ESTIMATORS` (keys ``<type>`` and, with ``sigma_a``,
    ``<type>@sigma_a``), and the car's RMS acceleration along its heading (``accel_rms``, m/s²).

    A job that fails (e.g. a run record without detections) gives NaN for every figure and its error under ``error``,
    so one bad run does not stop a report.
    """
    try:
        return _run_job(job)
    except Exception as exc:  # reported by the caller, never hidden
        keys = [*job.filters, *(f"{k}@sigma_a" for k in job.filters if job.sigma_a is not None), "accel_rms"]
        return {**{k: float("nan") for k in keys}, "error": f"{type(exc).__name__}: {exc}"}


def _run_job(job: ReplayJob) -> dict[str, Any]:
    if job.case == "single_road":
        case = single_road_case(job.seed, job.duration)
    elif job.case == "curve":
        case = curve_case(job.seed, job.duration)
    elif job.case in ("town_paper", "town_paper_route"):
        net, ts, ps, accel = town_truth(job.run_dir)
        if job.case == "town_paper_route":
            net = route_network(net, car_route(job.run_dir))
        case = ReplayCase(network=net, times=[ts, ts], scans=synthetic_scans(ts, ps, np.random.default_rng(job.seed)),
                          truth=ps, estimator=_paper_estimator(net), fusion=_convex_fusion, accel_rms=accel)
    elif job.case == "recorded":
        case = recorded_case(job.run_dir)
    else:
        raise ValueError(f"ReplayJob.case must be single_road, town_paper, town_paper_route, recorded or "
                         f"curve, "
                         f"got {job.case!r}")
    out = {kind: float(np.mean(fused_errors(case, kind)["fused"])) for kind in job.filters}
    if job.sigma_a is not None:
        model = {"singer_sigma_a": job.sigma_a}
        out.update({f"{kind}@sigma_a": float(np.mean(fused_errors(case, kind, model)["fused"]))
                    for kind in job.filters})
    out["accel_rms"] = case.accel_rms
    return out


def car_accel_rms(run_dir: str | Path, vehicle: int = 0) -> float:
    """RMS over time (stops included) of the acceleration along its heading (m/s²) of the car recorded in ``run_dir``
    (its physics accelerations at the record rate)."""
    from simulator.runrecord import load_stream

    v = load_stream(Path(run_dir) / "timeseries" / "vehicle_truth")
    own = v["vehicle"] == vehicle
    a_t = v["ax"][own] * np.cos(v["yaw"][own]) + v["ay"][own] * np.sin(v["yaw"][own])
    return float(np.sqrt(np.mean(a_t**2))) if a_t.size else float("nan")
