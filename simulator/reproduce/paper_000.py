"""Reproduction of paper 000 (Hu et al. 2018): SCIF + HCMCI consensus + fast MPC, cases 1 and 2.

Runs the kinematic closed loop :mod:`simulator.kinematic.consensus` ``ctx.runs`` times per configuration on common
seeds (the paper ran each case once; its results are qualitative and shown in figures only): the paper's cases, case
2's no-outage control, an L sweep and three separation configurations (:mod:`paper_000_loop`); and, as a cross-check on
PyBullet quadrotors, a campaign of the physics world ``consensus_fmpc`` per case (:mod:`paper_000_physics`). The
verdicts are a pure function of the per-run numbers (:mod:`paper_000_verdicts`).
"""

from __future__ import annotations

import numpy as np

from simulator.kinematic.consensus import ConsensusLoopConfig, ConsensusLoopResult
from simulator.reproduce.paper_000_loop import (CONSENSUS_LIMIT_M, NEAR_NADIR_M, OURS_MARGIN_M, PRIMARY_L, RunSummary,
                                                jobs_for, run_job)
from simulator.reproduce.paper_000_physics import WORLD, physics_runs, physics_table
from simulator.reproduce.paper_000_verdicts import (PAPER_STEP_MS, PROJECT_STEP_MS, SEPARATION_VARIANTS,
                                                    TRACKING_MARGIN_M, Results, collect, findings)
from simulator.reproduce.report import Figure, PaperReport, ReproContext, Table, mean_ci

__all__ = ["reproduce"]

SETTLE_STEPS = 20  # steps excluded from the every-step estimation claims (10 s): the start-up transient
QUICK_STEPS = 40


def _figures(ctx: ReproContext, runs: dict[int, ConsensusLoopResult]) -> list[Figure]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(12, 7), dpi=100)
    for col, case in enumerate((1, 2)):
        r = runs[case]
        for j in range(r.error.shape[1]):
            axes[0, col].plot(r.t, r.error[:, j], lw=0.9, label=f"UAV {j + 1}")
            axes[1, col].semilogy(r.t, np.maximum(r.consensus_error[:, j], 1e-6), lw=0.9, label=f"UAV {j + 1}")
        for ax in axes[:, col]:
            if r.outage.any():
                ax.fill_between(r.t, 0, 1, where=r.outage, transform=ax.get_xaxis_transform(), color="tab:red",
                                alpha=0.12, lw=0, label="link down")
            ax.grid(alpha=0.3)
            ax.set_xlabel("time (s)")
        axes[0, col].set_title(f"case {case}: position error ‖p̂_j − p‖ (m)")
        axes[1, col].set_title(f"case {case}: consensus error (m)")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(ctx.out_dir / "errors.png")
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 6), dpi=100)
    r = runs[1]
    ax.plot(r.target[:, 0], r.target[:, 1], "k-", lw=2, label="target")
    for j in range(r.uav.shape[1]):
        ax.plot(r.uav[:, j, 0], r.uav[:, j, 1], lw=0.8, label=f"UAV {j + 1}")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("case 1: target and UAV paths (m)")
    fig.tight_layout()
    fig.savefig(ctx.out_dir / "paths.png")
    plt.close(fig)
    return [Figure(path="errors.png", caption="Position and consensus errors of one run per case, paper's "
                                              "configuration (paper's Figs. 4 and 10)"),
            Figure(path="paths.png", caption="Target and UAV paths, case 1 (paper's Fig. 5)")]


def _ci(res: Results, v: str, c: int, name: str) -> str:
    return mean_ci(res.get(v, c, name)).text()


