"""Road surface footprints and render mesh."""

from __future__ import annotations

import numpy as np
import pytest

from worlds.roads.mesh import road_edges, road_polygons, road_surface_mesh
from worlds.roads.network import RoadNetwork


@pytest.fixture(scope="module")
def net() -> RoadNetwork:
    ang = np.linspace(0.0, np.pi / 2, 10)[1:-1]
    return RoadNetwork.from_spec({
        "nodes": {"A": [0, 0], "B": [100, 0], "C": [150, 50]},
        "streets": [
            {"id": "ab", "nodes": ["A", "B"], "lanes": 2, "lane_width": 3.5},
            {"id": "bc", "nodes": ["B", "C"], "via": np.c_[100 + 50 * np.sin(ang), 50 - 50 * np.cos(ang)].tolist(),
             "lane_width": 3.0, "two_way": False},
        ]})


def test_two_way_strips_tile_the_street(net):
    polys = road_polygons(net)
    # A->B has its 2 lanes on the right (y in [-7, 0]), B->A on the other side (y in [0, 7]).
    assert polys["ab.f"].bounds == pytest.approx((0.0, -7.0, 100.0, 0.0))
    assert polys["ab.r"].bounds == pytest.approx((0.0, 0.0, 100.0, 7.0))
    assert polys["ab.f"].area == pytest.approx(700.0) and polys["ab.r"].area == pytest.approx(700.0)
    assert polys["ab.f"].intersection(polys["ab.r"]).area == pytest.approx(0.0, abs=1e-9)


def test_curved_one_way_strip_area(net):
    """A quarter circle of radius 50 m, 3 m wide and centred: area = width x arc length (Pappus)."""
    road = net.roads["bc.f"]
    assert road.length == pytest.approx(25 * np.pi, rel=1e-4)
    poly = road_polygons(net)["bc.f"]
    assert poly.area == pytest.approx(3.0 * road.length, rel=2e-3)
    right, left = road_edges(road)
    centre = np.array([100.0, 50.0])
    np.testing.assert_allclose(np.hypot(*(right - centre).T), 51.5, atol=0.01)  # turning left: right edge outside
    np.testing.assert_allclose(np.hypot(*(left - centre).T), 48.5, atol=0.01)


def test_surface_mesh_is_flat_upward_and_covers_the_strips(net):
    mesh = road_surface_mesh(net, z=0.05)
    np.testing.assert_allclose(mesh.vertices[:, 2], 0.05)
    assert np.all(mesh.face_normals[:, 2] > 0.999)
    polys = road_polygons(net)
    assert mesh.area == pytest.approx(sum(p.area for p in polys.values()), rel=1e-6)


def test_empty_network_gives_empty_mesh():
    mesh = road_surface_mesh(RoadNetwork([], {}))
    assert len(mesh.faces) == 0
