"""Projections onto roads (worlds/roads/projection.py, compiled): Road.project against the algorithm written out in
plain Python here (nearest table sample, osculating-circle steps), and the batch projections of a network against the
per-point ones, on a procedural town's curved and straight roads, for points on the roads, beside them, far off and
beyond their ends."""

from __future__ import annotations

import math

import numpy as np
import pytest

from worlds.town import TownConfig, generate_town

TOL = 1e-9  # m: the compiled step's hypot is the C library's, the reference's Python's (last-bit differences)


def _reference(road, p):
    """Road.project in plain Python: the first nearest table sample, then osculating-circle steps (at most 8)."""
    px, py = float(p[0]), float(p[1])
    j = int(np.argmin(((road._xy - (px, py)) ** 2).sum(axis=1)))
    s = j * road._h
    x, y, th, ka = road._interp1(s)
    lat = 0.0
    for _ in range(8):
        a = (px - x) * math.cos(th) + (py - y) * math.sin(th)
        lat = -(px - x) * math.sin(th) + (py - y) * math.cos(th)
        if abs(ka) * (abs(a) + abs(lat)) < 1e-9:
            ds = a
        else:
            ds = math.atan2(ka * a, 1.0 - ka * lat) / ka
            lat = (1.0 - math.hypot(1.0 - ka * lat, ka * a)) / ka
        s_new = min(max(s + ds, 0.0), road.length)
        if s_new != s + ds:
            x, y, th, ka = road._interp1(s_new)
            return s_new, -(px - x) * math.sin(th) + (py - y) * math.cos(th)
        s = s_new
        if abs(ds) < 1e-9:
            return s, lat
        x, y, th, ka = road._interp1(s)
    return s, lat


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


def test_road_project_is_the_reference_and_project_on_is_road_project(net):
    rng = np.random.default_rng(11)
    rid, near, anywhere = _points(net, rng, 600)
    curved = sum(net.roads[r]._n > 1 for r in rid)
    assert curved > 100  # the spline roads' tables are exercised, not only straight ones
    for pts in (near, anywhere):
        one = np.array([net.roads[r].project(p) for r, p in zip(rid, pts, strict=True)])
        ref = np.array([_reference(net.roads[r], p) for r, p in zip(rid, pts, strict=True)])
        np.testing.assert_allclose(one, ref, rtol=0, atol=TOL)
        s, lat = net.project_on(rid, pts)
        np.testing.assert_array_equal(np.c_[s, lat], one)  # the same compiled steps
    assert (s == 0).any() and any(si == net.roads[r].length for r, si in zip(rid, s, strict=True))  # ends clipped


def _nearest_reference(net, p):
    """The nearest road point over every road, by the reference projection: least distance (to the micrometre), then
    the road with the point on its right (twins share a centre-line), then the road id."""
    best = None
    for rid, road in net.roads.items():
        s, lat = _reference(road, p)
        key = (round(float(np.hypot(*(road.point(s) - p))), 6), 0 if lat <= 0 else 1, rid, s, lat)
        if best is None or key[:3] < best[:3]:
            best = key
    return best[2], best[3], best[4]


def test_nearest_is_the_nearest_over_every_road(net):
    rng = np.random.default_rng(12)
    _, near, anywhere = _points(net, rng, 150)
    nodes = np.array(list(net.nodes.values()))  # junctions: many candidate roads, twins tied on the centre-line
    pts = np.vstack([near, anywhere, nodes + rng.normal(0, 3.0, nodes.shape)])
    ids, s, lat = net.nearest_many(pts)
    ref = [_nearest_reference(net, p) for p in pts]
    assert ids == [r[0] for r in ref]
    np.testing.assert_allclose(s, [r[1] for r in ref], rtol=0, atol=TOL)
    np.testing.assert_allclose(lat, [r[2] for r in ref], rtol=0, atol=TOL)
    assert [net.nearest(p) for p in pts[::25]] == [(i, si, li) for i, si, li in zip(ids[::25], s[::25], lat[::25],
                                                                                      strict=True)]
    assert net.nearest_many(np.zeros((0, 2)))[0] == []


def _numpy_interp(road, s):
    """Road table evaluation in vectorised NumPy (the form the compiled kernel replaced): x, y, theta, kappa."""
    s = np.clip(s, 0.0, road.length)
    h = road._h
    j = np.minimum((s / h).astype(np.int64), road._n - 1)
    u = s / h - j
    u2, u3 = u * u, u * u * u
    h00, h10, h01, h11 = 2 * u3 - 3 * u2 + 1, u3 - 2 * u2 + u, 3 * u2 - 2 * u3, u3 - u2
    th0, th1, k0, k1 = road._th[j], road._th[j + 1], road._ka[j], road._ka[j + 1]
    p0, p1 = road._xy[j], road._xy[j + 1]
    c0, s0, c1, s1 = np.cos(th0), np.sin(th0), np.cos(th1), np.sin(th1)
    x = h00 * p0[..., 0] + h10 * h * c0 + h01 * p1[..., 0] + h11 * h * c1
    y = h00 * p0[..., 1] + h10 * h * s0 + h01 * p1[..., 1] + h11 * h * s1
    th = h00 * th0 + h10 * h * k0 + h01 * th1 + h11 * h * k1
    d00, d10, d01, d11 = 6 * u2 - 6 * u, 3 * u2 - 4 * u + 1, 6 * u - 6 * u2, 3 * u2 - 2 * u
    ka = (d00 * th0 + d01 * th1) / h + d10 * k0 + d11 * k1
    return x, y, th, ka


def test_compiled_table_evaluation_is_the_numpy_form(net):
    """Road._interp / Road.sample (compiled) give the vectorised NumPy evaluation's numbers on every road of the
    town, at arc lengths inside, at the ends, on table knots and beyond; other shapes of ``s`` keep their shape;
    a NaN arc length is refused."""
    rng = np.random.default_rng(11)
    for road in net.roads.values():
        s = np.r_[rng.uniform(-5.0, road.length + 5.0, 40), 0.0, road.length, np.arange(road._n + 1) * road._h,
                  -np.inf, np.inf]
        x, y, th, ka = _numpy_interp(road, s)
        got = road._interp(s)
        for a, b in zip(got[:4], (x, y, th, ka), strict=True):
            assert np.array_equal(a, b)
        assert np.array_equal(got[4], np.clip(s, 0.0, road.length))
        xy, head, kap = road.sample(s)
        assert np.array_equal(xy, np.stack([x, y], axis=-1))
        assert np.array_equal(head, np.arctan2(np.sin(th), np.cos(th)))
        assert np.array_equal(kap, ka)
        assert np.array_equal(road.heading(s), head)
    road = next(iter(net.roads.values()))
    grid = rng.uniform(0.0, road.length, (3, 4))
    assert road.point(grid).shape == (3, 4, 2) and road.heading(grid).shape == (3, 4)
    assert np.array_equal(road.curvature(grid), _numpy_interp(road, grid)[3])
    with pytest.raises(ValueError, match="NaN"):
        road.sample(np.array([1.0, np.nan]))
