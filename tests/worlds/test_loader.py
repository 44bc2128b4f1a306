"""World files: every bad input names the file, the key path, the bad value and what was expected."""

from pathlib import Path

import pytest

from worlds.errors import WorldError
from worlds.loader import load_world, parse_key_path, parse_override, shipped_worlds
from world_files import write

GOOD = """\
name: tiny
sim: {physics_hz: 240, duration_s: 5, seed: 1}
uavs:
  - id: u1
    initial: {position: [0, 0, 30]}
    sensors:
      - {type: radar, rate_hz: 2, sigma_range: 20, sigma_azimuth_deg: 1, sigma_elevation_deg: 1}
"""


def error_of(path: Path, overrides=()) -> WorldError:
    with pytest.raises(WorldError) as info:
        load_world(path, list(overrides))
    return info.value


def test_good_world_loads(tmp_path):
    loaded = load_world(write(tmp_path, GOOD))
    assert loaded.world.name == "tiny"
    assert loaded.world.uavs[0].sensors[0].rate_hz == 2


def test_unknown_key_is_an_error_with_path_and_line(tmp_path):
    path = write(tmp_path, GOOD.replace("    initial:", "    intial_typo: 3\n    initial:"))
    err = error_of(path)
    msg = str(err)
    assert str(path) in msg
    assert "uavs[0].intial_typo" in msg and "no such key" in msg
    assert f"{path}:5:" in msg  # line of the offending key


def test_wrong_type(tmp_path):
    err = error_of(write(tmp_path, GOOD.replace("rate_hz: 2", "rate_hz: fast")))
    issue = err.issues[0]
    assert issue.path == "uavs[0].sensors[0].rate_hz"
    assert issue.value == "fast"
    assert "number" in issue.expected


def test_negative_duration(tmp_path):
    err = error_of(write(tmp_path, GOOD.replace("duration_s: 5", "duration_s: -5")))
    assert err.issues[0].path == "sim.duration_s" and err.issues[0].value == -5
    assert "greater than 0" in err.issues[0].expected


def test_rate_that_does_not_divide_physics_rate(tmp_path):
    err = error_of(write(tmp_path, GOOD.replace("rate_hz: 2", "rate_hz: 7")))
    issue = err.issues[0]
    assert issue.path == "uavs[0].sensors[0].rate_hz" and issue.value == 7
    assert "divides sim.physics_hz=240" in issue.expected
    assert issue.line == 7


def test_missing_file(tmp_path):
    err = error_of(tmp_path / "nope.yaml")
    assert "nope.yaml" in str(err) and "existing world file" in str(err)


def test_bad_yaml(tmp_path):
    err = error_of(write(tmp_path, "sim: {physics_hz: 240\nuavs: [\n"))
    assert err.issues[0].path == "<yaml>" and "valid YAML" in str(err)
    assert err.issues[0].line is not None


def test_missing_required_key(tmp_path):
    err = error_of(write(tmp_path, GOOD.replace("    initial: {position: [0, 0, 30]}\n", "")))
    assert err.issues[0].path == "uavs[0].initial" and "required" in err.issues[0].expected


def test_override_sets_value_and_is_validated(tmp_path):
    path = write(tmp_path, GOOD)
    loaded = load_world(path, ["sim.duration_s=30", "uavs[0].sensors[0].rate_hz=4",
                               "uavs.0.initial.position=[1, 2, 3]"])
    assert loaded.world.sim.duration_s == 30
    assert loaded.world.uavs[0].sensors[0].rate_hz == 4
    assert loaded.world.uavs[0].initial.position == (1, 2, 3)
    err = error_of(path, ["uavs[0].sensors[0].rate_hz=11"])
    assert err.issues[0].path == "uavs[0].sensors[0].rate_hz" and err.issues[0].value == 11
    err = error_of(path, ["sim.bogus=1"])
    assert err.issues[0].path == "sim.bogus"
    err = error_of(path, ["uavs[5].id=x"])
    assert "--set" in err.issues[0].path


def test_duplicate_ids_and_dangling_target(tmp_path):
    text = GOOD + "  - id: u1\n    initial: {position: [5, 0, 30]}\ntargets: [car9]\n"
    err = error_of(write(tmp_path, text))
    paths = {i.path for i in err.issues}
    assert "uavs[0].id" in paths and "targets[0].id" in paths


