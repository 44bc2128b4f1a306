"""Reproduction of paper 003 (Yang & Wang 2019): FIM-optimal formation with IMM bearings-only tracking.

Runs the kinematic closed loop :mod:`simulator.kinematic.formation` for the paper's four cases
(:mod:`.paper_003_runs`): the paper's configuration (Algorithm 1 on the agents' current ranges + Jacobi PD control),
that configuration with IMM turn rates away from the truth's, and — the comparison the paper omits, which the notes
ask for — the optimal formation against the start bearings held, a trailing fan and a random geometry, all four at
the same desired range. ``ctx.runs`` runs each, on common seeds. As a cross-check on PyBullet quadrotors,
:mod:`.paper_003_physics` runs the physics world ``formation_imm`` per case with the optimal formation and the trailing
fan at equal ranges. The verdicts are pure functions of the numbers (:mod:`.paper_003_findings`).
"""

from __future__ import annotations

import numpy as np

from simulator.kinematic.formation import FormationLoopConfig
from simulator.reproduce.paper_003_figures import figures
from simulator.reproduce.paper_003_findings import kinematic_findings
from simulator.reproduce.paper_003_physics import (PHYSICS_RUNS, QUICK_DURATION_S, WORLD, physics_findings,
                                                   physics_table, run_physics)
from simulator.reproduce.paper_003_runs import (FORMATIONS, MISMATCHED_RATES, PAPER, RANGE_M, SETTLE_S, Results,
                                                run_kinematic, variants)
from simulator.reproduce.report import PaperReport, ReproContext, Table, mean_ci

__all__ = ["reproduce", "PHYSICS_RUNS"]

PAPER_LEVEL = {1: "≈ 5", 2: "≈ 10", 3: "≈ 10", 4: "grows at each manoeuvre"}
LABEL = {PAPER: "Algorithm 1, current ranges (paper)", "optimal": "optimal", "fixed": "fixed (start bearings)",
         "trail": "trail (±15° fan)", "random": "random bearings"}


def _cell(res: Results, case: int, variant: str, key: str, digits: int = 3) -> str:
    x = res.get((case, variant), {}).get(key)
    return "–" if x is None else mean_ci(x).text(digits)


