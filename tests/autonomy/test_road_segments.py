"""Constant-curvature road approximation: exact circles, spline roads within tolerance, density, segment geometry."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autonomy.estimation.road.constraint import RoadConstraintModel, SegmentCursor
from autonomy.estimation.road.segments import (
    RoadApproximation,
    Segment,
    approximation_error,
    biarc,
    vertex_tangents,
)
from autonomy.estimation.models import SINGER
from worlds.roads.road import Road

# Stated tolerance of the biarc approximation of a spline road whose vertices are at most 50 m apart and turn by at
# most 30 degrees each (no corner knots): 0.1 m from the vertices alone, 5 mm after resampling every 10 m.
TOL_VERTICES = 0.1
TOL_RESAMPLED_10M = 5e-3


def gentle_road(spacing: float = 40.0) -> Road:
    """A 1.2 km road through vertices on a sine (turn per vertex < 30 deg)."""
    x = np.arange(0.0, 1200.0 + 1e-9, spacing)
    return Road(id="r", vertices=np.c_[x, 120.0 * np.sin(2 * np.pi * x / 900.0)], start_node="a", end_node="b")


@pytest.mark.parametrize("direction", [1, -1], ids=["ccw", "cw"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_circle_is_reproduced_exactly(seed, direction):
    rng = np.random.default_rng(seed)
    radius = float(rng.uniform(30.0, 800.0))
    centre = rng.uniform(-1e3, 1e3, size=2)
    angles = np.sort(rng.uniform(0.0, 5.0, size=int(rng.integers(3, 12))))[::direction]  # uneven spacing
    verts = centre + radius * np.c_[np.cos(angles), np.sin(angles)]
    approx = RoadApproximation.from_vertices(verts, line_curvature=1e-9)
    assert len(approx.segments) == 2 * (len(verts) - 1)
    for seg in approx.segments:
        assert seg.kind == "arc"
        assert np.sign(seg.kappa) == direction
        np.testing.assert_allclose(1.0 / abs(seg.kappa), radius, rtol=1e-6)
        np.testing.assert_allclose(seg.centre, centre, rtol=0, atol=1e-6 * radius)
    np.testing.assert_allclose(approx.length, radius * abs(angles[-1] - angles[0]), rtol=1e-9)


def test_collinear_vertices_give_lines_and_vertex_tangents_are_central_differences():
    verts = np.array([[0.0, 0.0], [10.0, 5.0], [30.0, 15.0], [35.0, 17.5]])
    approx = RoadApproximation.from_vertices(verts)
    assert all(g.kind == "line" for g in approx.segments)
    np.testing.assert_allclose(approx.length, np.hypot(35.0, 17.5), rtol=1e-12)
    # equal chords: the circle tangent is the central difference
    v = np.array([[0.0, 0.0], [10.0, 0.0], [10.0 + 10 * np.cos(0.3), 10 * np.sin(0.3)]])
    t = vertex_tangents(v)
    c = v[2] - v[0]
    np.testing.assert_allclose(t[1], c / np.hypot(*c), atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(5.0, 60.0), st.floats(-1.2, 1.2)), min_size=2, max_size=8))
def test_biarcs_are_tangent_continuous_and_interpolate_the_vertices(steps):
    heading, p = 0.3, np.zeros(2)
    verts = [p.copy()]
    for length, turn in steps:
        heading += turn
        p = p + length * np.array([np.cos(heading), np.sin(heading)])
        verts.append(p.copy())
    verts = np.array(verts)
    approx = RoadApproximation.from_vertices(verts, line_curvature=0.0)
    segs = approx.segments
    ends = [segs[0].p0] + [g.p1 for g in segs]
    for v in verts:  # every vertex is a segment end
        assert min(np.hypot(*(v - e)) for e in ends) < 1e-7
    for a, b in zip(segs[:-1], segs[1:], strict=True):
        np.testing.assert_allclose(a.point(a.length), b.p0, atol=1e-7)
        dth = np.angle(np.exp(1j * (a.heading(a.length) - b.theta0)))
        assert abs(dth) < 1e-7  # C1: common tangent at every joint
    for g in segs:
        np.testing.assert_allclose(g.point(g.length), g.p1, atol=1e-7)


def test_spline_road_within_stated_tolerance_and_density_lowers_the_error():
    road = gentle_road()
    err = approximation_error(RoadApproximation.from_road(road), road)
    assert err < TOL_VERTICES
    errors = {h: approximation_error(RoadApproximation.from_road(road, max_spacing=h), road) for h in (40, 20, 10, 5)}
    assert errors[10] < TOL_RESAMPLED_10M
    # biarcs with exact-for-circles tangents converge at third order or better: halving the spacing divides by > 4
    for coarse, fine in ((40, 20), (20, 10), (10, 5)):
        assert errors[fine] < errors[coarse] / 4.0
    approx = RoadApproximation.from_road(road, max_spacing=10)
    assert abs(approx.length - road.length) < 1e-3


@settings(max_examples=80, deadline=None)
@given(kappa=st.one_of(st.just(0.0), st.floats(-0.2, -1e-3), st.floats(1e-3, 0.2)),
       sigma_frac=st.floats(0.0, 1.0), lateral=st.floats(-3.0, 3.0), theta0=st.floats(-3.0, 3.0))
def test_segment_local_inverts_point(kappa, sigma_frac, lateral, theta0):
    length = 10.0 if kappa == 0 else min(10.0, 3.0 / abs(kappa))
    kind = "line" if kappa == 0.0 else "arc"
    p0 = np.array([3.0, -2.0])
    tmp = Segment(kind=kind, p0=p0, p1=p0, theta0=theta0, kappa=kappa, length=length)
    seg = Segment(kind=kind, p0=p0, p1=tmp.point(length), theta0=theta0, kappa=kappa, length=length)
    if kind == "arc" and abs(lateral) * abs(kappa) > 0.5:
        lateral = 0.5 / abs(kappa) * np.sign(lateral)
    sigma = sigma_frac * length
    p = seg.point(sigma, lateral)
    s1, l1, n1 = seg.local(p)
    assert s1 == pytest.approx(sigma, abs=1e-8)
    assert l1 == pytest.approx(lateral, abs=1e-8)
    th = seg.heading(sigma)
    np.testing.assert_allclose(n1, [-np.sin(th), np.cos(th)], atol=1e-9)
    # the vectorised path agrees with the scalar one
    s2, l2, n2 = seg.local(np.c_[p, p + 0.1])
    assert s2[0] == pytest.approx(s1, abs=1e-9) and l2[0] == pytest.approx(l1, abs=1e-9)
    np.testing.assert_allclose(n2[:, 0], n1, atol=1e-12)


def test_arc_continues_as_its_end_tangents():
    seg = biarc([0.0, 0.0], [1.0, 0.0], [20.0, 20.0], [0.0, 1.0])[0]
    th1 = seg.heading(seg.length)
    t1 = np.array([np.cos(th1), np.sin(th1)])
    n1 = np.array([-t1[1], t1[0]])
    p = seg.p1 + 7.0 * t1 + 1.5 * n1
    sigma, lat, n = seg.local(p)
    assert sigma == pytest.approx(seg.length + 7.0) and lat == pytest.approx(1.5)
    np.testing.assert_allclose(n, n1, atol=1e-12)
    sigma, lat, _ = seg.local(seg.p0 - 4.0 * np.array([1.0, 0.0]) - 2.0 * np.array([0.0, 1.0]))
    assert sigma == pytest.approx(-4.0) and lat == pytest.approx(-2.0)


@pytest.mark.parametrize("kappa", [0.0, 0.05, -0.02], ids=["line", "left", "right"])
def test_constraint_jacobian_matches_finite_differences(kappa):
    p0 = np.array([1.0, 2.0])
    kind = "line" if kappa == 0 else "arc"
    tmp = Segment(kind=kind, p0=p0, p1=p0, theta0=0.4, kappa=kappa, length=15.0)
    seg = Segment(kind=kind, p0=p0, p1=tmp.point(15.0), theta0=0.4, kappa=kappa, length=15.0)
    x = np.array([seg.point(6.0, 0.8)[0], 3.0, 0.1, seg.point(6.0, 0.8)[1], -1.0, 0.2])
    model = RoadConstraintModel(SINGER, seg, x[[0, 3]], velocity=True)
    H = model.jacobian(x)
    eps = 1e-6
    H_num = np.column_stack([(model.h(x + eps * e) - model.h(x - eps * e)) / (2 * eps) for e in np.eye(6)])
    np.testing.assert_allclose(H, H_num, atol=1e-6)
    assert model.h(x)[0] == pytest.approx(0.8, abs=1e-9)


def test_cursor_follows_the_estimate_along_the_path_and_not_back_across_a_junction():
    a = RoadApproximation.from_vertices(np.array([[0.0, 0.0], [50.0, 0.0], [100.0, 0.0]]), road_id="a")
    b = RoadApproximation.from_vertices(np.array([[100.0, 0.0], [100.0, 60.0]]), road_id="b")
    cur = SegmentCursor(a.segments + b.segments, 0)
    assert cur.follow(np.array([70.0, 1.0])).road_id == "a"
    assert cur.active.p0[0] <= 70.0 <= cur.active.p1[0]
    assert cur.remaining(np.array([70.0, 1.0])) == pytest.approx(30.0 + 60.0)
    assert cur.next_road_start() == len(a.segments)
    cur.follow(np.array([130.0, 0.0]))  # past the end of road a: onto b's first segment (extended back)
    assert cur.road_id == "b"
    cur.follow(np.array([99.0, -20.0]))  # before b's start: stays on b, does not step back onto a
    assert cur.road_id == "b"
    assert cur.road_ids() == ("a", "b")
    # the paper's gate moves on when the segment end lies inside the position ellipse
    assert [g.length for g in a.segments] == pytest.approx([25.0] * 4)
    cur2 = SegmentCursor(a.segments, 0)
    cur2.follow(np.array([40.0, 0.0]), P_pos=np.eye(2) * 400.0)
    assert cur2.index == 1  # along-track: the foot point lies on [25, 50]
    cur2.follow(np.array([40.0, 0.0]), P_pos=np.eye(2) * 400.0, gate=0.8)
    assert cur2.index == 2  # (50 - 40)² / 400 < 0.8
    cur2 = SegmentCursor(a.segments, 1)
    cur2.follow(np.array([40.0, 0.0]), P_pos=np.eye(2) * 4.0, gate=0.8)
    assert cur2.index == 1
