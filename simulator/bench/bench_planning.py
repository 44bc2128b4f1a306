"""Planning benchmarks: one step of the communication-aware information planner (3 UAVs, paper 001 scenario 3,
team objective, log-det criterion, 7 heading rates × 3 steps = 343 sequences per UAV, two coordinate-ascent sweeps)
and one step of the FIM-optimal formation law for the whole team (3 agents, Algorithm 1, 72-step rotation search
refined 40-fold, Jacobi PD). Figures are medians over repeated calls; the planner is fresh each call (no warm start).
"""

from __future__ import annotations

import time

import numpy as np

from autonomy.guidance.formation.guidance import FormationConfig, formation_step
from autonomy.guidance.infoplan.config import InfoPlannerConfig
from autonomy.guidance.infoplan.planner import TeamInfoPlanner
from interfaces.state import TargetEstimate
from simulator.bench.registry import BenchRecord, benchmark, median_of, time_call

_REPEATS = 15


@benchmark("planning", produces=("info_planner_step_ms", "formation_step_us"))
def bench_planning() -> list[BenchRecord]:
    """Wall time of one team planning step of each law (median of repeats)."""
    cfg = InfoPlannerConfig(base_p_W=(-500.0, -1000.0), d_safe=250.0)
    p = np.array([[-400.0, -900.0], [-800.0, 300.0], [-800.0, 0.0]])
    chi = np.deg2rad([10.0, 0.0, 0.0])
    p_t, v_t = np.array([-800.0, 600.0]), 10.0 * np.array([np.cos(-0.349), np.sin(-0.349)])
    TeamInfoPlanner(cfg).plan(p, chi, p_t, v_t)  # import and cache warm-up
    info_ms = 1e3 * median_of(lambda: time_call(lambda: TeamInfoPlanner(cfg).plan(p, chi, p_t, v_t)), _REPEATS)

    fcfg = FormationConfig(team_size=3, ranges=(40.0, 50.0, 60.0))
    q = np.array([[0.0, 5.0], [5.0, -2.0], [0.0, 0.0]])
    v = np.tile([8.5, 8.5], (3, 1))
    target = TargetEstimate(t=0.0, p_W=[5.0, 5.0], v_W=[8.5, 8.5])
    formation_step(q, v, target, fcfg)
    n_inner = 20

    def many() -> float:
        t0 = time.perf_counter()
        for _ in range(n_inner):
            formation_step(q, v, target, fcfg)
        return (time.perf_counter() - t0) / n_inner

    form_us = 1e6 * median_of(many, _REPEATS)
    return [BenchRecord(name="info_planner_step_ms", value=info_ms, unit="ms", better="lower"),
            BenchRecord(name="formation_step_us", value=form_us, unit="us", better="lower")]
