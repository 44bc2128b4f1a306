"""The batch projections of a road network (worlds/roads/projection.py) against the per-point ones they stand for:
:meth:`Road.project` and :meth:`RoadNetwork.nearest`, on a procedural town's curved and straight roads, for points on
the roads, beside them, far off and beyond their ends."""

from __future__ import annotations

import numpy as np
import pytest

from worlds.town import TownConfig, generate_town

TOL = 1e-9  # m: the compiled step's hypot is the C library's, Road.project's Python's (last-bit differences)


@pytest.fixture(scope="module")
def net():
    return generate_town(TownConfig(extent=(400.0, 400.0), block_size=100.0, curved_fraction=0.5),
                         np.random.default_rng(3)).network


def _points(net, rng, m):
    """Points near random roads (up to 12 m off, some beyond the ends) and anywhere in the town."""
    ids = list(net.roads)
    rid = [ids[k] for k in rng.integers(len(ids), size=m)]
    s = np.array([rng.uniform(-15.0, net.roads[r].length + 15.0) for r in rid])
    lat = rng.uniform(-12.0, 12.0, size=m)
    near = np.array([net.roads[r].point(si, li) for r, si, li in zip(rid, s, lat, strict=True)])
    return rid, near, rng.uniform(-260.0, 260.0, size=(m, 2))


def test_project_on_is_road_project(net):
    rng = np.random.default_rng(11)
    rid, near, anywhere = _points(net, rng, 600)
    curved = sum(net.roads[r]._n > 1 for r in rid)
    assert curved > 100  # the spline roads' tables are exercised, not only straight ones
    for pts in (near, anywhere):
        s, lat = net.project_on(rid, pts)
        ref = np.array([net.roads[r].project(p) for r, p in zip(rid, pts, strict=True)])
        np.testing.assert_allclose(s, ref[:, 0], rtol=0, atol=TOL)
        np.testing.assert_allclose(lat, ref[:, 1], rtol=0, atol=TOL)
    assert (s == 0).any() and any(si == net.roads[r].length for r, si in zip(rid, s, strict=True))  # ends clipped


def test_nearest_many_is_nearest(net):
    rng = np.random.default_rng(12)
    _, near, anywhere = _points(net, rng, 400)
    nodes = np.array(list(net.nodes.values()))  # junctions: many candidate roads, twins tied on the centre-line
    pts = np.vstack([near, anywhere, nodes + rng.normal(0, 3.0, nodes.shape)])
    ids, s, lat = net.nearest_many(pts)
    ref = [net.nearest(p) for p in pts]
    assert ids == [r[0] for r in ref]
    np.testing.assert_allclose(s, [r[1] for r in ref], rtol=0, atol=TOL)
    np.testing.assert_allclose(lat, [r[2] for r in ref], rtol=0, atol=TOL)
    assert net.nearest_many(np.zeros((0, 2)))[0] == []
