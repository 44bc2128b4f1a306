"""Paper 000's verdicts: a pure function of the aggregated per-run numbers (:class:`Results`), so the verdict logic is
tested on constructed results (``tests/simulator/test_reproduce_000.py``).

Rules and why:

- every-step claims ("errors are lower than 10 m", "consensus errors are lower than 0.05 m", "inputs satisfy the
  constraints strictly", "distance much larger than 10 m") are judged on the worst value over every run and step
  (:func:`rules.all_below` / :func:`rules.all_at_least`), after a settling time for the estimation claims: our nodes
  start from their own first fixes, metres apart, where the paper's start from one common h = 0, so the first steps
  carry a start-up transient the paper's figures do not have;
- the outage effect is judged as the paired difference over the outage windows between case 2 and its control (same
  seeds and windows, links never cut), so the target's manoeuvres inside the windows cancel;
- "little influence on the tracking performance" is an equivalence claim on the UAV-to-target distance
  (:func:`rules.paired_within`, margin :data:`TRACKING_MARGIN_M`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from simulator.reproduce import rules
from simulator.reproduce.paper_000_loop import CONSENSUS_LIMIT_M, OURS_MARGIN_M, PRIMARY_L, RunSummary
from simulator.reproduce.report import Finding, mean_ci

__all__ = ["ERROR_LIMIT_M", "PAPER_STEP_MS", "PROJECT_STEP_MS", "SEPARATION_M", "SEPARATION_VARIANTS",
           "TRACKING_MARGIN_M", "Results", "collect", "findings"]

ERROR_LIMIT_M = 10.0
SEPARATION_M = 10.0
PAPER_STEP_MS = 61.9e3 / 400 / 4  # 61.9 s for 400 steps of 4 UAVs on a 2.7 GHz Pentium
PROJECT_STEP_MS = 2.0
TRACKING_MARGIN_M = 2.0
"""Equivalence margin of "little influence on the tracking performance" (m of mean UAV-to-target distance over the
outage windows). The paper gives no number: its Figs. 11–12 (not in our text of the paper) are read as "the curves
look alike"; 2 m is a fifth of its 10 m safe distance, the scale on which it plots these distances, and well under
the ≈ 10–20 m the UAVs keep from the target in our runs, so a larger change would be visible in such a figure."""
SEPARATION_VARIANTS: dict[str, tuple[str, bool]] = {
    "paper": ("robust linearisation, margin 0: D' = D", True),
    "half-plane": ("the paper's half-plane (eq. 29), margin 0", True),
    "margin 4 m": (f"robust linearisation, our margin D' = D + {OURS_MARGIN_M:g} m", False),
}
"""Separation configuration → (words, judged on the paper's configuration)."""


@dataclass(frozen=True, kw_only=True)
class Results:
    """Per-run numbers of every configuration (arrays in run-seed order; the same seeds in every configuration).

    ``runs[variant][case]`` holds the :class:`RunSummary` list of that configuration; ``physics`` the cross-check's
    per-run arrays: ``worst_err`` (case 1, worst UAV's whole-run mean e_p, m), ``cover`` (case 1, smallest share of
    steps with an estimate) and ``sep`` (cases 1 and 2 together, m)."""

    runs: dict[str, dict[int, list[RunSummary]]]
    settle_s: float
    mission_s: float
    physics: dict[str, np.ndarray] = field(default_factory=dict)

    def get(self, variant: str, case: int, name: str) -> np.ndarray:
        """``name`` of every run of ``variant`` / ``case`` (empty when not run)."""
        return np.array([getattr(r, name) for r in self.runs.get(variant, {}).get(case, [])], dtype=float)


def collect(summaries: Sequence[RunSummary], settle_s: float, mission_s: float,
            physics: dict[str, np.ndarray] | None = None) -> Results:
    """Group run summaries by configuration and case (keeping their order: run-seed order)."""
    runs: dict[str, dict[int, list[RunSummary]]] = {}
    for s in summaries:
        runs.setdefault(s.variant, {}).setdefault(s.case, []).append(s)
    return Results(runs=runs, settle_s=settle_s, mission_s=mission_s, physics=physics or {})


def _sweep(res: Results) -> dict[int, str]:
    """Consensus iteration counts run on case 1 → configuration name."""
    out = {PRIMARY_L: "paper"}
    for v in res.runs:
        if v.startswith("L="):
            out[int(v[2:])] = v
    return dict(sorted(out.items()))


def findings(res: Results) -> tuple[Finding, ...]:
    """Every verdict of paper 000 from ``res`` (module docstring)."""
    out: list[Finding] = []
    settle = f"after the first {res.settle_s:g} s (start-up transient: the nodes start from their own fixes)"
    e1 = res.get("paper", 1, "err_max")
    out.append(Finding.judged(
        "Case 1: each UAV's position error stays below 10 m", rules.all_below(e1, ERROR_LIMIT_M, " m"),
        paper="\"The position errors are lower than 10m\" (Fig. 4, one run)",
        why=f"largest e_p per run {settle}; mean e_p {mean_ci(res.get('paper', 1, 'err_mean')).text()} m"))
    for n, v in _sweep(res).items():
        c = res.get(v, 1, "cons_max")
        share = res.get(v, 1, "cons_share")
        out.append(Finding.judged(
            f"Case 1, L = {n}: the consensus error stays below {CONSENSUS_LIMIT_M:g} m",
            rules.all_below(c, CONSENSUS_LIMIT_M, " m"),
            paper="\"The consensus errors are lower than 0.05m\" (Fig. 4); L is not printed" +
                  (f" (ours: L = {PRIMARY_L})" if n == PRIMARY_L else ""),
            why=f"largest consensus error per run {settle}: mean {mean_ci(c).text()} m; share of UAV-steps over "
                f"{CONSENSUS_LIMIT_M:g} m {mean_ci(share).text()}",
            paper_claim=n == PRIMARY_L))
    for v, (words, faithful) in SEPARATION_VARIANTS.items():
        for case in (1, 2):
            s = res.get(v, case, "sep_min")
            if s.size == 0:
                continue
            out.append(Finding.judged(
                f"Case {case}: same-altitude UAVs keep the separation D = {SEPARATION_M:g} m ({words})",
                rules.all_at_least(s, SEPARATION_M, " m"),
                paper="\"The collision avoidance distance is much larger than 10m\" (Figs. 6, 12)",
                why=f"smallest horizontal distance per run, whole run: median {np.median(s):.2f} m; the rule asks "
                    "the constraint's own bound D, not the paper's \"much larger\" (which gives no number)",
                paper_faithful=faithful))
    out += _outage_findings(res)
    viol = np.concatenate([res.get("paper", c, "input_violation") for c in (1, 2)])
    out.append(Finding.judged(
        "Inputs stay within their bounds (0 ≤ v ≤ 40 m/s, |ω| ≤ 5 rad/s)", rules.all_below(viol, 1e-9),
        paper="\"the control inputs satisfy the constraints strictly\" (Fig. 7)",
        why="largest excess of an input over its bound per run, cases 1 and 2; holds by construction: the "
            "guidance clips the fixed-iteration solver's inputs to the box before flying them"))
    comp = res.get("paper", 1, "compute_s")
    out.append(Finding.judged(
        f"The whole loop runs faster than the mission ({res.mission_s:g} s)",
        rules.all_below(comp, res.mission_s, " s"),
        paper="61.9 s for the 200 s mission on a 2.7 GHz Pentium: \"high real-time performance\"",
        why=f"computation of the four UAVs (fast MPC, SCIF information step, HCMCI) per case-1 run, this machine; "
            f"mean {mean_ci(comp).text()} s"))
    ms = res.get("paper", 1, "step_ms")
    out.append(Finding.judged(
        f"Computation per UAV per step within the project's {PROJECT_STEP_MS:g} ms target",
        rules.mean_below(ms, PROJECT_STEP_MS, " ms"),
        paper=f"— (the paper's run time is ≈ {PAPER_STEP_MS:.1f} ms per UAV per step, MATLAB on a 2.7 GHz Pentium)",
        why="median over steps of each run; wall time on 2 shared cores", paper_claim=False))
    out += _physics_findings(res)
    return tuple(out)


def _outage_findings(res: Results) -> list[Finding]:
    """Case 2 against its paired control over the outage windows (same seeds and windows, links never cut)."""
    cons_o, cons_c = res.get("paper", 2, "win_cons"), res.get("control", 2, "win_cons")
    if cons_o.size == 0 or cons_c.size != cons_o.size or not np.isfinite(cons_o).any():
        why = "the runs end before the first outage (shortened runs)" if cons_o.size else "case 2 was not run"
        return [Finding(claim="Case 2: the consensus and estimation errors grow while links are down; tracking is "
                              "barely affected", verdict="not comparable", why=why, rule="—", ours="—",
                        paper="Figs. 10–12")]
    err_o, err_c = res.get("paper", 2, "win_err"), res.get("control", 2, "win_err")
    dist_o, dist_c = res.get("paper", 2, "win_dist"), res.get("control", 2, "win_dist")
    names = ("control", "outages")
    paper = "\"The estimation errors and consensus errors increase as the communication topology varies\" (Fig. 10)"
    return [
        Finding.judged("Case 2: the consensus error grows while links are down (paired against no outages)",
                       rules.paired_less(cons_c, cons_o, " m", names=names), paper=paper,
                       why=f"mean consensus error over the outage windows: outages {mean_ci(cons_o).text()} m, "
                           f"control {mean_ci(cons_c).text()} m"),
        Finding.judged("Case 2: the estimation error grows while links are down (paired against no outages)",
                       rules.paired_less(err_c, err_o, " m", names=names), paper=paper,
                       why=f"mean e_p over the outage windows: outages {mean_ci(err_o).text()} m, control "
                           f"{mean_ci(err_c).text()} m"),
        Finding.judged(
            "Case 2: the outages barely affect tracking (UAV-to-target distance, paired against no outages)",
            rules.paired_within(dist_o, dist_c, TRACKING_MARGIN_M, " m", names=names[::-1]),
            paper="\"it has little influence on the tracking performance\" (Figs. 11–12, no number)",
            why=f"mean horizontal UAV-to-target distance over the outage windows: outages {mean_ci(dist_o).text()} m, "
                f"control {mean_ci(dist_c).text()} m; margin ±{TRACKING_MARGIN_M:g} m (a fifth of the paper's 10 m "
                f"safe distance); estimation error outages − control {mean_ci(err_o - err_c).text()} m"),
    ]


def _physics_findings(res: Results) -> list[Finding]:
    """The cross-check on quadrotors (never the paper's configuration: see the world's header)."""
    p = res.physics
    worst, cover, sep = (np.asarray(p.get(k, []), dtype=float) for k in ("worst_err", "cover", "sep"))
    cov = f"every UAV with an estimate at ≥ {np.min(cover):.3f} of its steps" if cover.size else "no run completed"
    return [
        Finding.judged("Case 1 on quadrotors (physics world): each UAV's mean position error is below 10 m",
                       rules.all_below(worst, ERROR_LIMIT_M, " m"),
                       paper="\"The position errors are lower than 10m\" (Fig. 4; every step, unicycle UAVs)",
                       why=f"worst UAV's whole-run mean e_p per run (the physics runs record means, not every "
                           f"step); {cov}", paper_faithful=False),
        Finding.judged("Cases 1 and 2 on quadrotors (physics world): same-altitude UAVs keep D = 10 m",
                       rules.all_at_least(sep, SEPARATION_M, " m"),
                       paper="\"The collision avoidance distance is much larger than 10m\" (Figs. 6, 12)",
                       why=f"smallest horizontal distance per run from the truth at 10 Hz; the world flies our margin "
                           f"D' = D + {OURS_MARGIN_M:g} m", paper_faithful=False),
    ]
