"""Guidance benchmarks: NMPC standoff solve time (2 UAVs, N = 20, closed loop around a moving target) and fast-MPC
solve time (3 UAVs, paper-000-like scenario), both on the kinematic unicycle harness.

Solve times are wall times of the optimiser call only; the first ``_WARMUP`` steps of each run (the cold-start
transient while the UAVs converge onto the orbit) are excluded. Each figure is the median over repeats.
"""

from __future__ import annotations

import numpy as np

from autonomy.guidance.fast_mpc import FastMpcConfig, FastMpcGuidance
from autonomy.guidance.nmpc import NmpcStandoffGuidance
from autonomy.guidance.nmpc_config import NmpcConfig
from autonomy.guidance.unicycle import UnicycleParams
from simulator.bench.registry import BenchRecord, benchmark
from simulator.kinematic.unicycle_loop import LoopConfig, run_kinematic_loop

_WARMUP = 10
_REPEATS = 3


def _nmpc_times(solver: str, steps: int = 240, **overrides: object) -> tuple[float, float, float, float]:
    """(wall p50, wall p95, CPU p95, CPU p50) solve time (ms) of one closed-loop run with ``solver``; ``overrides``
    are further :class:`NmpcConfig` fields (to compare solver options on the same problem)."""
    cfg = NmpcConfig(solver=solver, horizon=20, **overrides)
    laws = [NmpcStandoffGuidance(cfg, 0), NmpcStandoffGuidance(cfg, 1)]
    x0 = np.array([[150.0, 20.0, 1.5, 12.0, 0.0], [-100.0, -90.0, 0.0, 12.0, 0.0]])
    run_kinematic_loop(laws, x0, LoopConfig(dt=0.5, steps=steps, target_v=(4.0, 1.0)))
    t = np.concatenate([np.asarray(law.stats.solve_times_s[_WARMUP:]) for law in laws]) * 1e3
    c = np.concatenate([np.asarray(law.stats.solve_cpu_times_s[_WARMUP:]) for law in laws]) * 1e3
    return (float(np.percentile(t, 50)), float(np.percentile(t, 95)), float(np.percentile(c, 95)),
            float(np.percentile(c, 50)))


@benchmark("guidance_nmpc", produces=("nmpc_solve_ms_p50", "nmpc_solve_ms_p95", "nmpc_solve_cpu_ms_p95",
                                      "nmpc_uncompiled_solve_ms_p95", "nmpc_fatrop_solve_ms_p50",
                                      "nmpc_fatrop_solve_ms_p95", "nmpc_ipopt_solve_ms_p50", "nmpc_rti_solve_ms_p50"))
def bench_nmpc() -> list[BenchRecord]:
    """NMPC standoff tracking, default solver (tiered SQP + qrqp, compiled functions), plus the same solver
    uncompiled, Fatrop (``road_standoff``'s solver), IPOPT and RTI for comparison (the uncompiled and Fatrop runs
    alternate with the default ones, so their ratios are measured under the same load).

    ``nmpc_solve_cpu_ms_p95`` is the thread CPU time of the same calls: on a shared machine the wall-time tail
    mostly measures preemption by other processes. The first run on a machine compiles the solver (cached).
    """
    runs, vm, fat = [], [], []
    for _ in range(_REPEATS):
        runs.append(_nmpc_times("sqp"))
        vm.append(_nmpc_times("sqp", compiled=False)[1])
        fat.append(_nmpc_times("fatrop"))
    p50 = float(np.median([r[0] for r in runs]))
    p95 = float(np.median([r[1] for r in runs]))
    cpu95 = float(np.median([r[2] for r in runs]))
    ipopt = float(np.median([_nmpc_times("ipopt", steps=120)[0] for _ in range(_REPEATS)]))
    rti = float(np.median([_nmpc_times("rti", steps=120)[0] for _ in range(_REPEATS)]))
    return [
        BenchRecord(name="nmpc_solve_ms_p50", value=p50, unit="ms", better="lower"),
        BenchRecord(name="nmpc_solve_ms_p95", value=p95, unit="ms", target=2.0, better="lower"),
        BenchRecord(name="nmpc_solve_cpu_ms_p95", value=cpu95, unit="ms", target=2.0, better="lower"),
        BenchRecord(name="nmpc_uncompiled_solve_ms_p95", value=float(np.median(vm)), unit="ms", better="lower"),
        BenchRecord(name="nmpc_fatrop_solve_ms_p50", value=float(np.median([r[0] for r in fat])), unit="ms",
                    better="lower"),
        BenchRecord(name="nmpc_fatrop_solve_ms_p95", value=float(np.median([r[1] for r in fat])), unit="ms",
                    better="lower"),
        BenchRecord(name="nmpc_ipopt_solve_ms_p50", value=ipopt, unit="ms", better="lower"),
        BenchRecord(name="nmpc_rti_solve_ms_p50", value=rti, unit="ms", better="lower"),
    ]


@benchmark("guidance_fast_mpc", produces=("fast_mpc_solve_ms_p50",))
def bench_fast_mpc() -> list[BenchRecord]:
    """Fast MPC (M = 10, 3 same-altitude UAVs with separation), interior point capped at 30 iterations."""
    meds = []
    for _ in range(_REPEATS):
        cfg = FastMpcConfig(v_max=18.0, omega_max=2.0)
        laws = [FastMpcGuidance(cfg) for _ in range(3)]
        x0 = np.array([[4510, -8, 2, 0, 0], [4490, -8, 2, 0, 0], [4500, 5, 2, 0, 0]], dtype=float)
        loop = LoopConfig(dt=0.5, steps=100, target_p0=(4500.0, -8.0), target_v=(3.0, 1.0),
                          plant=UnicycleParams(tau_v=0.0, tau_omega=0.0))
        run_kinematic_loop(laws, x0, loop, altitude=100.0)
        t = np.concatenate([np.asarray(law.stats.solve_times_s[_WARMUP:]) for law in laws]) * 1e3
        meds.append(float(np.median(t)))
    # the paper reports ≈ 39 ms per UAV per step (whole-mission time / steps / UAVs) on a 2.7 GHz Pentium
    return [BenchRecord(name="fast_mpc_solve_ms_p50", value=float(np.median(meds)), unit="ms", target=39.0,
                        better="lower")]


@benchmark("paper000_loop", produces=("fast_mpc_scif_hcmci_step_ms_p50",))
def bench_paper000_loop() -> list[BenchRecord]:
    """Paper 000's whole per-UAV step in its closed loop (:mod:`simulator.kinematic.consensus`, case 1, 4 UAVs):
    one fast MPC solve, one SCIF information step and a quarter of the 4-node HCMCI (L = 3); median over 100 steps
    after a 10-step warm-up, median of 3 runs. Target 2 ms (the paper's MATLAB: ≈ 39 ms)."""
    from simulator.kinematic.consensus import ConsensusLoopConfig, run_consensus_loop

    meds = []
    for seed in range(_REPEATS):
        res = run_consensus_loop(ConsensusLoopConfig(case=1, steps=110), np.random.default_rng(seed))
        meds.append(1e3 * float(np.median(res.step_time_s[10:])))
    return [BenchRecord(name="fast_mpc_scif_hcmci_step_ms_p50", value=float(np.median(meds)), unit="ms", target=2.0,
                        better="lower")]
