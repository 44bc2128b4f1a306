"""Estimation benchmarks: one filter step (predict + update) for one target with a radar measurement.

The scenario: a Singer target (6 states, α = 0.6 1/s, σa = 0.66 m/s²) on the ground, a radar at 100 m altitude
measuring (slant range, azimuth, elevation) at 2 Hz; measurements are generated before timing. Each figure is the median
over repeats of the mean CPU time per step over a batch of steps. ``ekf_ref_step_us`` times a textbook covariance-form
EKF step written inline (the operations FilterPy's ExtendedKalmanFilter performs, Joseph form included) in the same
run, so the ratio ``ekf_step_us / ekf_ref_step_us`` is meaningful on a noisy machine. ``imm3_step_ratio`` is an IMM
step with three EKF modes (CV, CT ±0.2 rad/s) divided by one EKF step on the CV mode; ``imm3_batched_step_ratio`` the
same for :class:`~autonomy.estimation.imm_batched.BatchedEKFIMM`, which stacks the modes into batched arrays.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from autonomy.estimation.factory import make_filter
from autonomy.estimation.imm import IMM
from autonomy.estimation.imm_batched import BatchedEKFIMM
from autonomy.estimation.measurements import Measurement, RadarModel
from autonomy.estimation.models import ConstantVelocity, CoordinatedTurn, Singer
from simulator.bench.registry import BenchRecord, benchmark, median_of

N_STEPS = 2000
REPEATS = 5
DT = 0.5
P_SENSOR = np.array([0.0, 0.0, 100.0])
SIGMA = np.array([2.0, 0.01, 0.01])


def _scenario(model, seed: int = 0) -> tuple[np.ndarray, np.ndarray, list[Measurement]]:
    rng = np.random.default_rng(seed)
    n = len(model.layout)
    x = np.zeros(n)
    x[model.layout.index("x")], x[model.layout.index("y")] = 400.0, 300.0
    x[model.layout.index("vx")], x[model.layout.index("vy")] = 8.0, -3.0
    F, Q = model.matrices(DT)
    w, V = np.linalg.eigh(Q)
    S_Q = V * np.sqrt(np.clip(w, 0, None))
    radar = RadarModel(model.layout, P_SENSOR, 3)
    R = np.diag(SIGMA**2)
    meas = []
    x0 = x.copy()
    for k in range(N_STEPS):
        x = F @ x + S_Q @ rng.normal(size=n)
        z = radar.h(x) + SIGMA * rng.normal(size=3)
        meas.append(Measurement(z=z, R=R, t_meas=(k + 1) * DT, p_sensor_W=P_SENSOR))
    P0 = np.diag([25.0, 4.0, 1.0, 25.0, 4.0, 1.0][:n] if n == 6 else [25.0, 4.0] * (n // 2))
    return x0, P0, meas


def _time_steps(make: Callable[[], object], meas: list[Measurement]) -> float:
    """Median over repeats of the mean time (µs) of ``update`` over the measurements.

    CPU time of this process (``time.process_time``), not wall time: the step is single-threaded and CPU-bound, and on
    a shared machine wall time mostly measures how long the process waited for a core.
    """

    def once() -> float:
        f = make()
        t0 = time.process_time()
        for m in meas:
            f.update(m)
        return (time.process_time() - t0) / len(meas) * 1e6

    return median_of(once, REPEATS)


class _ReferenceEKF:
    """Textbook EKF step with inline numpy (the FilterPy operation count), used as an in-run yardstick."""

    def __init__(self, model, x0, P0) -> None:
        self.F, self.Q = (np.array(a) for a in model.matrices(DT))
        self.x, self.P = x0.copy(), P0.copy()
        self.I = np.eye(len(x0))

    def update(self, m: Measurement) -> None:
        x = self.F @ self.x
        P = self.F @ self.P @ self.F.T + self.Q
        dx, dy, dz = x[0] - m.p_sensor_W[0], x[3] - m.p_sensor_W[1], -m.p_sensor_W[2]
        rho2 = dx * dx + dy * dy
        rho, r2 = math.sqrt(rho2), rho2 + dz * dz
        r = math.sqrt(r2)
        H = np.zeros((3, 6))
        H[0, 0], H[0, 3] = dx / r, dy / r
        H[1, 0], H[1, 3] = -dy / rho2, dx / rho2
        H[2, 0], H[2, 3] = -dz * dx / (rho * r2), -dz * dy / (rho * r2)
        hx = np.array([r, math.atan2(dy, dx), math.atan2(dz, rho)])
        y = m.z - hx
        y[1] = (y[1] + math.pi) % (2 * math.pi) - math.pi
        PHT = P @ H.T
        S = H @ PHT + m.R
        K = PHT @ np.linalg.inv(S)
        self.x = x + K @ y
        IKH = self.I - K @ H
        self.P = IKH @ P @ IKH.T + K @ m.R @ K.T


@benchmark("estimation_filter_step", produces=("ekf_step_us", "ukf_step_us", "ckf_step_us", "scif_step_us",
                                               "ekf_ref_step_us"))
def bench_filter_steps() -> list[BenchRecord]:
    model = Singer(alpha=0.6, sigma_a=0.66)
    x0, P0, meas = _scenario(model)
    targets = {"ekf": 30.0, "ukf": 150.0, "ckf": 150.0, "scif": 200.0}
    records = [BenchRecord(name="ekf_ref_step_us", value=_time_steps(lambda: _ReferenceEKF(model, x0, P0), meas),
                           unit="us", target=None, better="lower")]
    for kind, target in targets.items():
        us = _time_steps(lambda k=kind: make_filter(k, model, x0, P0), meas)
        records.append(BenchRecord(name=f"{kind}_step_us", value=us, unit="us", target=target, better="lower"))
    return records


@benchmark("estimation_imm", produces=("imm3_step_ratio", "imm3_batched_step_ratio"))
def bench_imm() -> list[BenchRecord]:
    cv = ConstantVelocity(q=0.5)
    modes = [cv, CoordinatedTurn(omega=0.2, q=0.5), CoordinatedTurn(omega=-0.2, q=0.5)]
    x0, P0, meas = _scenario(cv)
    meas = meas[: N_STEPS // 2]
    Pi = np.full((3, 3), 0.025) + 0.925 * np.eye(3)

    ratios: dict[str, list[float]] = {"generic": [], "batched": []}
    for _ in range(3):  # interleaved, so load changes hit numerator and denominator alike
        single = _time_steps(lambda: make_filter("ekf", cv, x0, P0), meas)
        generic = _time_steps(lambda: IMM([make_filter("ekf", m, x0, P0) for m in modes], Pi), meas)
        batched = _time_steps(lambda: BatchedEKFIMM(modes, x0, P0, Pi), meas)
        ratios["generic"].append(generic / single)
        ratios["batched"].append(batched / single)
    return [
        BenchRecord(name="imm3_step_ratio", value=float(np.median(ratios["generic"])), unit="x", target=3.0,
                    better="lower"),
        BenchRecord(name="imm3_batched_step_ratio", value=float(np.median(ratios["batched"])), unit="x", target=3.0,
                    better="lower"),
    ]