def _tables(res: Results) -> tuple[Table, ...]:
    cases = sorted({c for c, _ in res})
    sens = tuple(f"{PAPER}@{w:g}" for w in MISMATCHED_RATES)
    t_err = Table(
        title=f"Steady-state position error (m), mean over t ≥ {SETTLE_S:g} s",
        columns=("case", "paper (m)", LABEL[PAPER], *(f"{LABEL[f]} at {RANGE_M:g} m" for f in FORMATIONS),
                 *(f"sensitivity: paper's, IMM CT ±{w:g} rad/s" for w in MISMATCHED_RATES)),
        rows=tuple((str(c), PAPER_LEVEL[c], *(_cell(res, c, v, "error") for v in (PAPER, *FORMATIONS, *sens)))
                   for c in cases),
        note="Mean ± 95 % CI over the runs (common run seeds in every cell). The paper's levels are read off its "
             "figures, with a bearing noise it does not define in radians: not comparable in absolute terms. The "
             "sensitivity columns are not the paper's configuration (it gives no CT rates; ours is ±0.3 rad/s).")
    geo_rows = []
    for c in cases:
        for v in (PAPER, *FORMATIONS):
            ld = res.get((c, v), {}).get("logdet")
            det = "–" if ld is None else mean_ci(np.exp(ld) * 1e4).text()
            geo_rows.append((str(c), LABEL[v], _cell(res, c, v, "range"), _cell(res, c, v, "logdet"), det,
                             _cell(res, c, v, "gap", 2)))
    t_geo = Table(title=f"Geometry over t ≥ {SETTLE_S:g} s: ranges flown and det F (absolute, and as a gap to the "
                        "bound for the ranges flown)",
                  columns=("case", "formation", "mean agent–target range (m)", "mean ln det F (F in m⁻²)",
                           "exp(mean ln det F) × 10⁴ (m⁻⁴)", "ln(bound) − ln det F (0 = optimal)"),
                  rows=tuple(geo_rows),
                  note="det F falls as the fourth power of range, so formations are compared at the same desired range "
                       f"({RANGE_M:g} m); the paper's Algorithm 1 keeps each agent's current range instead.")
    turn_rows = []
    for v in (PAPER, *sens):
        r4, r1 = res.get((4, v), {}), res.get((1, v), {})
        for j in (1, 2):
            if f"turn{j}_early" not in r4:
                continue
            sw = r4[f"turn{j}_switched"]
            turn_rows.append((v.replace(f"{PAPER}@", "paper's, CT ±").replace(PAPER, "paper's, CT ±0.3") + " rad/s",
                              f"turn {j}", mean_ci(r1[f"turn{j}_early"]).text(), mean_ci(r4[f"turn{j}_before"]).text(),
                              mean_ci(r4[f"turn{j}_early"]).text(), mean_ci(r4[f"turn{j}_peak"]).text(),
                              mean_ci(r4[f"turn{j}_late"]).text(), f"{int(sw.sum())}/{sw.size}",
                              mean_ci(r4[f"turn{j}_delay"]).text()))
    t_turn = Table(title="Case 4: error around the manoeuvres (m) and IMM switching",
                   columns=("IMM bank", "manoeuvre", "case 1, same window (control)", "before (3 s)",
                            "first 3 s of the turn", "peak in the first 3 s", "last 3 s of the turn",
                            "runs with μ_CT > 0.5 in the turn", "delay until μ_CT > 0.5 (s)"),
                   rows=tuple(turn_rows),
                   note="The turn's first 3 s are judged against the same window of case 1 (no manoeuvre, same run "
                        "seeds and bank); 'before' includes the exit of the previous turn or the filter's start.")
    return t_err, t_geo, t_turn


