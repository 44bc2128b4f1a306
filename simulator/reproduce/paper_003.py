"""Reproduction of paper 003 (Yang & Wang 2019): FIM-optimal formation with IMM bearings-only tracking.

Runs the kinematic closed loop :mod:`simulator.kinematic.formation` for the paper's four cases, with the
FIM-optimal formation (Algorithm 1 + Jacobi PD control) and two formations that are not optimised (the start geometry
held, and a fan trailing the target), ``ctx.runs`` seeded runs each. The paper has no tables: its claims are
qualitative (error levels per case, growth at manoeuvres until the IMM switches) and it never compares against a
non-optimal formation, which the notes ask us to do.

As a cross-check on PyBullet quadrotors, campaigns of the physics world ``formation_imm`` run each case (its ``--set``
variants) with the FIM-optimal formation and with the trailing fan, ``min(ctx.runs, PHYSICS_RUNS)`` runs each: every
UAV runs the IMM on the whole team's shared bearings and flies the formation law around its own estimate.
"""

from __future__ import annotations

import numpy as np

from simulator.kinematic.formation import CASES, FormationLoopConfig, FormationLoopResult, run_formation_loop
from simulator.reproduce.report import Figure, Finding, PaperReport, ReproContext, Table, mean_ci

__all__ = ["reproduce"]

FORMATIONS = ("optimal", "fixed", "trail")
WORLD = "formation_imm"
PHYSICS_RUNS = 10
"""Runs per case and formation of the physics campaigns (at most ``ctx.runs``): a 60 s run costs ≈ 15 s of wall time."""
PHYSICS_SETTLE_S = 15.0  # the car starts from rest and the tracks from triangulated fixes (world header)
QUICK_DURATION_S = 8.0  # quick mode: one run per configuration, judged over its second half
QUICK_CASES = (1, 2)  # quick mode: in 8 s the car of cases 3 and 4 is still on the lead-in road of case 1
CASE_SETS: dict[int, tuple[str, ...]] = {
    1: (),
    2: ("ground_vehicles[0].driver.accel=0.3", "roads.streets[1].speed_limit=30"),
    3: ("ground_vehicles[0].route.roads=[lead.f, ring_e.f, ring_w.f, ring_e.f, ring_w.f, ring_e.f]",),
    4: ("ground_vehicles[0].route.roads=[lead.f, sbend.f]",),
}
"""The world's ``--set`` variants of the paper's cases (header of ``worlds/formation_imm.yaml``)."""
PHYSICS_FORMATIONS = ("optimal", "trail")
SETTLE_S = 5.0  # steady-state window starts here, s
PAPER_LEVEL = {1: "≈ 5", 2: "≈ 10", 3: "≈ 10", 4: "grows at each manoeuvre"}


def _one(args: tuple[int, str, int, bool]) -> FormationLoopResult:
    case, formation, seed, quick = args
    cfg = FormationLoopConfig(case=case, formation=formation, max_duration=6.0 if quick else None)
    return run_formation_loop(cfg, np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(case,))))


def _run_all(ctx: ReproContext) -> dict[tuple[int, str], list[FormationLoopResult]]:
    jobs = [(case, form, ctx.seed * 100_003 + r, ctx.quick) for case in CASES for form in FORMATIONS
            for r in range(ctx.runs)]
    results = ctx.map(_one, jobs, chunksize=4)
    out: dict[tuple[int, str], list[FormationLoopResult]] = {}
    for (case, form, _, _), res in zip(jobs, results, strict=True):
        out.setdefault((case, form), []).append(res)
    return out


def _steady(res: FormationLoopResult, what: np.ndarray) -> float:
    ok = res.t >= min(SETTLE_S, res.t[-1] / 2)
    return float(np.mean(what[ok]))


