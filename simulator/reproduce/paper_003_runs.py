"""Paper 003's kinematic experiments: which variants run, with which seeds, and the numbers kept of each run.

Every variant of every case runs on the same run seeds (:meth:`ReproContext.run_seeds`): run ``r`` draws its bearing
noise from the first child of ``SeedSequence(seed_r)`` and its random geometry from the second, whatever the case or
variant, so differences between variants and between cases are paired (common random numbers).

Variants (the same IMM and PD law in all):

- ``alg1``: the paper's configuration, Algorithm 1 around the estimate with each agent's current range as its input
  (the paper's claims are judged on it);

and, for the comparison the paper omits, formations that all fly the desired range :data:`RANGE_M` for every agent
(so they differ only in bearings, not in ranges):

- ``optimal``: Algorithm 1 around the estimate at those ranges;
- ``fixed``: the start bearings held (translated with the estimate);
- ``trail``: a ±15° fan behind the target;
- ``random``: bearings drawn uniformly on [0, 2π) once per run (from the run seed), held like ``fixed``;
- ``alg1@ω``: the paper's configuration with the IMM's CT models at ±ω rad/s instead of ±0.3
  (:data:`MISMATCHED_RATES`, away from the scripted 0.25 / 0.35 rad/s turns), in the turning cases and case 1
  (:data:`MISMATCH_CASES`).
"""

from __future__ import annotations

import numpy as np

from simulator.kinematic.formation import CASES, FormationLoopConfig, FormationLoopResult, run_formation_loop
from simulator.reproduce.report import ReproContext

__all__ = ["PAPER", "FORMATIONS", "MISMATCHED_RATES", "MISMATCH_CASES", "RANGE_M", "SETTLE_S", "Results", "variants",
           "run_kinematic", "summarize", "turn_windows", "random_bearings"]

PAPER = "alg1"
FORMATIONS = ("optimal", "fixed", "trail", "random")
MISMATCHED_RATES = (0.15, 0.5)
"""IMM CT rates (rad/s) of the sensitivity runs: well below and above the scripted 0.25 and 0.35 rad/s turns."""
MISMATCH_CASES = (1, 3, 4)
"""Case 1 is the turns' no-manoeuvre control (same windows, same seeds)."""
RANGE_M = 95.0
"""Desired range of every agent in every formation, m: the mean start range (75, 105 and 106 m, mean 95.5 m)."""
SETTLE_S = 10.0
"""Steady window starts here, s: a random geometry can lie across the target from the start, ≈ 7 s away at 30 m/s."""
QUICK_DURATION_S = 6.0
QUICK_CASES = (1, 2)
TURN_WINDOW_S = 3.0

Results = dict[tuple[int, str], dict[str, np.ndarray]]
"""Per (case, variant): each kept number (:func:`summarize`) as an array over runs, in run-seed order."""


def variants(case: int) -> tuple[str, ...]:
    """The variants run for ``case``."""
    extra = tuple(f"{PAPER}@{w:g}" for w in MISMATCHED_RATES) if case in MISMATCH_CASES else ()
    return (PAPER, *FORMATIONS, *extra)


def _config(case: int, variant: str, quick: bool, bearings: tuple[float, ...]) -> FormationLoopConfig:
    form, _, rate = variant.partition("@")
    extra: dict = {"turn_rate": float(rate)} if rate else {}
    if form == "random":
        extra["fixed_bearings"] = bearings
    if form != PAPER:
        extra["ranges"] = (RANGE_M,) * 3
    formation = {"random": "fixed", PAPER: "optimal"}.get(form, form)
    return FormationLoopConfig(case=case, formation=formation, max_duration=QUICK_DURATION_S if quick else None,
                               **extra)


def _streams(seed: int) -> tuple[np.random.SeedSequence, np.random.SeedSequence]:
    """Run ``seed``'s bearing-noise and random-geometry streams (the same for every case and variant)."""
    noise, geometry = np.random.SeedSequence(seed).spawn(2)
    return noise, geometry


