"""Paper 000's kinematic experiments: the configurations run on common seeds, and each run reduced to the numbers
the verdicts need (a :class:`RunSummary`), so that only scalars travel back from the worker processes.

Configurations (every one on the same evaluation seeds, ``ctx.run_seeds()``; the run's noise generator is seeded by
the run seed alone, never by the configuration, so differences between configurations are paired):

- ``paper``: cases 1 and 2 with separation margin 0 (D' = D = 10 m), the paper-faithful column;
- ``control``: case 2's weights with its outages off, the paired control of the outage effect;
- ``L=…``: case 1 with other consensus iteration counts (the paper does not print its L);
- ``half-plane``: cases 1 and 2 with the paper's own separation linearisation (eq. 29), margin 0;
- ``margin 4 m``: cases 1 and 2 with our planner margin D' = D + 4 m (the ``FastMpcConfig`` default).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from simulator.kinematic.consensus import ConsensusLoopConfig, ConsensusLoopResult, run_consensus_loop, target_drive

__all__ = ["CONSENSUS_LIMIT_M", "L_SWEEP", "OURS_MARGIN_M", "PRIMARY_L", "Job", "RunSummary", "jobs_for",
           "outage_windows", "run_job", "summarise"]

CONSENSUS_LIMIT_M = 0.05
"""The paper's consensus-error bound (m)."""
PRIMARY_L = 3
"""Our consensus iteration count L (the paper does not print its own; its notes suggest 2–5)."""
L_SWEEP = (1, 2, 3, 5, 8)
OURS_MARGIN_M = 4.0
"""Planner margin added to D in our configuration (``FastMpcConfig.separation_margin``'s default), m."""
NEAR_NADIR_M = 5.0
"""Horizontal UAV–target distance under which a UAV counts as "over" the target in the spike table, m (about half
the radar's nadir-angle noise footprint σ_ϕ·h ≈ 9 m at 100 m)."""


@dataclass(frozen=True, kw_only=True)
class Job:
    """One closed-loop run: configuration ``variant`` of ``case`` on run seed ``seed``."""

    variant: str
    case: int
    seed: int
    steps: int
    settle: int
    iterations: int = PRIMARY_L
    margin_m: float = 0.0
    mode: str = "buffered"
    outages: bool = True
    keep: bool = False  # return the full time series (for the figures)

    def config(self) -> ConsensusLoopConfig:
        base = ConsensusLoopConfig()
        mpc = replace(base.mpc, separation_margin=self.margin_m, separation_mode=self.mode)
        return ConsensusLoopConfig(case=self.case, steps=self.steps, consensus_iterations=self.iterations,
                                   outages=self.outages, mpc=mpc)


@dataclass(frozen=True, kw_only=True)
class RunSummary:
    """One run reduced to the verdicts' numbers (after the first ``settle`` steps unless said otherwise)."""

    variant: str
    case: int
    seed: int
    err_max: float  # largest e_p over UAVs and steps, m
    err_mean: float
    cons_max: float  # largest consensus error, m
    cons_max_transient: float  # largest consensus error in the settling steps, m
    cons_share: float  # share of UAV-steps with consensus error > CONSENSUS_LIMIT_M
    cons_mean: float
    sep_min: float  # smallest same-altitude horizontal distance, whole run, m
    input_violation: float  # largest excess of an input over its bound, m/s or rad/s
    compute_s: float  # total computation of the four UAVs over the run, s
    step_ms: float  # median over steps of the per-UAV computation, ms
    win_cons: float = float("nan")  # means over case 2's outage windows (steps 150–200, 300–350)
    win_err: float = float("nan")
    win_dist: float = float("nan")  # UAV-to-target horizontal distance, mean over UAVs, m
    peak_err: float = float("nan")  # case 2's window-1 error peak (mean over UAVs), m
    peak_step: int = -1
    peak_speed: float = float("nan")  # the target's speed at the peak, m/s
    peak_near: int = -1  # UAVs within NEAR_NADIR_M of the target at the peak


def jobs_for(seeds: list[int], steps: int, settle: int) -> list[Job]:
    """Every configuration's run on every seed (module docstring)."""
    jobs = []
    for n, s in enumerate(seeds):
        kw = dict(seed=s, steps=steps, settle=settle)
        jobs += [Job(variant="paper", case=c, keep=n == 0, **kw) for c in (1, 2)]
        jobs.append(Job(variant="control", case=2, outages=False, **kw))
        jobs += [Job(variant=f"L={n}", case=1, iterations=n, **kw) for n in L_SWEEP if n != PRIMARY_L]
        jobs += [Job(variant="half-plane", case=c, mode="paper", **kw) for c in (1, 2)]
        jobs += [Job(variant="margin 4 m", case=c, margin_m=OURS_MARGIN_M, **kw) for c in (1, 2)]
    return jobs


def outage_windows(steps: int) -> np.ndarray:
    """(steps,) bool: case 2's outage steps (1-based steps 150–200 and 300–350), whether or not the links are cut."""
    cfg = ConsensusLoopConfig(case=2, steps=steps)
    return np.array([bool(cfg.outage_links(k)) for k in range(1, steps + 1)])


def summarise(job: Job, r: ConsensusLoopResult) -> RunSummary:
    """The numbers of :class:`RunSummary` from run ``r`` of ``job``."""
    cfg, s = job.config(), job.settle
    u = r.inputs
    viol = max(float(np.max(u[..., 0] - cfg.mpc.v_max)), float(np.max(cfg.mpc.v_min - u[..., 0])),
               float(np.max(np.abs(u[..., 1]) - cfg.mpc.omega_max)))
    win = outage_windows(len(r.t))
    dist = np.linalg.norm(r.uav[1:, :, :2] - r.target[:, None, :], axis=-1)  # row k: UAVs at t_k
    extra = {}
    if win.any():
        extra = dict(win_cons=float(r.consensus_error[win].mean()), win_err=float(r.error[win].mean()),
                     win_dist=float(dist[win].mean()))
        first = np.flatnonzero(win & (np.arange(len(win)) < 250))
        if job.case == 2 and first.size:
            em = r.error.mean(axis=1)
            i = int(first[np.argmax(em[first])])
            truth = target_drive(len(r.t), cfg.dt)[i + 1]  # row i of the result is step i + 1
            speed = np.hypot(truth[1], truth[4])
            extra |= dict(peak_err=float(em[i]), peak_step=i + 1, peak_speed=float(speed),
                          peak_near=int(np.sum(dist[i] < NEAR_NADIR_M)))
    return RunSummary(
        variant=job.variant, case=job.case, seed=job.seed,
        err_max=float(r.error[s:].max()), err_mean=float(r.error[s:].mean()),
        cons_max=float(r.consensus_error[s:].max()), cons_max_transient=float(r.consensus_error[:s].max()),
        cons_share=float(np.mean(r.consensus_error[s:] > CONSENSUS_LIMIT_M)),
        cons_mean=float(r.consensus_error[s:].mean()), sep_min=float(r.separation.min()), input_violation=viol,
        compute_s=float(r.step_time_s.sum()), step_ms=float(1e3 * np.median(r.step_time_s[1:])), **extra)


def run_job(job: Job) -> tuple[RunSummary, ConsensusLoopResult | None]:
    """Run ``job`` (its noise from the run seed alone); the full result comes back only where ``job.keep``."""
    r = run_consensus_loop(job.config(), np.random.default_rng(job.seed))
    return summarise(job, r), r if job.keep else None
