"""Benchmark of team size: the demo town flown by 2, 10 and 50 radar UAVs that share their states.

Each UAV of the team is the demo's first UAV (a GMTI radar at 2 Hz, an EKF on a constant-velocity model at 10 Hz,
vector-field standoff guidance with phase keeping over the whole team) and the team shares only its states (no
fusion: :class:`autonomy.team.independent.IndependentTeam`), so every UAV's guidance reads all its teammates at every
step. The world keeps the demo's roads, buildings and target car and leaves out its traffic cars: with them every UAV
runs the multi-target tracker, whose cost the traffic benchmarks (``traffic_rtf``, ``mtt_*``) measure. The UAVs
start on a ring around the block, their altitudes layered 2 m apart so the orbit can hold fifty.
"""

from __future__ import annotations

import copy
import math
import statistics
from typing import Any

import yaml

from simulator.bench.registry import BenchRecord, benchmark

__all__: list[str] = []

TEAM_SIZES = (2, 10, 50)
DURATION_S = 30.0
REPEATS = 3
RING_CENTRE_M = (150.0, 100.0)
RING_RADIUS_M = 250.0
ALTITUDE_M = 60.0
ALTITUDE_STEP_M = 2.0
ALTITUDE_LAYERS = 10


def team_world(n: int, duration_s: float = DURATION_S) -> dict[str, Any]:
    """The demo world's data with ``n`` copies of its first UAV (module docstring), run for ``duration_s``."""
    from worlds.loader import shipped_worlds

    raw = yaml.safe_load(shipped_worlds()["demo"].read_text(encoding="utf-8"))
    base = raw["uavs"][0]
    uavs = []
    for k in range(n):
        uav = copy.deepcopy(base)
        a = 2.0 * math.pi * k / n
        z = ALTITUDE_M + ALTITUDE_STEP_M * (k % ALTITUDE_LAYERS)
        uav["id"] = f"uav{k + 1}"
        uav["initial"] = {"position": [RING_CENTRE_M[0] + RING_RADIUS_M * math.cos(a),
                                       RING_CENTRE_M[1] + RING_RADIUS_M * math.sin(a), z],
                          "yaw_deg": math.degrees(a) + 90.0}
        uav["autonomy"].pop("fusion", None)  # the team shares its states only
        uav["autonomy"]["guidance"]["altitude"] = z
        uavs.append(uav)
    raw.update(name=f"demo_team_{n}", uavs=uavs,
               ground_vehicles=[g for g in raw["ground_vehicles"] if g.get("role") == "target"])
    raw["sim"]["duration_s"] = duration_s
    return raw


def run_team(n: int, duration_s: float = DURATION_S) -> dict[str, float]:
    """One run of :func:`team_world`: its simulated time, the CPU and wall time of its loop (from the end of tick 1,
    after setup, to the end of the run directory) and the wall time of its agents' phase (``autonomy``)."""
    from simulator.bench.scaling import loop_rtf

    r = loop_rtf(team_world(n, duration_s))
    return {"sim_s": r["sim_s"], "cpu_s": r["cpu_s"], "wall_s": r["wall_s"], "autonomy_s": r["autonomy"] * r["sim_s"]}


def agent_steps(n: int, duration_s: float = DURATION_S) -> int:
    """Agent steps of a run of :func:`team_world` (``n`` UAVs at the demo's autonomy rate)."""
    from worlds.loader import shipped_worlds

    rate = yaml.safe_load(shipped_worlds()["demo"].read_text(encoding="utf-8"))["uavs"][0]["autonomy"]["rate_hz"]
    return n * round(duration_s * rate)


@benchmark("team_scaling", produces=("team_cpu_rtf_50uav", "team_rtf_50uav",
                                     *(f"team_autonomy_us_per_uav_step_{n}uav" for n in TEAM_SIZES),
                                     "team_autonomy_growth_50v2"))
def bench_team_scaling() -> list[BenchRecord]:
    """The demo town with 2, 10 and 50 UAVs sharing their states (module docstring), 30 s each, the sizes run in turn
    ``REPEATS`` times so all see the same load; medians.

    ``team_cpu_rtf_50uav``: simulated time over the CPU time of the 50-UAV run's loop (setup excluded; target >= 2);
    ``team_rtf_50uav`` its wall-time twin. ``team_autonomy_us_per_uav_step_<n>uav``: the wall time of the agents'
    phase (inbox, estimator, guidance, their records) per agent step; ``team_autonomy_growth_50v2`` the 50-UAV
    figure over the 2-UAV one: 1 when a UAV's cost does not grow with its team (target <= 1.25).
    """
    runs: dict[int, list[dict[str, float]]] = {n: [] for n in TEAM_SIZES}
    for _ in range(REPEATS):
        for n in TEAM_SIZES:
            runs[n].append(run_team(n))
    med = statistics.median
    per_step = {n: med(r["autonomy_s"] for r in runs[n]) / agent_steps(n) * 1e6 for n in TEAM_SIZES}
    big = runs[TEAM_SIZES[-1]]
    return [BenchRecord(name="team_cpu_rtf_50uav", value=med(r["sim_s"] / r["cpu_s"] for r in big), unit="x",
                        target=2.0, better="higher"),
            BenchRecord(name="team_rtf_50uav", value=med(r["sim_s"] / r["wall_s"] for r in big), unit="x",
                        better="higher"),
            *(BenchRecord(name=f"team_autonomy_us_per_uav_step_{n}uav", value=per_step[n], unit="us",
                          better="lower") for n in TEAM_SIZES),
            BenchRecord(name="team_autonomy_growth_50v2", value=per_step[TEAM_SIZES[-1]] / per_step[TEAM_SIZES[0]],
                        unit="x", target=1.25, better="lower")]