def _turn_response(res: FormationLoopResult, dt: float) -> list[dict[str, float]]:
    """Per turn of case 4: error before, peak after the onset, at the turn's end, and the IMM's switching delay."""
    out, t0 = [], 0.0
    for seg in CASES[4]:
        t1 = t0 + seg.duration
        if seg.omega != 0.0 and t1 <= res.t[-1] + 1e-9:
            mode = 1 if seg.omega > 0 else 2
            before = (res.t > t0 - 2.0) & (res.t <= t0)
            early = (res.t > t0) & (res.t <= t0 + 3.0)
            late = (res.t > t1 - 3.0) & (res.t <= t1)
            inside = (res.t > t0) & (res.t <= t1)
            switched = np.flatnonzero(res.mode_probability[inside, mode] > 0.5)
            out.append({"before": float(res.error[before].mean()), "peak": float(res.error[early].max()),
                        "end": float(res.error[late].mean()),
                        "delay": float(res.t[inside][switched[0]] - t0) if switched.size else float("nan")})
        t0 = t1
    return out


def _figures(ctx: ReproContext, runs: dict[tuple[int, str], list[FormationLoopResult]]) -> list[Figure]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colors = {"optimal": "tab:blue", "fixed": "tab:orange", "trail": "tab:red"}
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), dpi=100, sharex=False)
    for ax, case in zip(axes.ravel(), CASES, strict=True):
        for form in FORMATIONS:
            res = runs[(case, form)]
            n = min(len(r.error) for r in res)
            e = np.array([r.error[:n] for r in res])
            t = res[0].t[:n]
            ax.plot(t, e.mean(axis=0), color=colors[form], lw=1.2, label=form)
            if len(res) > 1:
                ax.fill_between(t, np.percentile(e, 10, axis=0), np.percentile(e, 90, axis=0), color=colors[form],
                                alpha=0.15, lw=0)
        ax.set_title(f"case {case}")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("position error (m)")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"IMM position error, mean and 10–90 % band over {len(runs[(1, 'optimal')])} runs")
    fig.tight_layout()
    fig.savefig(ctx.out_dir / "errors.png")
    plt.close(fig)

    fig, axes = plt.subplots(1, 3, figsize=(14, 4.6), dpi=100)
    for ax, form in zip(axes[:2], ("optimal", "trail"), strict=True):
        r = runs[(4, form)][0]
        ax.plot(r.truth[:, 0], r.truth[:, 2], "k-", lw=1.5, label="target")
        for i in range(r.agents.shape[1]):
            ax.plot(r.agents[:, i, 0], r.agents[:, i, 1], lw=1.0, label=f"agent {i + 1}")
        ax.set_aspect("equal")
        ax.set_title(f"case 4, {form} formation")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    r = runs[(4, "optimal")][0]
    for j, name in enumerate(("CV", "CT +", "CT −")):
        axes[2].plot(r.t, r.mode_probability[:, j], label=name)
    axes[2].set_title("case 4: IMM mode probabilities (optimal formation)")
    axes[2].set_xlabel("time (s)")
    axes[2].legend(fontsize=8)
    axes[2].grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(ctx.out_dir / "case4.png")
    plt.close(fig)
    return [Figure(path="errors.png", caption="Position error over time per case and formation (paper's Figs. 4–7)"),
            Figure(path="case4.png", caption="Case 4 trajectories for the optimal and the trailing formation, and "
                                             "the IMM's mode probabilities")]


