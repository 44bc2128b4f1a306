"""Paper 001's tables and figure, from the kinematic runs (:mod:`simulator.reproduce.paper_001`)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from simulator.reproduce.paper_001_findings import PAPER, Results, runs_to_resolve
from simulator.reproduce.paper_001_loop import TARGET_ACCEL_STD, LoopResult
from simulator.reproduce.paper_001_physics import (CHAIN4, PAPER4_A3_DIRECT, PAPER4_BETA, PAPER4_ERRORS,
                                                   relay_patterns)
from simulator.reproduce.report import Figure, ReproContext, Table, mean_ci

__all__ = ["tables", "figures"]

PAPER2_TRACE = {"A": (72.4468, 50.5545, 55.9077), "B": (46.2311, 52.0081, 60.4408)}
PAPER4_TRACE = (40.7112, 13.0033, 13.1245, 14.9834)
NAMES = {"A": "A: paper's eq. 42 (own delivered trace)", "B": "B: paper's sensing trace (β ≡ 1)",
         "chain": "paper's eq. 42 over the fixed chain", "team": "ours: team log-det over the MST",
         "team_B": "ours: team log-det, β ≡ 1", "team_chain": "ours: team log-det over the fixed chain"}
Flights = dict[tuple[str, str], list[LoopResult]]


def _c(values: list[float] | np.ndarray, digits: int = 3) -> str:
    return mean_ci(values).text(digits)


def _table2(fl: Flights, runs: int) -> Table:
    rows = []
    for v in ("A", "B", "team", "team_B"):
        o = fl[("1", v)]
        ours = (_c([x.base_err for x in o]), *(_c([x.uav_err[i] for x in o]) for i in (0, 1)),
                *(_c([x.beta[i] for x in o], 2) for i in (0, 1)), _c([x.base_trace for x in o]),
                *(_c([x.uav_trace[i] for x in o]) for i in (0, 1)))
        if v in ("A", "B"):
            k = 0 if v == "A" else 1
            paper = (PAPER["base_1"][k], *PAPER["uav_1"][k], *PAPER["beta_1"][k], *PAPER2_TRACE[v])
            rows.append((NAMES[v], *(f"{p:g} / {q}" for p, q in zip(paper, ours, strict=True))))
        else:
            rows.append((NAMES[v], *(f"– / {q}" for q in ours)))
    return Table(title="Table 2 (scenario 1, moving target): paper / ours",
                 columns=("configuration", "base error (m)", "A1 error (m)", "A2 error (m)", "A1 β", "A2 β",
                          "base tr(Y)", "A1 tr(Y)", "A2 tr(Y)"),
                 rows=tuple(rows),
                 note=f"Ours: mean ± 95 % CI over {runs} runs (the paper: 10). tr(Y): time-averaged trace of the "
                      "filter's whole information matrix (the paper does not state its units, so only orderings "
                      "compare).")


def _table4(fl: Flights) -> Table:
    rows = []
    for v, pv in (("A", PAPER["base_2"][0]), ("chain", PAPER["base_2"][1]), ("team", None), ("team_chain", None)):
        o = fl[("2", v)]
        rows.append((NAMES[v], "–" if pv is None else f"{pv:g}", _c([x.base_err for x in o]),
                     *(_c([x.uav_err[i] for x in o]) for i in (0, 1)),
                     *(_c([x.beta[i] for x in o], 2) for i in (0, 1))))
    return Table(title="Table 4 (scenario 2, static target): MST against the fixed relay chain",
                 columns=("configuration", "paper base error (m)", "ours base error (m)", "A1 error (m)",
                          "A2 error (m)", "A1 β", "A2 β"), rows=tuple(rows),
                 note="Paper, Table 4: A1/A2 errors 0.7203/1.1680 m (MST) and 0.9029/0.7240 m (chain), β "
                      "0.7463/0.9818 and 0.9209/0.6051.")


def _static(fl: Flights, cfg: object, bound: Callable[..., float], res: Results) -> Table:
    """Why our static-target errors exceed Table 4's: what the paper's own filter model allows at best."""
    rows = []
    for v in ("A", "team"):
        o = fl[("2", v)]
        rows.append((f"{NAMES[v]}: our base error over the whole run / over t ≥ 10 s / the base filter's own "
                     "√tr P_pos (time mean)",
                     f"{_c([x.base_err for x in o])} / {_c([x.base_err_late for x in o])} / "
                     f"{_c([x.base_sigma for x in o])}"))
    for label, args in ((f"the paper's filter model (CV, δ = {TARGET_ACCEL_STD:g} m/s²)", (TARGET_ACCEL_STD,)),
                        ("a CV filter without process noise (velocity still estimated)", (0.0,)),
                        ("a position-only filter of a static target (velocity known to be 0)", (0.0, True))):
        rows.append((f"best case: two UAVs circling the target in quadrature at v/ω_max = 95.5 m, every packet "
                     f"delivered, {label}", f"{bound(cfg, *args):.3f}"))
    d = res.configs[("2", "A")].base_err - res.configs[("2", "chain")].base_err
    return Table(title="Why scenario 2's base errors exceed the paper's Table 4 (0.4266 m)",
                 columns=("quantity", "mean ‖p̂ − p‖ at the base (m)"), rows=tuple(rows),
                 note="Best case: the time mean over 100 s of √(π/4 · tr P_pos), the mean error of a circular "
                      "Gaussian, from the information recursion with the runs' prior (5 m, 2 m/s), δr = 2 m, "
                      "δθ = 0.05 rad. With the paper's stated target model (δ = 0.1 m/s²) even perfect geometry and "
                      "delivery cannot go below the first best-case figure; the paper's 0.4266 m matches a filter "
                      "that knows the target is static (the last), which the paper does not describe. Our runs use "
                      "the stated model, so their errors sit near its floor; MST against chain is a difference of "
                      f"such errors ({runs_to_resolve(d, PAPER['base_2'][0] - PAPER['base_2'][1])}).")


def _table3(fl: Flights) -> Table:
    rows = []
    for v in ("A", "team"):
        o = fl[("3", v)]
        rows.append((NAMES[v], _c([np.mean(["A2→A3→A1→B" in r for r in relay_patterns(x.parent)]) for x in o], 2),
                     _c([x.beta[1] for x in o], 2), _c([x.direct_beta[1] for x in o], 2),
                     _c([x.base_err for x in o]), *(_c([x.uav_err[i] for x in o]) for i in range(3))))
    return Table(title="Scenario 3 (three UAVs, moving target): relay chain and A2's route probability",
                 columns=("configuration", "share of steps with A2 → A3 → A1 → B", "A2's β", "A2's direct β",
                          "base error (m)", "A1 error (m)", "A2 error (m)", "A3 error (m)"),
                 rows=(("paper", "the pattern of Figs. 17–19", "about 0.5 (Table 6: 0.4653)", "< 0.1", "1.2454",
                        "6.2889", "1.7638", "4.0183"), *rows))


def _table8(fl: Flights) -> Table:
    paper = (*PAPER4_ERRORS, *PAPER4_BETA, PAPER4_A3_DIRECT, *PAPER4_TRACE)
    rows = [("paper", *(f"{p:.4g}" for p in paper), "from t ≈ 10 s (Figs. 23–24)")]
    for v in ("A", "team"):
        o = fl[("4", v)]
        rows.append((NAMES[v], _c([x.base_err for x in o]), *(_c([x.uav_err[i] for x in o]) for i in range(3)),
                     *(_c([x.beta[i] for x in o], 2) for i in range(3)), _c([x.direct_beta[2] for x in o], 2),
                     _c([x.base_trace for x in o]), *(_c([x.uav_trace[i] for x in o]) for i in range(3)),
                     _c([np.mean([CHAIN4 in r for r in relay_patterns(x.parent)]) for x in o], 2)))
    return Table(title="Table 8 (scenario 4, three UAVs, static target)",
                 columns=("configuration", "base error (m)", "A1 error (m)", "A2 error (m)", "A3 error (m)", "A1 β",
                          "A2 β", "A3 β", "A3's direct β", "base tr(Y)", "A1 tr(Y)", "A2 tr(Y)", "A3 tr(Y)",
                          f"share of steps with {CHAIN4.replace('→', ' → ')}"),
                 rows=tuple(rows), note="tr(Y) as in Table 2; the static-target errors as in scenario 2's note.")


def _table5(res: Results) -> Table:
    ns = sorted(next(iter(res.sweep.values()))) if res.sweep else []
    rows = tuple((NAMES[v], *(_c(res.sweep[v][n]) for n in ns)) for v in res.sweep)
    runs = len(next(iter(res.sweep.get("A", {}).values()), []))
    return Table(title="Scenario 5: base-station error (m) against team size N (random starts in a 2 km square)",
                 columns=("configuration", *(f"N = {n}" for n in ns)), rows=rows,
                 note=f"Mean ± 95 % CI over {runs} runs per N (the paper: a monotonic decrease in its Fig. 27, "
                      "100 runs per N).")


def tables(res: Results, fl: Flights, ctx: ReproContext, bound: Callable[..., float]) -> tuple[Table, ...]:
    """Every kinematic table: the paper's numbers beside ours."""
    from simulator.reproduce.paper_001 import SCENARIOS

    return (_table2(fl, ctx.runs), _table4(fl), _static(fl, SCENARIOS["2"][0], bound, res), _table3(fl),
            _table8(fl), _table5(res))


