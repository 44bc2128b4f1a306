"""A UAV starting inside a building of a generated town is refused when the world is built, naming the UAV's key path;
the shipped worlds build."""

from __future__ import annotations

import numpy as np
import pytest

from worlds.build import build_geometry
from worlds.errors import WorldError
from worlds.loader import load_world, shipped_worlds


def _rng() -> np.random.Generator:
    return np.random.default_rng(7)


def test_a_uav_inside_a_town_building_is_refused_at_build():
    loaded = load_world("road_standoff")
    town = build_geometry(loaded.world, loaded.path, _rng())
    b = max(town.buildings, key=lambda b: b.height)
    x, y = (float(c) for c in b.footprint.mean(axis=0))  # a cuboid's centroid is inside it
    inside = load_world("road_standoff", overrides=[f"uavs[1].initial.position=[{x}, {y}, {b.height / 2}]"])
    with pytest.raises(WorldError, match=r"uavs\[1\]\.initial\.position.*building") as err:
        build_geometry(inside.world, inside.path, _rng())
    assert "uavs[0]" not in str(err.value)
    above = load_world("road_standoff", overrides=[f"uavs[1].initial.position=[{x}, {y}, {b.height + 5}]"])
    build_geometry(above.world, above.path, _rng())  # above the roof: fine


@pytest.mark.parametrize("name", [n for n in sorted(shipped_worlds()) if "helsinki" not in n])
def test_shipped_worlds_start_outside_their_buildings(name):
    loaded = load_world(name)
    build_geometry(loaded.world, loaded.path, _rng())
