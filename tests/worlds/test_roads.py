"""Road centre-line geometry against closed-form lines and circles."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import LineString

from worlds.roads.road import Road


def _arc(R: float, a0: float, a1: float, n: int, center=(0.0, 0.0)) -> np.ndarray:
    ang = np.linspace(a0, a1, n)
    return np.c_[center[0] + R * np.cos(ang), center[1] + R * np.sin(ang)]


def _road(vertices, **kw) -> Road:
    return Road(id=kw.pop("id", "r"), vertices=vertices, start_node="a", end_node="b", **kw)


# ---------------------------------------------------------------- straight lines
def test_two_vertex_road_is_exact_line():
    r = _road([[1.0, 2.0], [4.0, 6.0]])  # 3-4-5 triangle
    assert r.length == pytest.approx(5.0, abs=1e-12)
    s = np.array([0.0, 1.0, 2.5, 5.0])
    np.testing.assert_allclose(r.point(s), [[1, 2], [1.6, 2.8], [2.5, 4.0], [4, 6]], atol=1e-12)
    np.testing.assert_allclose(r.tangent(2.0), [0.6, 0.8], atol=1e-12)
    assert r.heading(3.0) == pytest.approx(np.arctan2(4, 3), abs=1e-12)
    np.testing.assert_allclose(r.curvature(s), 0.0, atol=1e-12)
    # left normal is (-0.8, 0.6): a point 2 m to the left of s = 2.5
    s_p, lat = r.project(np.array([2.5, 4.0]) + 2.0 * np.array([-0.8, 0.6]))
    assert (s_p, lat) == (pytest.approx(2.5, abs=1e-9), pytest.approx(2.0, abs=1e-9))
    s_p, lat = r.project(np.array([2.5, 4.0]) - 3.0 * np.array([-0.8, 0.6]))
    assert (s_p, lat) == (pytest.approx(2.5, abs=1e-9), pytest.approx(-3.0, abs=1e-9))


def test_queries_clip_to_the_ends():
    r = _road([[0.0, 0.0], [10.0, 0.0]])
    np.testing.assert_allclose(r.point(-5.0), [0, 0], atol=1e-12)
    np.testing.assert_allclose(r.point(50.0), [10, 0], atol=1e-12)
    assert r.project(np.array([-3.0, 1.0])) == (0.0, pytest.approx(1.0))
    assert r.project(np.array([14.0, -2.0])) == (10.0, pytest.approx(-2.0))


def test_collinear_uneven_vertices_give_an_exact_line():
    t = np.array([0.0, 0.7, 3.0, 3.2, 9.0, 20.0])
    d = np.array([np.cos(0.3), np.sin(0.3)])
    r = _road(np.array([5.0, -1.0]) + t[:, None] * d)
    assert r.length == pytest.approx(20.0, rel=1e-12)
    s = np.linspace(0.0, 20.0, 101)
    np.testing.assert_allclose(r.point(s), np.array([5.0, -1.0]) + s[:, None] * d, atol=1e-9)
    np.testing.assert_allclose(r.curvature(s), 0.0, atol=1e-9)
    np.testing.assert_allclose(r.heading(s), 0.3, atol=1e-9)


# ---------------------------------------------------------------- circles
@pytest.mark.parametrize("direction", [1.0, -1.0], ids=["ccw", "cw"])
@pytest.mark.parametrize("R,n", [(50.0, 19), (200.0, 37), (15.0, 19)])
def test_arc_length_and_curvature_on_circle(R, n, direction):
    """Vertices every <= 10 deg on a half circle: arc length R*pi to 1e-5 relative, curvature 1/R to 0.5 % inside."""
    a0, a1 = 0.0, direction * np.pi
    r = _road(_arc(R, a0, a1, n))
    assert r.length == pytest.approx(R * np.pi, rel=1e-5)
    s = np.linspace(0.15 * r.length, 0.85 * r.length, 200)
    np.testing.assert_allclose(r.curvature(s), direction / R, rtol=5e-3)
    np.testing.assert_allclose(np.hypot(*r.point(s).T), R, atol=1e-5 * R)
    # heading of a circle traversed at angle phi is phi +/- pi/2
    phi = a0 + direction * s / R
    expected = phi + direction * np.pi / 2
    np.testing.assert_allclose(np.angle(np.exp(1j * (r.heading(s) - expected))), 0.0, atol=1e-4)
    # tangent is the derivative of position with respect to arc length
    ds = 1e-4
    fd = (r.point(s + ds) - r.point(s - ds)) / (2 * ds)
    np.testing.assert_allclose(fd, r.tangent(s), atol=1e-5)
    np.testing.assert_allclose(np.hypot(*r.tangent(s).T), 1.0, atol=1e-12)


@pytest.mark.parametrize("direction", [1.0, -1.0], ids=["ccw", "cw"])
def test_projection_onto_circle(direction):
    R = 80.0
    r = _road(_arc(R, 0.0, direction * np.pi, 25))
    rng = np.random.default_rng(3)
    for _ in range(50):
        phi = direction * rng.uniform(0.2, np.pi - 0.2)
        d = rng.uniform(-10.0, 10.0)  # radial offset, outward positive
        s, lat = r.project(np.array([(R + d) * np.cos(phi), (R + d) * np.sin(phi)]))
        assert s == pytest.approx(R * abs(phi), abs=2e-3)
        # outside the circle is right of travel when turning left (ccw), left when turning right (cw)
        assert lat == pytest.approx(-direction * d, abs=2e-3)


def test_arc_length_parametrisation_is_uniform():
    r = _road([[0, 0], [30, 5], [60, 30], [70, 80], [40, 120]])
    s = np.linspace(0.0, r.length, 4001)
    steps = np.hypot(*np.diff(r.point(s), axis=0).T)
    np.testing.assert_allclose(steps, s[1] - s[0], rtol=1e-4)
    # heading integrates curvature: theta(s1) - theta(s0) = int kappa ds
    th = np.unwrap(r.heading(s))
    k = r.curvature(s)
    integral = np.concatenate([[0.0], np.cumsum((k[1:] + k[:-1]) / 2 * np.diff(s))])
    np.testing.assert_allclose(th - th[0], integral, atol=1e-4)  # trapezoid rule error


@pytest.mark.parametrize("v", [
    [[0, 0], [0, 50], [50, 50]],  # right-angle corner
    [[0, 0], [0, 2], [100, 2], [100, 60]],  # 2 m jog between long legs
    [[0, 0], [3, 0.2], [200, 0.2]],  # 3 m chord next to a 197 m one
    [[0, 0], [40, 0], [41, 1], [41, 40]],
], ids=["corner", "jog", "short-long", "chamfer"])
def test_corners_stay_close_to_the_polyline(v):
    """Through every vertex, and never more than 0.6 m from the polyline (no spline overshoot at sharp corners)."""
    r = _road(v)
    pts = r.point(np.linspace(0.0, r.length, 3000))
    dist = shapely.distance(LineString(v), shapely.points(pts))
    assert dist.max() < 0.6
    for p in np.asarray(v, dtype=float):
        assert abs(r.project(p)[1]) < 2e-3
    assert r.length == pytest.approx(LineString(v).length, rel=0.02)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(seed=st.integers(0, 10_000), frac=st.floats(0.05, 0.95), lat=st.floats(-4.0, 4.0))
def test_project_inverts_offset_point(seed, frac, lat):
    """point(s, lateral) projects back to (s, lateral) on gently curving random roads."""
    rng = np.random.default_rng(seed)
    heading = np.cumsum(rng.uniform(-0.3, 0.3, 8))
    steps = rng.uniform(15.0, 40.0, 8)
    v = np.vstack([[0.0, 0.0], np.cumsum(steps[:, None] * np.c_[np.cos(heading), np.sin(heading)], axis=0)])
    r = _road(v)
    kmax = np.abs(r.curvature(np.linspace(0, r.length, 2000))).max()
    if abs(lat) * kmax > 0.5:
        return
    s = frac * r.length
    s_p, lat_p = r.project(r.point(s, lat))
    assert s_p == pytest.approx(s, abs=1e-6)
    assert lat_p == pytest.approx(lat, abs=1e-6)


def test_scalar_and_vector_queries_agree():
    r = _road(_arc(40.0, 0.0, 2.0, 9))
    s = np.linspace(-1.0, r.length + 1.0, 37)
    P, T, H, K = r.point(s), r.tangent(s), r.heading(s), r.curvature(s)
    for i, si in enumerate(s):
        np.testing.assert_allclose(r.point(float(si)), P[i], atol=1e-12)
        np.testing.assert_allclose(r.tangent(float(si)), T[i], atol=1e-12)
        assert r.heading(float(si)) == pytest.approx(H[i], abs=1e-12)
        assert r.curvature(float(si)) == pytest.approx(K[i], abs=1e-12)
    q = P + np.array([0.5, -1.5])
    ps, pl = r.project_many(q)
    one_by_one = np.array([r.project(p) for p in q])
    np.testing.assert_allclose(ps, one_by_one[:, 0], atol=1e-9)
    np.testing.assert_allclose(pl, one_by_one[:, 1], atol=1e-9)


# ---------------------------------------------------------------- lanes, twins, validation
def test_lane_offsets_right_hand_traffic():
    two_way = _road([[0, 0], [100, 0]], lanes=2, lane_width=3.5, twin="r2")
    assert two_way.lane_offset(0) == pytest.approx(-5.25)  # rightmost
    assert two_way.lane_offset(1) == pytest.approx(-1.75)
    assert two_way.edge_offsets == (-7.0, 0.0)
    one_way = _road([[0, 0], [100, 0]], lanes=2, lane_width=3.0)
    assert one_way.lane_offset(0) == pytest.approx(-1.5)
    assert one_way.lane_offset(1) == pytest.approx(1.5)
    single = _road([[0, 0], [100, 0]], lanes=1)
    assert single.lane_offset() == 0.0
    # a lane point lies to the right of travel on a road heading north
    north = _road([[0, 0], [0, 50]], lanes=1, lane_width=4.0, twin="x")
    np.testing.assert_allclose(north.point(10.0, north.lane_offset(0)), [2.0, 10.0], atol=1e-12)
    with pytest.raises(ValueError, match="lane must be in"):
        two_way.lane_offset(2)


def test_reversed_twin_matches_a_fresh_fit():
    v = np.array([[0, 0], [20, 3], [45, 15], [60, 40], [62, 70.0]])
    fwd = _road(v, id="s.f", twin="s.r", lanes=2)
    rev = fwd.reversed(id="s.r")
    fresh = Road(id="x", vertices=v[::-1], start_node="b", end_node="a")
    assert (rev.start_node, rev.end_node, rev.twin, rev.lanes) == ("b", "a", "s.f", 2)
    s = np.linspace(0.0, fresh.length, 300)
    assert rev.length == pytest.approx(fresh.length, rel=1e-12)
    np.testing.assert_allclose(rev.point(s), fresh.point(s), atol=1e-9)
    np.testing.assert_allclose(rev.curvature(s), fresh.curvature(s), atol=1e-9)
    np.testing.assert_allclose(rev.point(s), fwd.point(fwd.length - s), atol=1e-9)
    with pytest.raises(ValueError, match="needs twin"):
        fwd.reversed(id="other")


def test_vertices_are_read_only():
    r = _road([[0, 0], [5, 5], [10, 0]])
    with pytest.raises(ValueError):
        r.vertices[0, 0] = 1.0


@pytest.mark.parametrize("kw,match", [
    (dict(vertices=[[0, 0]]), "vertices must be"),
    (dict(vertices=[[0, 0], [1, 1], [1, 1]]), "coincide"),
    (dict(vertices=[[0, 0], [np.nan, 1]]), "non-finite"),
    (dict(lanes=0), "lanes must be"),
    (dict(lane_width=-1.0), "lane_width"),
    (dict(speed_limit=0.0), "speed_limit"),
    (dict(id=""), "id must be"),
])
def test_validation_names_field(kw, match):
    args = dict(id="r", vertices=[[0, 0], [10, 0]], start_node="a", end_node="b") | kw
    with pytest.raises(ValueError, match=match):
        Road(**args)
