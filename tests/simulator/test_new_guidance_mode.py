"""A new guidance mode end to end, from one test-only module (``user_modules/circle_guidance.py``: settings, builder,
law and one registry line): the world file names it, the loader checks its settings, the run flies it."""

import numpy as np
import pytest

import tests.simulator.user_modules.circle_guidance  # noqa: F401  (registers guidance type 'circle')
from simulator.api import run
from worlds.errors import WorldError
from worlds.loader import load_world

CIRCLE = ["uavs[0].autonomy.guidance.type=circle", "uavs[0].autonomy.guidance.speed=6",
          "uavs[0].autonomy.guidance.altitude=45", "uavs[0].autonomy.guidance.params={centre: [-60, -60], radius: 30}"]


def test_the_new_type_loads_with_its_typed_settings():
    g = load_world("demo", CIRCLE).world.uavs[0].autonomy.guidance
    assert g.type == "circle"
    assert (g.settings.centre, g.settings.radius, g.settings.direction) == ((-60.0, -60.0), 30.0, 1)


@pytest.mark.parametrize("override, path, value, expected", [
    ("uavs[0].autonomy.guidance.params.radius=-5", "uavs[0].autonomy.guidance.params.radius", -5, "greater than 0"),
    ("uavs[0].autonomy.guidance.params.direction=2", "uavs[0].autonomy.guidance.params.direction", 2, "1 or -1"),
    ("uavs[0].autonomy.guidance.params.bogus=1", "uavs[0].autonomy.guidance.params.bogus", 1, "no such key"),
])
def test_bad_settings_of_the_new_type_are_refused_at_load(override, path, value, expected):
    with pytest.raises(WorldError) as info:
        load_world("demo", [*CIRCLE, override])
    issue = info.value.issues[0]
    assert (issue.path, issue.value) == (path, value) and expected in issue.expected


def test_an_unknown_type_lists_the_known_ones_including_the_new():
    with pytest.raises(WorldError) as info:
        load_world("demo", ["uavs[0].autonomy.guidance.type=circel"])
    issue = info.value.issues[0]
    assert issue.path == "uavs[0].autonomy.guidance.type" and "'circle'" in issue.expected
    assert "'nmpc'" in issue.expected


def test_the_new_type_flies(tmp_path):
    result = run("demo", duration=6.0, seed=2, out_dir=tmp_path, overrides=CIRCLE)
    assert result.status == "completed"
    ut = result.stream("uav_truth", uav=0)
    assert abs(ut["z"][-1] - 45.0) < 5.0  # climbing/descending to the circle's altitude
    assert np.max(np.hypot(ut["x"] + 60, ut["y"] + 60)) < 45.0  # and near the circle