def figures(ctx: ReproContext, fl: Flights, res: Results) -> list[Figure]:
    """Scenario 1's paths with the relay links (the paper's configuration and ours) and scenario 5's errors."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from simulator.reproduce.paper_001 import SCENARIOS

    base = np.asarray(SCENARIOS["1"][0].base_p_W)
    fig, axes = plt.subplots(1, 3, figsize=(18, 5.5), dpi=100)
    for ax, v in zip(axes[:2], ("A", "team"), strict=True):
        r = fl[("1", v)][0]
        ax.plot(r.target_p_W[:, 0], r.target_p_W[:, 1], "k-", lw=2, label="target")
        for i in range(r.p_W.shape[1]):
            ax.plot(r.p_W[:, i, 0], r.p_W[:, i, 1], lw=1.0, label=f"A{i + 1}")
        ax.plot(*base, "ks", ms=9, label="base B")
        for k in range(0, len(r.parent), 10):
            for i, par in enumerate(r.parent[k]):
                a = r.p_W[k + 1, i]
                b = base if par == -1 else (r.p_W[k + 1, int(par)] if par >= 0 else None)
                if b is not None:
                    ax.plot([a[0], b[0]], [a[1], b[1]], color="0.6", lw=0.6)
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(f"Scenario 1, {NAMES[v]}: first run, links every 10 s", fontsize=9)
    ax = axes[2]
    for v, d in res.sweep.items():
        ns = sorted(d)
        m = [mean_ci(d[n]) for n in ns]
        ax.errorbar(ns, [c.mean for c in m], yerr=[c.half or 0 for c in m], marker="o", label=NAMES[v])
    ax.set_xlabel("number of UAVs N")
    ax.set_ylabel("base station mean position error (m)")
    ax.set_title("Scenario 5: base error against team size")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(ctx.out_dir / "scenarios.png")
    plt.close(fig)
    return [Figure(path="scenarios.png", caption="Scenario 1 paths with the relay links (paper's Figs. 6–8) for the "
                                                 "paper's objective and ours, and scenario 5's base error against N "
                                                 "(paper's Fig. 27)")]
