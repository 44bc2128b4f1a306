"""The world mistakes that once passed the loader and crashed the run after PyBullet had started: each is now refused
by ``load_world`` with the file, the line, the key path, the bad value and what was expected, and by ``skytrack run``
with exit code 2 before any run directory (or scene) exists."""

from pathlib import Path

import pytest

from simulator.cli import main
from worlds.errors import WorldError
from worlds.loader import load_world, shipped_worlds

DEMO = shipped_worlds()["demo"]

PHYSICS_100 = ("sim.physics_hz=100", "uavs[0].outer_loop_hz=50", "uavs[1].outer_loop_hz=50",
               *(f"ground_vehicles[{k}].driver.rate_hz=20" for k in (1, 2, 3)))
"""Every visible rate of demo divides 100 Hz after these (the traffic cars' drivers at 20 Hz); only the target car's
driver's own 40 Hz does not."""

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
    (("uavs[0].initial.position=[1.0e9, 0, 60]",), "uavs[0].initial.position[0]", "less than or equal to 50000"),
    (("roads.nodes.a=[1.0e9, 0]",), "roads.nodes.a[0]", "less than or equal to 50000"),
    (("environment.gravity=1e9",), "environment.gravity", "less than or equal to 20"),
    (("environment.wind.turbulence.sigma=50",), "environment.wind.turbulence.sigma", "less than or equal to 5"),
    (("buildings[0].size=[70, 50, 1e9]",), "buildings[0].size[2]", "less than or equal to 1000"),
    (("terrain.size=[.inf, 800]",), "terrain.size[0]", "a finite number"),
    (("sim.physics_hz=100000",), "sim.physics_hz", "less than or equal to 2400"),
    (("ground_vehicles[0].driver.path_horizon=1e9",), "ground_vehicles[0].driver.path_horizon",
     "less than or equal to 2000"),
    (("roads.nodes.b=[0, 0]",), "roads.streets", "a usable road network (street 'south'"),
    (("ground_vehicles[0].route.random_walk_from=nowhere.f",), "ground_vehicles[0].route.random_walk_from",
     "a road id of the network (e.g. south.f"),
    (("buildings[0].size=[1e-300, 50, 25]",), "buildings[0].size[0]", "greater than or equal to 0.5"),
    (("uavs[0].sensors[0].rate_hz=1e-300",), "uavs[0].sensors[0].rate_hz", "divides sim.physics_hz=240"),
    (("ground_vehicles[0].route.start_s=1.0e9",), "ground_vehicles[0].route.start_s",
     "a start on the first road: at most its length, 300.0 m of 'south.f'"),
])
def test_other_hidden_rules_and_physical_ranges_are_refused(overrides, path, expected):
    with pytest.raises(WorldError) as info:
        load_world("demo", list(overrides))
    assert any(i.path == path and expected in i.expected for i in info.value.issues), str(info.value)


@pytest.mark.parametrize("override, expected", [
    ("roads.town.block_size=1.0e-300", "at most 100 blocks along each axis"),
    ("roads.town.block_size=.nan", "a valid town (TownConfig.block_size must be > 0 m, got nan)"),
    ("roads.town.bogus=1", "only fields of TownConfig"),
    ("roads.town.footprint_range=[1.0e-300, 1]", "building footprints from 1 m to 2 km"),
    ("roads.town.height_range=[6, 1.0e9]", "building heights of at most 1 km"),
])


def test_town_settings_are_checked_at_load(override, expected):
    with pytest.raises(WorldError) as info:
        load_world("road_standoff", [override])
    issue = info.value.issues[0]
    assert issue.path == "roads.town" and expected in issue.expected, str(info.value)


def test_routes_in_a_town_name_its_roads():
    with pytest.raises(WorldError) as info:
        load_world("road_standoff", ["ground_vehicles[0].route.random_walk_from=h9_9.f"])
    issue = info.value.issues[0]
    assert issue.path == "ground_vehicles[0].route.random_walk_from" and "a road id of the network" in issue.expected


def test_town_road_ids_are_the_generated_ones():
    import numpy as np

    from worlds.town import TownConfig, generate_town, town_road_ids

    for cfg in (TownConfig(), TownConfig(extent=(300.0, 520.0), block_size=100.0, arterial_every=2)):
        for seed in (0, 1):
            assert sorted(generate_town(cfg, np.random.default_rng(seed)).network.roads) == sorted(town_road_ids(cfg))
