"""Procedural towns: determinism, no overlaps, connectivity, configuration checks."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from worlds.roads.mesh import road_polygons, road_surface_mesh
from worlds.town import Town, TownConfig, generate_town

CFG = TownConfig(extent=(500.0, 400.0), block_size=100.0, curved_fraction=0.5, setback=3.0, building_gap=4.0)


@pytest.fixture(scope="module")
def town() -> Town:
    return generate_town(CFG, np.random.default_rng(2024))


def _signature(t: Town) -> tuple:
    return (tuple((rid, r.vertices.tobytes()) for rid, r in t.network.roads.items()),
            tuple((b.footprint.tobytes(), b.height) for b in t.buildings))


def test_deterministic_per_seed(town):
    again = generate_town(CFG, np.random.default_rng(2024))
    other = generate_town(CFG, np.random.default_rng(2025))
    assert _signature(again) == _signature(town)
    assert _signature(other) != _signature(town)


def test_grid_layout(town):
    net = town.network
    assert len(net.nodes) == 6 * 5  # 500 x 400 m in 100 m blocks
    assert len(net.roads) == 2 * (5 * 5 + 6 * 4)  # every street two-way
    assert net.is_connected()
    np.testing.assert_allclose(net.nodes["n0_0"], [-250.0, -200.0])
    # arterials (every 3rd line from the first) have 2 lanes per direction, the rest 1
    assert net.roads["h0_0.f"].lanes == 2 and net.roads["h0_1.f"].lanes == 1 and net.roads["v3_1.r"].lanes == 2


def test_curved_arterials():
    lines = 2 + 2  # rows 0, 3 and columns 0, 3 of a 6 x 5 grid
    for frac, n_curved in ((0.0, 0), (0.5, 2), (1.0, 4)):
        t = generate_town(TownConfig(extent=(500.0, 400.0), curved_fraction=frac), np.random.default_rng(1))
        curved_h = {rid.split("_")[1].split(".")[0] for rid, r in t.network.roads.items()
                    if rid.startswith("h") and r.vertices.shape[0] > 2}
        curved_v = {rid.split("_")[0] for rid, r in t.network.roads.items()
                    if rid.startswith("v") and r.vertices.shape[0] > 2}
        assert len(curved_h) + len(curved_v) == n_curved <= lines
    # a meander bulges by curve_amplitude * block_size at mid-block and keeps the junctions on the grid
    t = generate_town(TownConfig(extent=(300.0, 300.0), curved_fraction=1.0, curve_amplitude=0.1),
                      np.random.default_rng(0))
    road = t.network.roads["h0_0.f"]
    s, lat = road.project(np.array([-100.0, -150.0]))
    assert abs(lat) == pytest.approx(10.0, abs=0.05)
    assert road.vertices[0].tolist() == [-150.0, -150.0]


def test_road_surface_mesh_faces_up(town):
    mesh = road_surface_mesh(town.network)
    assert np.all(mesh.face_normals[:, 2] > 0.999)
    polys = road_polygons(town.network)
    assert mesh.area == pytest.approx(sum(p.area for p in polys.values()), rel=1e-6)


def test_buildings_clear_roads_and_each_other(town):
    assert len(town.buildings) > 50
    roads = shapely.union_all(list(road_polygons(town.network).values()))
    polys = [Polygon(b.footprint) for b in town.buildings]
    dist_to_road = shapely.distance(roads, polys)
    assert dist_to_road.min() >= CFG.setback - 1e-6
    tree = shapely.STRtree(polys)
    i, j = tree.query(polys, predicate="dwithin", distance=CFG.building_gap - 1e-6)
    assert np.all(i == j)  # only each building with itself


def test_building_sizes_in_range(town):
    lo, hi = CFG.footprint_range
    for b in town.buildings:
        assert b.is_cuboid
        _, size, yaw = b.cuboid_params
        assert lo - 1e-9 <= size[0] <= hi + 1e-9 and lo - 1e-9 <= size[1] <= hi + 1e-9 and yaw == 0.0
        assert CFG.height_range[0] <= b.height <= CFG.height_range[1]
    heights = np.array([b.height for b in town.buildings])
    # uniform heights: the mean lies within 4 standard errors of the interval's midpoint
    mid, sd = np.mean(CFG.height_range), np.ptp(CFG.height_range) / np.sqrt(12)
    assert abs(heights.mean() - mid) < 4 * sd / np.sqrt(len(heights))


def test_max_buildings_subset():
    cfg = TownConfig(extent=(1000.0, 1000.0), max_buildings=500)
    t = generate_town(cfg, np.random.default_rng(9))
    assert len(t.buildings) == 500
    assert len({b.name for b in t.buildings}) == 500
    x0, y0, x1, y1 = t.bounds()
    assert x0 >= -510 and x1 <= 510 and y0 >= -510 and y1 <= 510


@pytest.mark.parametrize("kw,match", [
    (dict(block_size=0.0), "block_size"),
    (dict(extent=(50.0, 500.0)), "extent"),
    (dict(lanes=0), "lanes"),
    (dict(curved_fraction=1.5), "curved_fraction"),
    (dict(curve_amplitude=0.4), "curve_amplitude"),
    (dict(footprint_range=(20.0, 10.0)), "footprint_range"),
    (dict(height_range=(0.0, 10.0)), "height_range"),
    (dict(setback=-1.0), "setback"),
    (dict(max_buildings=-3), "max_buildings"),
])
def test_config_validation(kw, match):
    with pytest.raises(ValueError, match=f"TownConfig.{match}"):
        TownConfig(**kw)


def test_config_from_mapping():
    cfg = TownConfig.from_mapping({"extent": [300, 300], "height_range": [5, 9]})
    assert cfg.extent == (300.0, 300.0) and cfg.height_range == (5.0, 9.0)
    with pytest.raises(ValueError, match="unknown field.*'blocks'"):
        TownConfig.from_mapping({"blocks": 3})
