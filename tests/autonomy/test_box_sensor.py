"""Bounded-error nadir sensor: footprint, building shadows, guaranteed boxes, decoy visibility cones."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import stats

from autonomy.sensing.box_sensor import BoxSensor, BoxSensorConfig
from autonomy.sensing.fake_scene import FakeScene
from autonomy.sensing.scene import SensorPose, TargetTruth
from worlds.geometry import Building


def yaw_q(yaw: float) -> np.ndarray:
    return np.array([0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2)])


def ground_targets(xy, kind=None, **extra) -> TargetTruth:
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    m = len(xy)
    return TargetTruth(
        ids=np.arange(m),
        p_W=np.column_stack([xy, np.full(m, 0.5)]),
        v_W=np.zeros((m, 3)),
        kind=kind or ("car",) * m,
        yaw=np.zeros(m),
        **extra,
    )


def test_footprint_matches_paper_size():
    sensor = BoxSensor(BoxSensorConfig(opening_angle=np.pi / 4, footprint_frame="world"))
    region = sensor.observed_region(SensorPose(p_W=[50.0, 60.0, 100.0]))
    side = 2 * 100 * np.tan(np.pi / 8)
    assert side == pytest.approx(82.84, abs=0.01)
    assert region.area == pytest.approx(side**2, rel=1e-9)
    np.testing.assert_allclose(region.bounds, [50 - side / 2, 60 - side / 2, 50 + side / 2, 60 + side / 2])
    turned = BoxSensor(BoxSensorConfig(footprint_frame="heading")).observed_region(
        SensorPose(p_W=[0.0, 0.0, 100.0], q_WB=yaw_q(np.pi / 4))
    )
    assert turned.bounds[2] == pytest.approx(side / np.sqrt(2), rel=1e-9)


def test_shadow_of_tall_building_reaches_footprint_edge_and_short_one_is_finite():
    tall = Building.cuboid((15.0, 0.0), (10.0, 10.0, 100.0))
    short = Building.cuboid((-15.0, 0.0), (10.0, 10.0, 50.0))
    sensor = BoxSensor(BoxSensorConfig(footprint_frame="world"), buildings=[tall, short])
    region = sensor.observed_region(SensorPose(p_W=[0.0, 0.0, 100.0]))
    assert not region.intersects(shapely.Point(41.0, 0.0))  # behind the tall one, at the footprint edge
    # short building (top 50 m, half-way up): its roof edge at x = -20 projects to x = -40 from 100 m
    assert not region.intersects(shapely.Point(-39.0, 0.0))
    assert region.intersects(shapely.Point(-41.0, 0.0))
    assert region.intersects(shapely.Point(0.0, 30.0))


buildings_st = st.lists(
    st.tuples(
        st.floats(-50, 50),
        st.floats(-50, 50),
        st.floats(4, 25),
        st.floats(4, 25),
        st.floats(5, 140),
        st.floats(-np.pi, np.pi),
    ),
    min_size=1,
    max_size=4,
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    buildings=buildings_st,
    sx=st.floats(-20, 20),
    sy=st.floats(-20, 20),
    h=st.floats(60, 120),
    yaw=st.floats(-np.pi, np.pi),
    seed=st.integers(0, 2**31),
)
def test_observed_region_agrees_with_exact_line_of_sight(buildings, sx, sy, h, yaw, seed):
    blds = [Building.cuboid((x, y), (a, b, hh), yaw=ps) for x, y, a, b, hh, ps in buildings]
    pose = SensorPose(p_W=[sx, sy, h], q_WB=yaw_q(yaw))
    if any(shapely.Polygon(b.footprint).buffer(0.5).contains(shapely.Point(sx, sy)) and b.top_z >= h for b in blds):
        return  # sensor inside a building
    region = BoxSensor(BoxSensorConfig(), buildings=blds).observed_region(pose)
    rng = np.random.default_rng(seed)
    half = h * np.tan(np.pi / 8)
    pts = np.column_stack(
        [sx + rng.uniform(-1.3 * half, 1.3 * half, 400), sy + rng.uniform(-1.3 * half, 1.3 * half, 400)]
    )
    fp = BoxSensor(BoxSensorConfig()).observed_region(pose)
    in_region = shapely.intersects_xy(region, pts[:, 0], pts[:, 1])
    boundary = shapely.boundary(region) if not region.is_empty else shapely.Point()
    far_from_edges = shapely.distance(boundary, shapely.points(pts)) > 1e-3
    far_from_edges &= shapely.distance(fp.boundary, shapely.points(pts)) > 1e-3
    in_fp = shapely.intersects_xy(fp, pts[:, 0], pts[:, 1])
    los = FakeScene(blds).line_of_sight(
        np.repeat(pose.p_W[None], len(pts), 0), np.column_stack([pts, np.zeros(len(pts))])
    )
    expected = in_fp & los
    assert np.array_equal(in_region[far_from_edges], expected[far_from_edges])


@settings(max_examples=40, deadline=None)
@given(
    buildings=buildings_st,
    sx=st.floats(-20, 20),
    sy=st.floats(-20, 20),
    h=st.floats(60, 120),
    bound=st.floats(0.1, 10.0),
    seed=st.integers(0, 2**31),
)
def test_every_target_in_observed_region_is_detected_inside_its_box(buildings, sx, sy, h, bound, seed):
    blds = [Building.cuboid((x, y), (a, b, hh), yaw=ps) for x, y, a, b, hh, ps in buildings]
    sensor = BoxSensor(BoxSensorConfig(noise_bound=bound), buildings=blds)
    pose = SensorPose(p_W=[sx, sy, h])
    rng = np.random.default_rng(seed)
    tg = ground_targets(rng.uniform(-70, 70, size=(30, 2)))
    out = sensor.measure(0.0, pose, tg, FakeScene(blds), rng)
    region = out.extras["observed_region"]
    inside = np.flatnonzero(shapely.intersects_xy(region, tg.p_W[:, 0], tg.p_W[:, 1]))
    assert sorted(out.truth_ids.tolist()) == inside.tolist()
    for det, tid in zip(out.detections, out.truth_ids, strict=True):
        lo, hi = det.z - det.bound, det.z + det.bound
        assert np.all(lo <= tg.p_W[tid, :2]) and np.all(tg.p_W[tid, :2] <= hi)
        np.testing.assert_allclose(det.bound, [bound, bound])


def test_bounded_noise_is_uniform():
    sensor = BoxSensor(BoxSensorConfig(noise_bound=5.0))
    tg = ground_targets([[3.0, -4.0]])
    rng = np.random.default_rng(0)
    err = np.array(
        [
            sensor.measure(0.0, SensorPose(p_W=[0, 0, 100.0]), tg, FakeScene(), rng).detections[0].z - tg.p_W[0, :2]
            for _ in range(2000)
        ]
    )
    for k in range(2):
        assert stats.kstest(err[:, k], stats.uniform(loc=-5.0, scale=10.0).cdf).pvalue > 0.01


def test_decoy_seen_only_from_inside_its_cone():
    half = np.pi / 10
    tilt = half  # axis tilted from vertical by the aperture, pointing east
    axis = [np.sin(tilt), 0.0, np.cos(tilt)]
    tg = ground_targets(
        [[0.0, 0.0], [0.0, 5.0]], kind=("decoy", "car"), cone_axis_W=[axis, [0, 0, 1]], cone_half_angle=[half, half]
    )
    sensor = BoxSensor(BoxSensorConfig(footprint_frame="world"))
    rng = np.random.default_rng(1)
    inside = sensor.measure(0.0, SensorPose(p_W=[20.0, 0.0, 100.0]), tg, FakeScene(), rng)  # 11 deg off vertical, east
    outside = sensor.measure(0.0, SensorPose(p_W=[-20.0, 0.0, 100.0]), tg, FakeScene(), rng)  # west: 29 deg off axis
    assert sorted(inside.truth_ids.tolist()) == [0, 1]
    assert outside.truth_ids.tolist() == [1]  # the car's cone is ignored


def test_non_convex_building_shadow_and_line_of_sight_agree():
    # L-shaped block: the notch (x > 10, y > 10) is open ground
    ell = Building(footprint=np.array([[0, 0], [30, 0], [30, 10], [10, 10], [10, 30], [0, 30]], float), height=40.0)
    scene = FakeScene([ell])
    over_notch = np.array([[20.0, 20.0, 60.0]])
    assert scene.line_of_sight(over_notch, np.array([[25.0, 25.0, 0.0]]))[0]  # straight down into the notch
    assert not scene.line_of_sight(over_notch, np.array([[5.0, 5.0, 0.0]]))[0]  # through the L's corner block
    assert scene.line_of_sight(np.array([[12.0, 40.0, 1.0]]), np.array([[40.0, 12.0, 1.0]]))[0]  # across the notch
    pose = SensorPose(p_W=[20.0, 20.0, 60.0])
    region = BoxSensor(BoxSensorConfig(footprint_frame="world"), buildings=[ell]).observed_region(pose)
    fp = BoxSensor(BoxSensorConfig(footprint_frame="world")).observed_region(pose)
    rng = np.random.default_rng(0)
    pts = rng.uniform(-5, 45, size=(3000, 2))
    keep = np.asarray(shapely.distance(shapely.boundary(region), shapely.points(pts)) > 1e-3)
    los = scene.line_of_sight(np.repeat(pose.p_W[None], len(pts), 0), np.column_stack([pts, np.zeros(len(pts))]))
    expected = shapely.intersects_xy(fp, pts[:, 0], pts[:, 1]) & los
    got = shapely.intersects_xy(region, pts[:, 0], pts[:, 1])
    assert 0.1 < np.mean(got) < 0.9
    assert np.array_equal(got[keep], expected[keep])