def _physics_run(run_dir: object, n_uavs: int, sigma: float, settle: float) -> dict[str, float]:
    """One physics run's numbers from its record, over t ≥ ``settle`` (s): the worst UAV's mean position error (m),
    the smallest share of agent steps with an estimate, the mean ln-det gap to the bound of the true geometry, the
    smallest 3-D distance between two UAVs over the whole run (m), and the teammates' bearings used per own one."""
    from autonomy.metrics.fim import bearing_fim, max_det_bearing_fim
    from simulator.runrecord import load_run

    rec = load_run(run_dir)
    est, ut, vt = rec.stream("estimates"), rec.stream("uav_truth"), rec.stream("vehicle_truth")
    t_car = vt["t"]
    errs, cover = [], []
    for k in range(n_uavs):
        mine = est["uav"] == k
        late = mine & (est["t"] >= settle)
        ok = late & est["valid"]
        cover.append(ok.sum() / max(late.sum(), 1))
        tx = np.interp(est["t"][ok], t_car, vt["x"]), np.interp(est["t"][ok], t_car, vt["y"])
        errs.append(float(np.mean(np.hypot(est["x"][ok] - tx[0], est["y"][ok] - tx[1]))) if ok.any() else np.nan)
    uav = np.stack([np.c_[ut["x"], ut["y"], ut["z"]][ut["uav"] == k] for k in range(n_uavs)], axis=1)
    car = np.c_[vt["x"], vt["y"]]
    gaps = []
    for p, c in zip(uav[t_car >= settle, :, :2], car[t_car >= settle], strict=True):
        c2 = 1.0 / (sigma**2 * np.sum((p - c) ** 2, axis=1))
        gaps.append(np.log(max_det_bearing_fim(c2)) - np.log(np.linalg.det(bearing_fim(c, p, sigma))))
    dist = min(float(np.linalg.norm(uav[:, i] - uav[:, j], axis=1).min())
               for i in range(n_uavs) for j in range(i + 1, n_uavs))
    sh = rec.stream("measurement_sharing")
    last = [np.flatnonzero(sh["uav"] == k)[-1] for k in range(n_uavs)]
    mates = min(sh["mates_used"][i] / max(sh["own_used"][i], 1) for i in last)
    return {"error": float(np.max(errs)), "cover": float(min(cover)), "gap": float(np.mean(gaps)),
            "distance": dist, "mates_per_own": float(mates)}


def _physics(ctx: ReproContext) -> tuple[dict[tuple[int, str], list[dict]], int, float]:
    """Per (case, formation): each completed run's numbers (:func:`_physics_run`) plus its collisions; the runs per
    configuration, and the time (s) from which runs are judged."""
    import math

    from simulator.campaign.runner import CampaignConfig, run_campaign
    from worlds.loader import load_world

    world = load_world(WORLD).world
    n = len(world.uavs)
    sigma = math.radians(world.uavs[0].sensors[0].sigma_azimuth_deg)
    runs = 1 if ctx.quick else min(ctx.runs, PHYSICS_RUNS)
    settle = QUICK_DURATION_S / 2 if ctx.quick else PHYSICS_SETTLE_S
    trail = tuple(f"uavs[{i}].autonomy.guidance.formation={{geometry: trail}}" for i in range(n))
    out: dict[tuple[int, str], list[dict]] = {}
    for case, sets in CASE_SETS.items():
        if ctx.quick and case not in QUICK_CASES:
            continue
        for form in PHYSICS_FORMATIONS:
            cdir = ctx.out_dir / "campaigns" / f"case{case}_{form}"
            res = run_campaign(CampaignConfig(world=WORLD, runs=runs, out_dir=cdir, seed=ctx.seed,
                                              duration_s=QUICK_DURATION_S if ctx.quick else None,
                                              overrides=sets + (trail if form == "trail" else ()),
                                              workers=ctx.workers, progress=ctx.progress))
            out[(case, form)] = [
                {**_physics_run(cdir / r.run_dir, n, sigma, settle),
                 "collisions": sum(v for k, v in r.metrics.items() if k.startswith("uavs.") and k.endswith(
                     ".collisions"))}
                for r in res.reports if r.status == "completed"]
    return out, runs, settle