def random_bearings(seed: int) -> tuple[float, ...]:
    """The ``random`` formation's directions target → agent (rad) of run ``seed``: uniform on [0, 2π)."""
    return tuple(float(b) for b in np.random.default_rng(_streams(seed)[1]).uniform(0.0, 2.0 * np.pi, 3))


def _one(args: tuple[int, str, int, bool]) -> tuple[FormationLoopResult, dict[str, float]]:
    case, variant, seed, quick = args
    res = run_formation_loop(_config(case, variant, quick, random_bearings(seed)),
                             np.random.default_rng(_streams(seed)[0]))
    return res, summarize(res)


def run_kinematic(ctx: ReproContext) -> tuple[Results, dict[tuple[int, str], FormationLoopResult],
                                               dict[tuple[int, str], np.ndarray]]:
    """Every case and variant on ``ctx.run_seeds()``: the kept numbers, the first run of each and the (runs, K)
    error series of each (for the figures)."""
    cases = QUICK_CASES if ctx.quick else tuple(CASES)
    jobs = [(case, var, seed, ctx.quick) for case in cases for var in variants(case) for seed in ctx.run_seeds()]
    out: dict[tuple[int, str], list[dict[str, float]]] = {}
    first: dict[tuple[int, str], FormationLoopResult] = {}
    series: dict[tuple[int, str], list[np.ndarray]] = {}
    done = ctx.map(_one, jobs, chunksize=4, store="loops", types=(FormationLoopResult,))
    for (case, var, _, _), (res, row) in zip(jobs, done, strict=True):
        out.setdefault((case, var), []).append(row)
        first.setdefault((case, var), res)
        series.setdefault((case, var), []).append(res.error)
    results = {k: {name: np.array([r[name] for r in rows]) for name in rows[0]} for k, rows in out.items()}
    return results, first, {k: np.array(v) for k, v in series.items()}


def turn_windows() -> list[tuple[float, float, int]]:
    """Case 4's turns: (start s, end s, index of the IMM's CT mode turning that way)."""
    out, t0 = [], 0.0
    for seg in CASES[4]:
        if seg.omega != 0.0:
            out.append((t0, t0 + seg.duration, 1 if seg.omega > 0 else 2))
        t0 += seg.duration
    return out


def summarize(res: FormationLoopResult) -> dict[str, float]:
    """One run's numbers over the steady window (t ≥ :data:`SETTLE_S`, or the second half of a shorter run): mean
    error (m), ln-det gap to the bound, ln det F (F in m⁻²), mean agent–target range (m); and for each of case 4's
    turn windows j (whatever the case: in case 1 they are the no-manoeuvre control): the mean error over the
    :data:`TURN_WINDOW_S` before the turn, its first and last :data:`TURN_WINDOW_S` (m), the largest error of its
    first window (m), whether the IMM's CT mode of that sense passed 0.5 within the turn (1/0) and when (s after
    the onset, nan if never)."""
    t = res.t
    steady = t >= min(SETTLE_S, t[-1] / 2)
    ranges = np.linalg.norm(res.agents - res.truth[:, None, [0, 2]], axis=2)
    row = {"error": float(res.error[steady].mean()),
           "gap": float(np.mean((res.max_log_det_fim - res.log_det_fim)[steady])),
           "logdet": float(res.log_det_fim[steady].mean()), "range": float(ranges[steady].mean())}
    for j, (t0, t1, mode) in enumerate(turn_windows(), start=1):
        if t1 > t[-1] + 1e-9:
            continue
        before = (t > t0 - TURN_WINDOW_S) & (t <= t0)
        early = (t > t0) & (t <= t0 + TURN_WINDOW_S)
        late = (t > t1 - TURN_WINDOW_S) & (t <= t1)
        inside = (t > t0) & (t <= t1)
        switched = np.flatnonzero(res.mode_probability[inside, mode] > 0.5)
        row |= {f"turn{j}_before": float(res.error[before].mean()), f"turn{j}_early": float(res.error[early].mean()),
                f"turn{j}_late": float(res.error[late].mean()), f"turn{j}_peak": float(res.error[early].max()),
                f"turn{j}_switched": float(switched.size > 0),
                f"turn{j}_delay": float(t[inside][switched[0]] - t0) if switched.size else float("nan")}
    return row