def _tables(res: Results, runs: int) -> list[Table]:
    """The kinematic tables: tracking per case, L sweep, separation, outage effect, case 2's error peak, timing."""
    main = Table(title=f"Tracking and consensus on the paper's configuration (after the first {res.settle_s:g} s)",
                 columns=("case", "paper e_p (m)", "mean e_p (m)", "largest e_p per run (m)",
                          "paper consensus (m)", "largest consensus error per run (m)",
                          f"share of UAV-steps over {CONSENSUS_LIMIT_M:g} m", "largest consensus error in the first "
                                                                              f"{res.settle_s:g} s (m)"),
                 rows=tuple((lab, "< 10" if c == 1 and v == "paper" else "–", _ci(res, v, c, "err_mean"),
                             _ci(res, v, c, "err_max"), "< 0.05" if c == 1 and v == "paper" else "–",
                             _ci(res, v, c, "cons_max"), _ci(res, v, c, "cons_share"),
                             _ci(res, v, c, "cons_max_transient"))
                            for lab, v, c in (("1", "paper", 1), ("2", "paper", 2),
                                              ("2, links never cut (control)", "control", 2))),
                 note=f"Mean ± 95 % CI over {runs} runs. The first {res.settle_s:g} s are left out of the every-step "
                      "claims: each node starts from its own first fix (the paper's common h = 0 start is km off), "
                      "so the four estimates start metres apart and the consensus needs a few steps to pull them "
                      "together; the last column shows that transient.")
    sweep = {PRIMARY_L: "paper", **{int(v[2:]): v for v in res.runs if v.startswith("L=")}}
    lsw = Table(title="Case 1: consensus error against the number of HCMCI iterations L (the paper does not print L)",
                columns=("L", "largest per run, mean (m)", "largest over all runs (m)",
                         f"share of UAV-steps over {CONSENSUS_LIMIT_M:g} m", "mean e_p (m)"),
                rows=tuple((f"{n}" + (" (ours)" if n == PRIMARY_L else ""), _ci(res, v, 1, "cons_max"),
                            f"{np.max(res.get(v, 1, 'cons_max')):.3g}", _ci(res, v, 1, "cons_share"),
                            _ci(res, v, 1, "err_mean"))
                           for n, v in sorted(sweep.items())),
                note=f"After the first {res.settle_s:g} s; same seeds for every L.")
    sep = Table(title="Smallest horizontal distance between same-altitude UAVs (D = 10 m)",
                columns=("separation constraint", "case", "paper's configuration", "per-run minimum, mean (m)",
                         "smallest over all runs (m)", "mean e_p (m)"),
                rows=tuple((words, str(c), "yes" if faithful else "no (ours)", _ci(res, v, c, "sep_min"),
                            f"{np.min(res.get(v, c, 'sep_min')):.2f}", _ci(res, v, c, "err_mean"))
                           for v, (words, faithful) in SEPARATION_VARIANTS.items() for c in (1, 2)
                           if res.get(v, c, "sep_min").size),
                note="The planner keeps D' = D + margin; the paper plans with D itself. Same seeds in every row.")
    tables = [main, lsw, sep]
    o = res.get("paper", 2, "win_cons")
    if o.size and np.isfinite(o).any():
        rows = []
        for lab, name in (("consensus error (m)", "win_cons"), ("position error e_p (m)", "win_err"),
                          ("UAV-to-target distance (m)", "win_dist")):
            a, b = res.get("paper", 2, name), res.get("control", 2, name)
            rows.append((lab, mean_ci(a).text(), mean_ci(b).text(), mean_ci(a - b).text()))
        tables.append(Table(title="Case 2: the outage windows (steps 150–200 and 300–350), outages against the "
                                  "paired control", columns=("mean over the windows", "links cut", "links never cut",
                                                             "paired difference"),
                            rows=tuple(rows),
                            note="Same seeds, same windows, same weights; only the two links differ. The target "
                                 "stops inside the first window. Tracking equivalence margin "
                                 f"±{TRACKING_MARGIN_M:g} m."))
        rows = []
        for lab, v in (("links cut", "paper"), ("links never cut (control)", "control")):
            near = res.get(v, 2, "peak_near")
            rows.append((lab, _ci(res, v, 2, "peak_err"), f"{np.median(res.get(v, 2, 'peak_step')):.0f}",
                         _ci(res, v, 2, "peak_speed"), f"{np.mean(near >= 2):.2f}", _ci(res, "paper", 1, "err_max")))
        tables.append(Table(title="Case 2's error peak in the first outage window (the target's stop)",
                            columns=("case 2", "peak mean e_p (m)", "median step of the peak",
                                     "target speed at the peak (m/s)",
                                     f"share of runs with ≥ 2 UAVs within {NEAR_NADIR_M:g} m of the target",
                                     "case 1's largest e_p, for scale (m)"),
                            rows=tuple(rows), note=_SPIKE_NOTE))
    tables.append(Table(title="Computation per UAV per step: fast MPC + SCIF information step + its share of HCMCI",
                        columns=("case", "paper (ms)", "ours, median (ms)", "project target (ms)"),
                        rows=tuple((str(c), f"{PAPER_STEP_MS:.1f}", _ci(res, "paper", c, "step_ms"),
                                    f"≤ {PROJECT_STEP_MS:g}") for c in (1, 2)),
                        note="Wall time on this machine (2 shared cores), this process; the paper's figure is for "
                             "MATLAB on a 2.7 GHz Pentium."))
    return tables


_SPIKE_NOTE = (
    "Case 2's largest errors come in the first window, while the target brakes to its stop (78–90 s), with or "
    "without the outages: the control's peak is of the same size, so comparing case 2 inside and outside the windows "
    "measures the stop, not the outages; the paired difference above removes it. Case 1 (same stop, same seeds; last "
    "column) has no such peak, so it comes with case 2's weights: UAV 1 and 3 (w_x = w_y = 0.2) trail the braking "
    "target. A suspected mechanism is near-nadir geometry: a UAV within a few metres of the target's nadir sees it at "
    "a nadir angle inside its own noise (σ ≈ 5°, ≈ 9 m at 100 m), where the azimuth's sensitivity to position grows "
    "as 1/ρ and the cubature filter's Gaussian approximation is poor; the column before last says how often two or "
    "more UAVs were that close at the peak, i.e. whether the geometry accompanies it. We do not mitigate it (the "
    "paper's filter and guidance are kept).")


