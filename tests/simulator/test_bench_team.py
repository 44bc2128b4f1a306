"""The team-size benchmark's world and its registration with ``skytrack bench``: its N UAVs are the demo's radar /
EKF / vector-field UAV sharing only states, in the demo town with its target car, and a short run completes."""

from __future__ import annotations

import tempfile
from pathlib import Path

import yaml

from simulator.bench.bench_team import agent_steps, run_team, team_world
from simulator.bench.runner import discover
from worlds.loader import load_world


def test_team_world_holds_n_copies_of_the_demo_uav_sharing_states_around_the_target_car():
    raw = team_world(50, duration_s=12.0)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "team.yaml"
        path.write_text(yaml.safe_dump(raw))
        world = load_world(path).world
    assert world.sim.duration_s == 12.0 and world.name == "demo_team_50"
    assert [u.id for u in world.uavs] == [f"uav{k}" for k in range(1, 51)]
    assert [g.id for g in world.ground_vehicles] == ["car1"]  # the target; the traffic cars left out
    for k, uav in enumerate(world.uavs):
        assert [s.type for s in uav.sensors] == ["radar"] and uav.autonomy.estimator.type == "ekf"
        assert uav.autonomy.guidance.type == "vector_field" and uav.autonomy.fusion.method == "none"
        assert uav.autonomy.guidance.altitude == uav.initial.position[2] == 60.0 + 2.0 * (k % 10)
    starts = [u.initial.position[:2] for u in world.uavs]
    assert len({(round(x), round(y)) for x, y in starts}) == 50  # no two UAVs start at one place
    assert agent_steps(50, 12.0) == 50 * 120


def test_a_short_team_run_completes_and_reports_its_times():
    r = run_team(3, duration_s=0.5)
    assert r["sim_s"] == 0.5 and r["cpu_s"] > 0 and r["wall_s"] > 0 and r["autonomy_s"] > 0


def test_team_benchmark_is_registered_with_its_records():
    bench = discover()["team_scaling"]
    assert bench.produces == ("team_cpu_rtf_50uav", "team_rtf_50uav", "team_autonomy_us_per_uav_step_2uav",
                              "team_autonomy_us_per_uav_step_10uav", "team_autonomy_us_per_uav_step_50uav",
                              "team_autonomy_growth_50v2")