def _physics_findings(phys: dict[tuple[int, str], list[dict]], runs: int,
                      settle: float) -> tuple[Table, list[Finding]]:
    """The cross-check table and findings: optimal vs trailing fan, paired by run seed, per case."""
    def col(case: int, form: str, key: str) -> np.ndarray:
        return np.array([r[key] for r in phys[(case, form)]])

    cases = sorted({c for c, _ in phys})
    rows = []
    for case in cases:
        for form in PHYSICS_FORMATIONS:
            rs = phys[(case, form)]
            rows.append((str(case), form, str(len(rs)), mean_ci(col(case, form, "error")).text(),
                         mean_ci(col(case, form, "gap")).text(2),
                         f"{col(case, form, 'cover').min():.3f}" if rs else "–",
                         f"{col(case, form, 'mates_per_own').min():.2f}" if rs else "–",
                         f"{col(case, form, 'distance').min():.1f}" if rs else "–",
                         str(int(col(case, form, "collisions").sum())) if rs else "–"))
    table = Table(title=f"Cross-check on PyBullet quadrotors: the physics world `{WORLD}` (t ≥ {settle:g} s)",
                  columns=("case", "formation", "runs", "worst UAV's mean e_p (m)", "ln-det gap to the bound",
                           "smallest share of steps with an estimate", "teammates' bearings used per own (min)",
                           "min 3-D distance between UAVs (m)", "collisions"),
                  rows=tuple(rows),
                  note=f"Mean ± 95 % CI over up to {runs} runs per configuration (same run seeds for both "
                       "formations). e_p: each UAV's own IMM estimate against the car's physics truth; the gap is "
                       "ln of the det F bound for the UAVs' true ranges minus ln det F of their true geometry. The "
                       f"world's deviations are in its header (`worlds/{WORLD}.yaml`).")

    def paired(key: str) -> dict[int, object]:
        out = {}
        for case in cases:
            a, b = col(case, "optimal", key), col(case, "trail", key)
            out[case] = mean_ci(a - b) if a.size == b.size and a.size else mean_ci([])
        return out

    def below_zero(d: dict[int, object]) -> bool:
        return all(x.n > 0 and x.half is not None and x.mean + x.half < 0 for x in d.values())

    findings = []
    for key, claim, unit in (
            ("gap", "On quadrotors (physics world), the FIM-optimal formation flies closer to the det F bound than "
                    "the trailing fan", ""),
            ("error", "On quadrotors (physics world), the FIM-optimal formation tracks better than the trailing "
                      "fan (the comparison the paper omits)", " m")):
        d = paired(key)
        complete = len(d) == len(CASE_SETS) and all(x.n > 1 for x in d.values())
        findings.append(Finding(
            claim=claim,
            verdict="not comparable" if not complete else ("reproduced" if below_zero(d) else "not reproduced"),
            why="optimal − trail, paired by run seed: "
                + ", ".join(f"case {c}: {x.text(2)}{unit}" for c, x in d.items())
                + " (rule: the 95 % interval below 0 in every case)"
                + ("" if complete else "; not every case has two or more runs, so no interval")))
    return table, findings


def _world_duration() -> float:
    from worlds.loader import load_world

    return float(load_world(WORLD).world.sim.duration_s)


