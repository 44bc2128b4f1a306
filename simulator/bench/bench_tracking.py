"""Multi-target association benchmarks: gating and assigning one radar scan against many car tracks.

The scenario: ``n`` cars spread uniformly over a 2 km × 2 km town (speeds up to 15 m/s), each held by a CV EKF track
(q = 0.5 m²/s³) whose estimate at t = 0 is the truth plus an error drawn from its covariance (σ = 8 m in position,
2 m/s in velocity); a 2-D radar ``z = [r, az]`` (σr = 20 m, σaz = 2°) 120 m above the town centre scans at t = 0.5 s,
detects each car with probability 0.9 and fills the scan up to ``n`` detections with clutter spread over the town.
Each figure is the median over repeats of the CPU time (``time.process_time``) of one call, gating included (every
track is predicted to the scan time, :class:`~autonomy.estimation.tracking.scan_gate.ScanGating`): the association
part of one multi-target tracker step.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from autonomy.estimation.factory import make_filter
from autonomy.estimation.measurements import Measurement, RadarDetectionModel, RadarModel
from autonomy.estimation.models import ConstantVelocity
from autonomy.estimation.tracking.assignment import GlobalNearestNeighbourAssociator
from autonomy.estimation.tracking.gate import ChiSquareGate, PredictedNis
from autonomy.estimation.tracking.jpda import JointProbabilisticAssociator
from autonomy.estimation.tracking.track import Track
from simulator.bench.registry import BenchRecord, benchmark, median_of

TOWN_M = 2000.0
P_SENSOR = np.array([1000.0, 1000.0, 120.0])
SIGMA = np.array([20.0, math.radians(2.0)])
P_DETECT = 0.9
GATE_P = 0.99
SCAN_T = 0.5
REPEATS = 31
MODEL = ConstantVelocity(q=0.5)
P0 = np.diag([8.0**2, 2.0**2, 8.0**2, 2.0**2])


def scenario(n: int, seed: int = 0) -> tuple[list[Track], list[Measurement]]:
    """``n`` car tracks at t = 0 and a radar scan of ``n`` detections at ``SCAN_T`` (module docstring)."""
    rng = np.random.default_rng(seed)
    truth = np.zeros((n, 4))
    truth[:, 0], truth[:, 2] = rng.uniform(0.0, TOWN_M, n), rng.uniform(0.0, TOWN_M, n)
    heading, speed = rng.uniform(-math.pi, math.pi, n), rng.uniform(0.0, 15.0, n)
    truth[:, 1], truth[:, 3] = speed * np.cos(heading), speed * np.sin(heading)
    L = np.linalg.cholesky(P0)
    tracks = [Track(make_filter("ekf", MODEL, x + L @ rng.standard_normal(4), P0, 0.0), 0.0) for x in truth]
    F, _ = MODEL.matrices(SCAN_T)
    radar = RadarModel(MODEL.layout, P_SENSOR, 2)
    seen = (F @ truth.T).T[rng.uniform(size=n) < P_DETECT]
    clutter = np.zeros((n - len(seen), 4))
    clutter[:, 0], clutter[:, 2] = rng.uniform(0.0, TOWN_M, (2, len(clutter)))
    z = radar.h(np.vstack([seen, clutter]).T).T + SIGMA * rng.standard_normal((n, 2))
    R = np.diag(SIGMA**2)
    model = RadarDetectionModel(dim=2)
    dets = [Measurement(z=zi, R=R, t_meas=SCAN_T, p_sensor_W=P_SENSOR, model=model) for zi in rng.permutation(z)]
    return tracks, dets


def clutter_density(n: int) -> float:
    """False detections per m·rad of the scan of ``n`` detections (the clutter spread over the radar's view)."""
    n_fa = n * (1.0 - P_DETECT)
    return n_fa / (TOWN_M / math.sqrt(2.0) * 2.0 * math.pi)


def _median_ms(call: Callable[[], object]) -> float:
    def once() -> float:
        t0 = time.process_time()
        call()
        return (time.process_time() - t0) * 1e3

    call()  # warm caches (F, Q per dt; χ² thresholds)
    return median_of(once, REPEATS)


@benchmark("mtt_assignment", produces=("mtt_assign_ms_50x50", "mtt_assign_ms_200x200", "mtt_jpda_ms_50x50"))
def bench_assignment() -> list[BenchRecord]:
    gate = ChiSquareGate(GATE_P)
    distance = PredictedNis(MODEL, 0.0)
    out = []
    for n, target in ((50, 1.0), (200, 5.0)):
        tracks, dets = scenario(n)
        gnn = GlobalNearestNeighbourAssociator(gate, distance)
        out.append(BenchRecord(name=f"mtt_assign_ms_{n}x{n}", value=_median_ms(lambda: gnn.assign(tracks, dets)),
                               unit="ms", target=target, better="lower"))
    tracks, dets = scenario(50)
    jpda = JointProbabilisticAssociator(gate, distance, P_DETECT, clutter_density(50))
    out.append(BenchRecord(name="mtt_jpda_ms_50x50", value=_median_ms(lambda: jpda.assign(tracks, dets)),
                           unit="ms", target=1.0, better="lower"))
    return out


def _tracker_with_tracks(n: int):
    """A multi-target tracker holding the ``n`` confirmed car tracks of :func:`scenario`, one of them believed to be
    the target, and the scan of ``n`` detections."""
    from autonomy.estimation.tracker import TrackerConfig
    from autonomy.estimation.tracking.identity import IdentityConfig
    from autonomy.estimation.tracking.multi import MultiTargetTracker, MultiTrackerConfig

    tracks, dets = scenario(n)
    tracker = MultiTargetTracker(TrackerConfig(filter="ekf", model="cv", q=0.5, gate_probability=GATE_P),
                                 MultiTrackerConfig(), IdentityConfig(target_classes={}, background={}), model=MODEL)
    for k, tr in enumerate(tracks, start=1):
        tr.track_id, tr.hits, tr.scans, tr.confirmed = k, 3, 3, True
        tracker.tracks.append(tr)
        est = tracker._estimate(tr)
        tracker.identity.confirmed(k, 0.0, est.p_W, est.P[:2, :2], 0.0)
    tracker._next_id = n + 1
    return tracker, dets


@benchmark("mtt_step", produces=("mtt_step_ms_50x50", "mtt_step_ms_200x200"))
def bench_mtt_step() -> list[BenchRecord]:
    """One whole step of the multi-target tracker (:class:`~autonomy.estimation.tracking.multi.MultiTargetTracker`,
    GNN, CV EKF tracks) on the scan of :func:`scenario`: gating, assignment, the filter updates, M-of-N bookkeeping,
    initiation from the unused detections (clutter), merging, the identity belief and the target's estimate; median
    CPU time over fresh copies of the same tracker (targets: 2 ms with 50 tracks and 50 detections, 10 ms with 200)."""
    import copy

    out = []
    for n, target in ((50, 2.0), (200, 10.0)):
        tracker, dets = _tracker_with_tracks(n)
        copies = [copy.deepcopy(tracker) for _ in range(REPEATS + 1)]

        def once(copies=copies, dets=dets) -> float:
            tr = copies.pop()
            t0 = time.process_time()
            tr.step(SCAN_T, dets)
            return (time.process_time() - t0) * 1e3

        once()  # warm caches
        out.append(BenchRecord(name=f"mtt_step_ms_{n}x{n}", value=median_of(once, REPEATS), unit="ms",
                               target=target, better="lower"))
    return out