def reproduce(ctx: ReproContext) -> PaperReport:
    """Run paper 003's cases and compare; see the module docstring."""
    res, first, series = run_kinematic(ctx)
    phys, phys_runs, settle = run_physics(ctx)
    from worlds.loader import load_world

    phys_duration = QUICK_DURATION_S if ctx.quick else float(load_world(WORLD).world.sim.duration_s)
    base = FormationLoopConfig()
    findings = (*kinematic_findings(res), *physics_findings(phys))
    n_var = len(variants(4))
    return PaperReport(
        paper="003", title="FIM-optimal formation and IMM bearings-only tracking (Yang & Wang, IEEE Access 2019)",
        runs=ctx.runs,
        setup=f"""
Kinematic closed loop (`simulator/kinematic/formation.py`): three agents with bearing sensors
(σ = {base.sigma_bearing} rad) every {base.dt} s; an IMM of three EKFs (CV, CT ±{base.turn_rate} rad/s, q = {base.q_cv}
m²/s³, p_stay = {base.p_stay}) on the stacked bearings (the paper's centralised augmented-measurement EKF per mode); the
team flies Algorithm 1's geometry around the estimate with the Jacobi PD law (velocity-tracking agents, ≤
{base.guidance.max_speed} m/s). Target: 12 m/s from {base.target_p0} heading 45°; agents start at {base.agents_p0}
with the target's velocity. Cases: 1 CV; 2 constant acceleration (0.25, 0.2) m/s²; 3 CT 0.25 rad/s; 4 CV 3 s,
CT +0.35 rad/s 10.5 s, CV 3 s, CT −0.35 rad/s 10.5 s, CV 3 s. Up to {n_var} variants per case on the same run seeds:

- **{LABEL[PAPER]}**: the paper's configuration (Algorithm 1's input is each agent's current range); the paper's
  claims are judged on it;
- **sensitivity**: the same with the IMM's CT models at ±{' and ±'.join(f'{w:g}' for w in MISMATCHED_RATES)} rad/s
  (away from the scripted 0.25 / 0.35 rad/s turns), cases 1, 3 and 4;
- the comparison the paper omits, every formation at the same desired range {RANGE_M:g} m for every agent (the mean
  start range), so they differ only in bearings: **optimal** (Algorithm 1 at those ranges), **fixed** (the start
  bearings held, translated with the estimate), **trail** (a ±15° fan behind the target), **random** (bearings
  drawn uniformly once per run from the run seed, held like fixed). Same filter and PD law.

Physics cross-check (`worlds/{WORLD}.yaml`, {phys_duration:g} s runs, {phys_runs} per case and formation): three
quadrotors with bearing sensors (σ = 0.1 rad, 10 Hz) share every bearing; each runs the same IMM on the stacked
bearings of the team and flies the formation law (optimal, or the trailing fan, both at {RANGE_M:g} m) around its own
estimate. The car drives road variants of the cases: 1 straight; 2 accelerating at 0.3 m/s² from rest; 3 a circle of
radius 40 m (0.25 rad/s at 10 m/s); 4 straight, left 210°, straight, right 210°.
""",
        tables=(*_tables(res), physics_table(phys, phys_runs, settle)), figures=tuple(figures(ctx, first, series)),
        findings=findings,
        deviations=(
            "The paper's target is a 100 m/s missile with agents 5–10 m away; here a car at 12 m/s with agents "
            "≈ 100 m away (the notes' advice). Case 2's acceleration is scaled from (5, 4) to (0.25, 0.2) m/s² and "
            "case 4's segment durations ×3 so the turns are a car's (radius 34 m).",
            "Bearing noise σ = 0.1 rad: the printed R = √200 I is not meaningful for radians. The absolute error "
            "levels (≈ 5 m, ≈ 10 m) are therefore not compared; the paper's ordering of the cases is judged instead.",
            f"IMM model set CV + CT(±{base.turn_rate} rad/s), q = {base.q_cv} m²/s³, transition diagonal "
            f"{base.p_stay}, no CA model: the paper names CV/CA/CT without matrices, rates or probabilities. The ±0.3 "
            "rad/s bank lies between the scripted 0.25 and 0.35 rad/s turns, so the case-4 claim is also judged with "
            f"banks at ±{' and ±'.join(f'{w:g}' for w in MISMATCHED_RATES)} rad/s (not the paper's configuration).",
            "The filter starts from the least-squares intersection of the first bearings with the target's known "
            "initial velocity (the paper's agents start with it).",
            "Kinematic agents (ideal velocity tracking) rather than the paper's double integrators: the PD law's "
            "acceleration is realised as a velocity step; the comparison isolates geometry.",
            f"Step {base.dt} s for bearings, filter and guidance, speed limit {base.guidance.max_speed} m/s and the "
            "Jacobi PD gains are ours: the paper gives no sample time, limit or gains.",
            f"Steady window t ≥ {SETTLE_S:g} s of the 30 s cases (the paper reads its figures by eye): a random "
            "geometry can lie across the target from the start, several seconds' flight away.",
            f"The baselines (fixed, trail, random) and the optimal formation they are compared with fly a common "
            f"desired range of {RANGE_M:g} m: the paper has no baseline, and its Algorithm 1 (kept for the paper's "
            "claims) uses the agents' current ranges, which would mix a range effect into a geometry comparison.",
            "Case 4's growth at a manoeuvre is judged against case 1 in the same time window (same seeds): the "
            "paper shows it on one error curve; a window before the turn holds the filter's start or the previous "
            "turn's exit.",
            "Physics cross-check: the world's own deviations (quadrotors at 50/60/70 m, a car on road arcs of "
            "radius 40 m, track start from triangulated fixes) are in its header; both formations fly "
            f"{RANGE_M:g} m.",
        ))