def reproduce(ctx: ReproContext) -> PaperReport:
    """Run paper 003's cases and compare; see the module docstring."""
    runs = _run_all(ctx)
    phys, phys_runs, settle = _physics(ctx)
    phys_table, phys_findings = _physics_findings(phys, phys_runs, settle)
    phys_duration = QUICK_DURATION_S if ctx.quick else _world_duration()
    base = FormationLoopConfig()
    err = {k: [_steady(r, r.error) for r in v] for k, v in runs.items()}
    gap = {k: [_steady(r, r.max_log_det_fim - r.log_det_fim) for r in v] for k, v in runs.items()}

    rows = []
    for case in CASES:
        diff = mean_ci(np.array(err[(case, "optimal")]) - np.array(err[(case, "trail")]))
        rows.append((str(case), PAPER_LEVEL[case], *(mean_ci(err[(case, f)]).text() for f in FORMATIONS),
                     diff.text()))
    t_err = Table(title="Steady-state position error (m), mean over t ≥ 5 s",
                  columns=("case", "paper (m)", "optimal", "fixed", "trail", "optimal − trail (paired)"),
                  rows=tuple(rows),
                  note=f"Mean ± 95 % CI over {ctx.runs} runs per cell. The paper's levels are read off its "
                       "figures, with a noise it does not define: not comparable in absolute terms.")
    t_gap = Table(title="Geometry quality: ln(det F bound) − ln det F over t ≥ 5 s (0 = optimal)",
                  columns=("case", *FORMATIONS),
                  rows=tuple((str(c), *(mean_ci(gap[(c, f)]).text() for f in FORMATIONS)) for c in CASES))

    turns = [_turn_response(r, base.dt) for r in runs[(4, "optimal")]]
    turn_rows, turn_ok = [], True
    n_turns = min((len(t) for t in turns), default=0)
    for j in range(n_turns):
        vals = {k: [t[j][k] for t in turns] for k in ("before", "peak", "end", "delay")}
        before, peak, end = (mean_ci(vals[k]) for k in ("before", "peak", "end"))
        delay = mean_ci(vals["delay"])
        turn_rows.append((f"turn {j + 1}", before.text(), peak.text(), end.text(), delay.text()))
        switched = np.isfinite(vals["delay"]).mean() >= 0.8
        turn_ok &= bool(peak.mean > 1.2 * before.mean and end.mean < peak.mean and switched)
    t_turn = Table(title="Case 4, optimal formation: error around the manoeuvres (m) and IMM switching delay (s)",
                   columns=("manoeuvre", "error before (last 2 s)", "peak (first 3 s)", "end of turn (last 3 s)",
                            "delay until μ_CT > 0.5"),
                   rows=tuple(turn_rows))

    findings = []
    worse = [c for c in CASES if mean_ci(np.array(err[(c, "optimal")]) - np.array(err[(c, "trail")])).mean >= 0]
    ci_hi = [mean_ci(np.array(err[(c, "optimal")]) - np.array(err[(c, "trail")])) for c in CASES]
    sig = all(d.half is not None and d.mean + d.half < 0 for d in ci_hi)
    findings.append(Finding(
        claim="The FIM-optimal formation tracks better than a non-optimal one (the comparison the paper omits)",
        verdict="reproduced" if not worse and (sig or ctx.runs < 2) else "not reproduced",
        why="optimal − trail paired error difference per case: "
            + ", ".join(f"case {c}: {d.text()} m" for c, d in zip(CASES, ci_hi, strict=True))
            + ("; every interval below 0" if sig else "; not every interval below 0")))
    vs_fixed = [mean_ci(np.array(err[(c, "optimal")]) - np.array(err[(c, "fixed")])) for c in CASES]
    better = [c for c, d in zip(CASES, vs_fixed, strict=True) if d.half is not None and d.mean + d.half < 0]
    findings.append(Finding(
        claim="The FIM-optimal formation also beats the start geometry held fixed",
        verdict="reproduced" if len(better) == len(CASES) else "not reproduced",
        why="optimal − fixed paired error difference: "
            + ", ".join(f"case {c}: {d.text()} m" for c, d in zip(CASES, vs_fixed, strict=True))
            + f"; significantly better in cases {better or 'none'}. The start geometry is already within "
              f"{mean_ci(gap[(1, 'fixed')]).mean:.2f} of the ln det F bound (table below), so in straight-line "
              "cases the optimum buys little and the optimal team's manoeuvring costs some of it back"))
    gaps_ok = all(mean_ci(gap[(c, "optimal")]).mean < min(mean_ci(gap[(c, f)]).mean for f in ("fixed", "trail"))
                  for c in CASES)
    findings.append(Finding(
        claim="Algorithm 1 drives the team to the det F bound (maximal information geometry)",
        verdict="reproduced" if gaps_ok else "not reproduced",
        why="steady ln-det gap to the bound, optimal: "
            + ", ".join(f"case {c} {mean_ci(gap[(c, 'optimal')]).text(2)}" for c in CASES)
            + "; the baselines stay further from it (table below); the remaining gap in cases 3–4 is the lag of "
              "the PD law behind a turning target"))
    findings.append(Finding(
        claim="Case 4: the error grows at each manoeuvre until the IMM switches, then falls back",
        verdict="reproduced" if turn_ok and n_turns == 2 else ("not comparable" if n_turns < 2 else "not reproduced"),
        why=("; ".join(f"{r[0]}: {r[1]} m before, peak {r[2]} m, {r[3]} m at the end, switch after {r[4]} s"
                       for r in turn_rows) if turn_rows else "the shortened run has no complete turn")
            + " (rule: peak > 1.2 × before, end < peak, μ_CT > 0.5 within the turn in ≥ 80 % of runs)"))
    findings.append(Finding(
        claim="Steady error ≈ 5 m in case 1 and ≈ 10 m in cases 2–3",
        verdict="not comparable",
        why=f"ours (optimal): case 1 {mean_ci(err[(1, 'optimal')]).text()} m, case 2 "
            f"{mean_ci(err[(2, 'optimal')]).text()} m, case 3 {mean_ci(err[(3, 'optimal')]).text()} m. The paper's "
            "bearing noise (R = √200 I) has no meaning in radians and its target is a 100 m/s missile 5–10 m from "
            "the agents; we scale to a car and choose σ = 0.1 rad, so only the ordering can be compared: the "
            "paper has cases 2 and 3 above case 1; ours has case 2 "
            + ("above" if mean_ci(err[(2, 'optimal')]).mean > mean_ci(err[(1, 'optimal')]).mean else "below")
            + " and case 3 "
            + ("above" if mean_ci(err[(3, 'optimal')]).mean > mean_ci(err[(1, 'optimal')]).mean else "below")
            + " case 1"))
    findings.extend(phys_findings)

    return PaperReport(
        paper="003", title="FIM-optimal formation and IMM bearings-only tracking (Yang & Wang, IEEE Access 2019)",
        runs=ctx.runs,
        setup=f"""
Kinematic closed loop (`simulator/kinematic/formation.py`): three agents with bearing sensors
(σ = {base.sigma_bearing} rad) every {base.dt} s; an IMM of three EKFs (CV, CT ±{base.turn_rate} rad/s, q = {base.q_cv}
m²/s³, p_stay = {base.p_stay}) on the stacked bearings (the paper's centralised augmented-measurement EKF per mode); the
team flies Algorithm 1's geometry around the estimate with the Jacobi PD law (velocity-tracking agents, ≤
{base.guidance.max_speed} m/s). Baselines with the same filter and PD law: **fixed** — the start geometry held,
translated with the estimate; **trail** — a ±15° fan behind the target at the start range. Target: 12 m/s from
{base.target_p0} heading 45°; agents start at {base.agents_p0} with the target's velocity. Cases: 1 CV; 2 constant
acceleration (0.25, 0.2) m/s²; 3 CT 0.25 rad/s; 4 CV 3 s, CT +0.35 rad/s 10.5 s, CV 3 s, CT −0.35 rad/s 10.5 s, CV 3 s.

Physics cross-check (`worlds/{WORLD}.yaml`, {phys_duration:g} s runs, {phys_runs} per case and formation): three
quadrotors with bearing sensors (σ = 0.1 rad, 10 Hz) share every bearing; each runs the same IMM on the stacked
bearings of the team and flies the formation law (optimal, or the trailing fan) around its own estimate. The car
drives road variants of the cases: 1 straight; 2 accelerating at 0.3 m/s² from rest; 3 a circle of radius 40 m
(0.25 rad/s at 10 m/s); 4 straight, left 210°, straight, right 210°.
""",
        tables=(t_err, t_gap, t_turn, phys_table), figures=tuple(_figures(ctx, runs)), findings=tuple(findings),
        deviations=(
            "The paper's target is a 100 m/s missile with agents 5–10 m away; here a car at 12 m/s with agents "
            "≈ 100 m away (the notes' advice). Case 2's acceleration is scaled from (5, 4) to (0.25, 0.2) m/s² and "
            "case 4's segment durations ×3 so the turns are a car's (radius 34 m).",
            "Bearing noise σ = 0.1 rad: the printed R = √200 I is not meaningful for radians; the notes suggest a "
            "value that puts case 1 near the paper's level.",
            "IMM model set CV + CT(±0.3 rad/s), transition diagonal 0.95: the paper names CV/CA/CT without matrices.",
            "The filter starts from the least-squares intersection of the first bearings with the target's known "
            "initial velocity (the paper's agents start with it).",
            "Kinematic agents (ideal velocity tracking) rather than quadrotors: the comparison isolates geometry.",
        ))
