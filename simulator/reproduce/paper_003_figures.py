"""Paper 003's figures: error over time per case and formation, and case 4's trajectories and mode probabilities."""

from __future__ import annotations

import numpy as np

from simulator.kinematic.formation import FormationLoopResult
from simulator.reproduce.paper_003_runs import FORMATIONS, PAPER
from simulator.reproduce.report import Figure, ReproContext

__all__ = ["figures"]

COLORS = {PAPER: "black", "optimal": "tab:blue", "fixed": "tab:orange", "trail": "tab:red", "random": "tab:green"}


def figures(ctx: ReproContext, first: dict[tuple[int, str], FormationLoopResult],
            series: dict[tuple[int, str], np.ndarray]) -> list[Figure]:
    """Write ``errors.png`` and ``case4.png`` (or the cases present) into ``ctx.out_dir``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = sorted({c for c, _ in first})
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), dpi=100)
    for ax, case in zip(axes.ravel(), cases, strict=False):
        for form in (PAPER, *FORMATIONS):
            e, t = series[(case, form)], first[(case, form)].t
            ax.plot(t, e.mean(axis=0), color=COLORS[form], lw=1.2, label=form)
            if len(e) > 1:
                ax.fill_between(t, np.percentile(e, 10, axis=0), np.percentile(e, 90, axis=0), color=COLORS[form],
                                alpha=0.12, lw=0)
        ax.set_title(f"case {case}")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("position error (m)")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    n = len(series[(cases[0], PAPER)])
    fig.suptitle(f"IMM position error, mean and 10–90 % band over {n} runs ({PAPER}: Algorithm 1 on current ranges; "
                 "the others at one common range)")
    fig.tight_layout()
    fig.savefig(ctx.out_dir / "errors.png")
    plt.close(fig)

    case = 4 if (4, "optimal") in first else cases[-1]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.6), dpi=100)
    for ax, form in zip(axes[:2], (PAPER, "trail"), strict=True):
        r = first[(case, form)]
        ax.plot(r.truth[:, 0], r.truth[:, 2], "k-", lw=1.5, label="target")
        for i in range(r.agents.shape[1]):
            ax.plot(r.agents[:, i, 0], r.agents[:, i, 1], lw=1.0, label=f"agent {i + 1}")
        ax.set_aspect("equal")
        ax.set_title(f"case {case}, {'Algorithm 1 (paper)' if form == PAPER else form} formation")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    r = first[(case, PAPER)]
    for j, name in enumerate(("CV", "CT +", "CT −")):
        axes[2].plot(r.t, r.mode_probability[:, j], label=name)
    axes[2].set_title(f"case {case}: IMM mode probabilities (paper's configuration)")
    axes[2].set_xlabel("time (s)")
    axes[2].legend(fontsize=8)
    axes[2].grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(ctx.out_dir / "case4.png")
    plt.close(fig)
    return [Figure(path="errors.png", caption="Position error over time per case and formation (paper's Figs. 9, "
                                              "11, 13, 15): the paper's Algorithm 1, and the four formations flown "
                                              "at one common range"),
            Figure(path="case4.png", caption=f"Case {case} trajectories for the paper's Algorithm 1 and the "
                                             "trailing formation (first run seed), and the IMM's mode probabilities")]
