"""The world mistakes that once passed the loader and crashed the run after PyBullet had started: each is now refused
by ``load_world`` with the file, the line, the key path, the bad value and what was expected, and by ``skytrack run``
with exit code 2 before any run directory (or scene) exists."""

from pathlib import Path

import pytest

from simulator.cli import main
from worlds.errors import WorldError
from worlds.loader import load_world, shipped_worlds

DEMO = shipped_worlds()["demo"]

PHYSICS_100 = ("sim.physics_hz=100", "uavs[0].outer_loop_hz=50", "uavs[1].outer_loop_hz=50")
"""Every visible rate of demo divides 100 Hz after these; only the car driver's own 40 Hz does not."""

MISTAKES = [
    pytest.param(("ground_vehicles[0].type=truck",), "ground_vehicles[0].type", "truck",
                 "one of the car types of vehicles/cars (sedan, van)", id="car-type"),
    pytest.param(("ground_vehicles[0].driver={bogus: 1}",), "ground_vehicles[0].driver.bogus", 1,
                 "no such key here", id="driver-key"),
    pytest.param(("uavs[0].initial.position=[.nan, 0, 60]",), "uavs[0].initial.position[0]", "nan",
                 "a finite number", id="nan-position"),
    pytest.param(("sim.flush_every_s=0.001",), "sim.flush_every_s", 0.001,
                 "at least one physics tick, 0.00416667 s at sim.physics_hz=240", id="flush-period"),
    pytest.param(("environment.wind.mean_W=[1e9, 0, 0]",), "environment.wind.mean_W", (1e9, 0, 0),
                 "a wind of at most 25 m/s", id="wind"),
    pytest.param(PHYSICS_100, "ground_vehicles[0].driver.rate_hz", 40,
                 "a rate in Hz that divides sim.physics_hz=100", id="driver-rate"),
]


def _same(value, expected) -> bool:
    if expected == "nan":
        return value != value
    if isinstance(expected, tuple):  # YAML 1.1 reads 1e9 (no dot) as a string, which pydantic then parses
        return [float(v) for v in value] == list(expected)
    return value == expected


@pytest.mark.parametrize("overrides, path, value, expected", MISTAKES)
def test_load_world_refuses_it_naming_path_value_and_expectation(overrides, path, value, expected):
    with pytest.raises(WorldError) as info:
        load_world("demo", list(overrides))
    issues = [i for i in info.value.issues if i.path == path]
    assert len(info.value.issues) == 1 and issues, str(info.value)
    issue = issues[0]
    assert _same(issue.value, value) and expected in issue.expected
    where = f"{DEMO}:{issue.line}" if "environment" not in path else str(DEMO)  # demo.yaml has no environment
    assert f"{where}: {path} = " in str(info.value)


@pytest.mark.parametrize("overrides, path, value, expected", MISTAKES)
def test_skytrack_run_exits_2_before_pybullet(tmp_path: Path, capsys, overrides, path, value, expected):
    out = tmp_path / "run"
    argv = ["run", "demo", "--duration", "0.1", "--quiet", "--no-plots", "--out", str(out)]
    for ov in overrides:
        argv += ["--set", ov]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{path} = " in err and expected in err and str(DEMO) in err
    assert not out.exists()  # no run directory, so no scene_built event: PyBullet never started


def test_the_driver_rate_mistake_says_where_the_hidden_rate_comes_from():
    with pytest.raises(WorldError) as info:
        load_world("demo", list(PHYSICS_100))
    assert "the driver's default is 40 Hz" in info.value.issues[0].expected
    loaded = load_world("demo", [*PHYSICS_100, "ground_vehicles[0].driver.rate_hz=20"])
    assert loaded.world.ground_vehicles[0].driver.rate_hz == 20


@pytest.mark.parametrize("overrides, path, expected", [
    (("uavs[1].outer_loop_hz=60",), "uavs[1].outer_loop_hz", "the outer_loop_hz of uavs[0]"),
    (("comms.latency_s=0.001",), "comms.latency_s", "a whole number of physics ticks"),
    (("uavs[0].airframe=blimp",), "uavs[0].airframe", "crazyflie, survey_quad"),
    (("uavs[0].initial.position=[0, 0, -1]",), "uavs[0].initial.position", "0 < z <= 5000 m"),
    (("uavs[0].initial.position=[1e9, 0, 60]",), "uavs[0].initial.position", "within 50 km of the origin"),
    (("environment.gravity=1e9",), "environment.gravity", "less than or equal to 20"),
    (("environment.wind.turbulence.sigma=50",), "environment.wind.turbulence.sigma", "less than or equal to 5"),
    (("buildings[0].size=[70, 50, 1e9]",), "buildings[0].size[2]", "less than or equal to 1000"),
    (("terrain.size=[.inf, 800]",), "terrain.size[0]", "a finite number"),
    (("sim.physics_hz=100000",), "sim.physics_hz", "less than or equal to 2400"),
    (("ground_vehicles[0].driver.path_horizon=1e9",), "ground_vehicles[0].driver.path_horizon",
     "less than or equal to 2000"),
])
def test_other_hidden_rules_and_physical_ranges_are_refused(overrides, path, expected):
    with pytest.raises(WorldError) as info:
        load_world("demo", list(overrides))
    assert any(i.path == path and expected in i.expected for i in info.value.issues), str(info.value)