def test_key_path_parsing():
    assert parse_key_path("uavs[1].sensors.0.rate_hz") == ["uavs", 1, "sensors", 0, "rate_hz"]
    assert parse_override("a.b=[1, 2]") == (["a", "b"], [1, 2])
    with pytest.raises(ValueError):
        parse_key_path("a..b")
    with pytest.raises(ValueError):
        parse_override("novalue")


@pytest.mark.parametrize("name", sorted(shipped_worlds()))
def test_every_shipped_world_validates(name):
    loaded = load_world(name)
    assert loaded.world.sim.duration_s > 0


def test_a_key_named_like_a_sensor_type_keeps_its_path(tmp_path):
    """``render.camera`` is a key, not the sensor-union tag ``camera`` that pydantic puts after ``sensors[i]``."""
    from worlds.errors import WorldError
    from worlds.loader import load_world

    path = tmp_path / "w.yaml"
    path.write_text("render:\n  camera: fisheye\nuavs:\n  - id: a\n    initial: {position: [0, 0, 10]}\n"
                    "    sensors:\n      - {type: camera, rate_hz: -5}\n")
    with pytest.raises(WorldError) as info:
        load_world(path)
    text = str(info.value)
    assert "render.camera = 'fisheye'" in text
    assert "uavs[0].sensors[0].rate_hz = -5" in text


HCMCI = GOOD + """\
    autonomy:
      estimator: {type: scif, model: singer}
      fusion: {method: hcmci, rounds: 4, b: 2}
  - id: u2
    initial: {position: [10, 0, 30]}
    autonomy:
      estimator: {model: singer, type: scif}
      fusion: {method: hcmci, rounds: 4, b: 2}
comms:
  links: [[u1, u2]]
"""


def test_hcmci_fusion_loads_with_its_rounds_gain_and_links(tmp_path):
    world = load_world(write(tmp_path, HCMCI)).world
    f = world.uavs[0].autonomy.fusion
    assert (f.method, f.rounds, f.b) == ("hcmci", 4, 2)
    assert world.comms.links == [("u1", "u2")]
    defaults = load_world(write(tmp_path, HCMCI.replace(", rounds: 4, b: 2", ""))).world.uavs[1].autonomy.fusion
    assert (defaults.rounds, defaults.b) == (3, "safe")


@pytest.mark.parametrize("old, new, path, value, expected", [
    ("{model: singer, type: scif}", "{model: singer, type: ekf}", "uavs[1].autonomy.estimator.type", "ekf", "scif"),
    ("{model: singer, type: scif}", "{model: cv, type: scif}", "uavs[1].autonomy.estimator.model", "cv",
     "'singer', the estimator model of uavs[0]"),
    ("{model: singer, type: scif}", "{model: singer, type: scif, params: {target_height: 1.5}}",
     "uavs[1].autonomy.estimator.params.target_height", 1.5, "0.0, the target height of uavs[0]"),
    ("hcmci, rounds: 4, b: 2}\n  - id", "hcmci, rounds: 0, b: 2}\n  - id", "uavs[0].autonomy.fusion.rounds", 0,
     "greater than or equal to 1"),
    ("hcmci, rounds: 4, b: 2}\n  - id", "hcmci, rounds: 4, b: lots}\n  - id", "uavs[0].autonomy.fusion.b", "lots",
     "'safe' or a finite number > 0"),
    ("hcmci, rounds: 4, b: 2}\ncomms", "hcmci, rounds: 5, b: 2}\ncomms", "uavs[1].autonomy.fusion",
     {"rounds": 5, "b": 2}, "the hcmci team runs one consensus"),
    ("hcmci, rounds: 4, b: 2}\ncomms", "convex, rounds: 4}\ncomms", "uavs[1].autonomy.fusion",
     {"method": "convex", "rounds": 4}, "only with method hcmci"),
    ("[[u1, u2]]", "[[u1, u7]]", "comms.links[0][1]", "u7", "a UAV id"),
])
def test_bad_hcmci_settings_are_named(tmp_path, old, new, path, value, expected):
    assert old in HCMCI
    path_file = write(tmp_path, HCMCI.replace(old, new))
    err = error_of(path_file)
    issue = err.issues[0]
    assert (issue.path, issue.value) == (path, value)
    assert expected in issue.expected and str(path_file) in str(err)