def reproduce(ctx: ReproContext) -> PaperReport:
    """Run paper 000's configurations and judge its claims; see the module docstring."""
    steps = QUICK_STEPS if ctx.quick else ConsensusLoopConfig().steps
    settle = min(SETTLE_STEPS, QUICK_STEPS // 2) if ctx.quick else SETTLE_STEPS
    cfg = ConsensusLoopConfig()
    out = ctx.map(run_job, jobs_for(ctx.run_seeds(), steps, settle), store="loops",
                  types=(RunSummary, ConsensusLoopResult))
    kept = {s.case: r for s, r in out if r is not None}
    phys_tab, phys = physics_table(physics_runs(ctx))
    res = collect([s for s, _ in out], settle_s=settle * cfg.dt, mission_s=steps * cfg.dt, physics=phys)
    return PaperReport(
        paper="000",
        title="Decentralized estimation and tracking with SCIF, HCMCI and fast MPC (Hu et al., IEEE Access 2018)",
        runs=ctx.runs,
        setup=f"""
Kinematic closed loop (`simulator/kinematic/consensus.py`): four unicycle UAVs (T = {cfg.dt} s, 0 ≤ v ≤
{cfg.mpc.v_max:g} m/s, |ω| ≤ {cfg.mpc.omega_max:g} rad/s) at {cfg.altitudes} m from {cfg.initial}; nadir-angle
radars with the printed R_j (read as variances); one SCIF per UAV on the Euler-discretised Singer model (the paper's;
α = {cfg.singer_alpha}, σa = {cfg.singer_sigma_a}); HCMCI with Metropolis weights, L = {PRIMARY_L}, b = "safe" over
the ring 1–3–2–4–1, L rounds per step of one synchronous consensus; fast MPC (horizon {cfg.mpc.horizon}, the paper's
weights per UAV and case, separation D = {cfg.mpc.separation_distance:g} m with margin 0 in the paper's configuration,
primal-dual interior point with a fixed iteration cap). Configurations, all on the same seeds: the paper's cases 1
and 2; case 2 with its links never cut (the control); case 1 with L in an L sweep; cases 1 and 2 with the paper's
half-plane separation, and with our planner margin of {OURS_MARGIN_M:g} m.
{"Quick mode: " + str(QUICK_STEPS) + " steps." if ctx.quick else "400 steps (200 s)."} On quadrotors: the physics
world `{WORLD}` (exact Singer discretisation, HCMCI as one team step per agent tick; see the deviations).
""",
        tables=(*_tables(res, ctx.runs), phys_tab), figures=tuple(_figures(ctx, kept)), findings=findings(res),
        deviations=_DEVIATIONS)


_DEVIATIONS = (
    "The target's path is given only as a figure: a scripted stop-and-go drive with turns from (4500, −8) "
    "(`STOP_AND_GO`); it stops at 78–90 s, inside case 2's first outage window.",
    "Filters start from each UAV's first measurement, not from the paper's h = 0 (the origin, km away); the "
    "every-step estimation claims are therefore judged after a 10 s settling time (the start-up transient is tabled).",
    "The ring 1–3–2–4–1 is our choice of topology containing the links 1–3 and 1–4 that case 2 cuts (the paper's "
    "topology is a figure).",
    f"The paper does not print its HCMCI iteration count L nor its weights: ours L = {PRIMARY_L}, Metropolis weights "
    "and the gain b = \"safe\" (no measurement counted twice); an L sweep shows how the consensus claim depends on L.",
    "Separation in the paper's configuration uses the constraint linearised along the line joining the two UAVs (the "
    "robust variant), not the paper's half-plane (eq. 29); the half-plane runs as a second paper-faithful "
    "configuration on the same seeds.",
    f"Our planner margin D' = D + {OURS_MARGIN_M:g} m (`FastMpcConfig.separation_margin`, the default of the "
    "shipped worlds) is judged apart (paper_faithful = False); the paper's configuration plans with D' = D.",
    "Fast MPC details the paper leaves open: reference = previous inputs shifted and rolled out (the paper shifts "
    "states), a heading regulariser ε θ², slack-softened separation (ρ₁ e + ρ₂ e²), interior-point centring and step "
    "rule ours (`autonomy/guidance/fast_mpc.py`, `pdip.py`).",
    "Case 2's outage effect is judged against a paired control (case 2 with no outages) over the outage windows, "
    "not as the paper's single run inside against outside the windows (which the target's stop confounds).",
    "\"Little influence on the tracking performance\" is judged on the UAV-to-target distance with an equivalence "
    f"margin of ±{TRACKING_MARGIN_M:g} m of our choosing (the paper gives no number).",
    "Monte Carlo over measurement noise (the paper shows one run per case); timing on this machine, not the paper's "
    "2.7 GHz Pentium.",
    "On quadrotors (`consensus_fmpc`), beyond the world's header: the estimator uses the exact Singer discretisation "
    "(the paper and our kinematic loop: Euler); HCMCI runs its L rounds as one synchronous team step with perfect "
    "comms at each agent tick, not as L rounds of radio messages; the planner keeps our 4 m margin; case 2 sets the "
    "paper's outages and UAV 1 and 3's case-2 weights through overrides.",
)
