"""Road-constrained filter benchmarks: one predict + update of MAEKF / ECUKF (paper 002) with a radar measurement.

The scenario: a car on a curved road (vertices every 20 m on a 150 m-amplitude sine, resampled every 10 m for the
biarc fit) at 12 m/s, a radar at 500 m standoff and 100 m altitude measuring (slant range, azimuth) at 2 Hz with
(20 m, 7°) noise, Singer model (α = 0.6 1/s, σa = 0.66 m/s²). Measurements are generated before timing. Each figure is
the median over repeats of the mean wall time per step over the run; ``ekf_road_ref_step_us`` times the unconstrained
EKF on the same measurements in the same run, as a yardstick on a noisy machine.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from autonomy.estimation.ekf import EKF
from autonomy.estimation.measurements import Measurement
from autonomy.estimation.models import Singer
from autonomy.estimation.road.constraint import RoadConstraintParams, SegmentCursor
from autonomy.estimation.road.filters import make_road_filter
from autonomy.estimation.road.roadmap import RoadMap
from simulator.bench.registry import BenchRecord, benchmark, median_of
from worlds.roads.network import RoadNetwork

N_STEPS = 400
REPEATS = 5
DT = 0.5
SPEED = 12.0  # m/s
SIGMA = np.array([20.0, np.deg2rad(7.0)])


def _scenario(seed: int = 0) -> tuple[RoadMap, list[Measurement], np.ndarray]:
    x = np.arange(0.0, 3000.0 + 1e-9, 20.0)
    y = 150.0 * np.sin(2 * np.pi * x / 700.0)
    net = RoadNetwork.from_spec({"nodes": {"a": [0.0, 0.0], "b": [x[-1], y[-1]]},
                                 "streets": [{"id": "s", "nodes": ["a", "b"], "via": np.c_[x, y][1:-1].tolist()}]})
    road = net.roads["s.f"]
    rng = np.random.default_rng(seed)
    meas = []
    for k in range(1, N_STEPS + 1):
        t = k * DT
        p = road.point(SPEED * t, road.lane_offset(0))
        p_s = np.array([p[0] + 500.0 * np.cos(0.08 * t), p[1] + 500.0 * np.sin(0.08 * t), 100.0])
        d = np.array([p[0], p[1], 0.0]) - p_s
        z = np.array([np.linalg.norm(d), np.arctan2(d[1], d[0])]) + SIGMA * rng.normal(size=2)
        meas.append(Measurement(z=z, R=np.diag(SIGMA**2), t_meas=t, p_sensor_W=p_s))
    t0 = road.tangent(0.0)
    x0 = np.array([0.0, SPEED * t0[0], 0.0, 0.0, SPEED * t0[1], 0.0])
    return RoadMap(net, RoadConstraintParams()), meas, x0


def _time_steps(make: Callable[[], object], meas: list[Measurement]) -> float:
    """Median over repeats of the mean wall time (µs) of one ``update`` (predict to the measurement + correct)."""

    def once() -> float:
        f = make()
        t0 = time.perf_counter()
        for m in meas:
            f.update(m)
        return (time.perf_counter() - t0) / len(meas) * 1e6

    return median_of(once, REPEATS)


@benchmark("road_filter_step", produces=("road_filter_step_us_maekf", "road_filter_step_us_ecukf",
                                         "ekf_road_ref_step_us"))
def bench_road_filter_step() -> list[BenchRecord]:
    roadmap, meas, x0 = _scenario()
    model = Singer(alpha=0.6, sigma_a=0.66, dim=2)
    P0 = np.diag([100.0, 4.0, 1.0, 100.0, 4.0, 1.0])
    approx = roadmap.approximation("s.f")

    def make(variant: str) -> object:
        return make_road_filter(variant, model, x0, P0, 0.0, cursor=SegmentCursor(approx.segments),
                                lanes=roadmap.lanes, params=roadmap.params)

    records = [BenchRecord(name="ekf_road_ref_step_us", value=_time_steps(lambda: EKF(model, x0, P0), meas),
                           unit="us", better="lower")]
    for variant in ("maekf", "ecukf"):
        records.append(BenchRecord(name=f"road_filter_step_us_{variant}",
                                   value=_time_steps(lambda v=variant: make(v), meas), unit="us", better="lower"))
    return records
