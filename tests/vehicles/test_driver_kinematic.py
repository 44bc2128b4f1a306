"""The road-following driver on the kinematic bicycle model (no physics engine)."""

import math

import numpy as np
import pytest

from car_fixtures import (ArcRoad, SimpleNetwork, StraightRoad, grid_network, run_kinematic, run_kinematic_multi,
                          s_curve_network)
from vehicles.car.driver_config import DriverConfig
from vehicles.car.lane_path import LanePath
from vehicles.car.longitudinal import curve_speed, envelope_accel, idm_plus_accel
from vehicles.car.params import load_car
from vehicles.car.route import Route

SEDAN = load_car("sedan")
A_LAT = 2.5


def _lane_limits(net, run, car=0):
    """Per-tick (lateral offset from the lane centre (m), curvature speed limit of the lane (m/s), speed limit)."""
    lat, v_curve, v_road = [], [], []
    for k in range(len(run.speed)):
        road = net.roads[run.road[k][car]]
        s, off = road.project(run.p_xy[k, car])
        d = road.lane_offset(0)
        kap = float(road.curvature(s))
        lat.append(off - d)
        v_curve.append(float(curve_speed(np.array([kap / (1 - d * kap)]), A_LAT)[0]))
        v_road.append(road.speed_limit)
    return np.array(lat), np.array(v_curve), np.array(v_road)


def test_lane_path_on_arc_is_the_offset_circle():
    road = ArcRoad(id="arc", start=(0.0, 0.0), heading0=0.3, kappa=1 / 30, arc_length=80.0, start_node="a",
                   end_node="b")
    path = LanePath([road], [0], ds=0.5)
    r_lane = 30.0 + road.lane_width / 2  # right lane of a left turn: larger radius
    assert np.allclose(np.linalg.norm(path.xy - road.centre, axis=1), r_lane, atol=1e-9)
    assert np.allclose(path.kappa, 1 / r_lane, rtol=1e-9)
    assert path.length == pytest.approx(80.0 * r_lane / 30.0, rel=1e-3)
    q = road.point(40.0) + np.array([0.1, 0.2])
    proj = path.project(q)
    s_road, lat_road = road.project(q)
    assert proj.lateral + road.lane_offset(0) == pytest.approx(lat_road, abs=2e-3)
    assert path.locate(proj.s)[1] == pytest.approx(s_road, abs=0.02)


def _project_numpy(path, p_xy, hint, window):
    """LanePath.project's closest segment written with numpy array operations: (index, s, lateral)."""
    n = len(path.s) - 1
    lo, hi = (0, n) if hint is None else (max(0, hint - window), min(n, hint + window))
    seg = np.linalg.norm(np.diff(path.xy, axis=0), axis=1)  # segment lengths and tangents as LanePath makes them
    t = (np.diff(path.xy, axis=0) / np.maximum(seg, 1e-12)[:, None])[lo:hi]
    a, seg = path.xy[lo:hi], seg[lo:hi]
    d = np.asarray(p_xy, dtype=float) - a
    u = np.minimum(np.maximum(np.einsum("ij,ij->i", d, t), 0.0), seg)
    r = d - u[:, None] * t
    i = int(np.argmin(np.einsum("ij,ij->i", r, r)))
    return lo + i, float(path.s[lo + i] + u[i]), float(t[i, 0] * d[i, 1] - t[i, 1] * d[i, 0])


def test_projection_equals_the_vectorised_formula_to_the_last_bit():
    """The compiled closest-segment search takes the same operations in the same order as numpy's vectorised form,
    so drivers (and every recorded run) are unchanged by it: on vertices, on segments, near and far, with and
    without a hint."""
    net = s_curve_network()
    path = LanePath([net.roads[r] for r in "abcde"], [0] * 5, s_start=3.7, ds=1.0, corner_length=7.0)
    rng = np.random.default_rng(7)
    n = len(path.xy)
    for k in range(3000):
        j = int(rng.integers(n))
        q = [path.xy[j], path.xy[j] + rng.normal(0, 0.5, 2), path.xy[j] + rng.normal(0, 30, 2),
             0.5 * (path.xy[j] + path.xy[min(j + 1, n - 1)])][k % 4]
        hint, window = (None, 60) if k % 10 == 0 else (int(rng.integers(n)), int(rng.choice([20, 60, 80])))
        proj = path.project(q, hint, window)
        assert (proj.index, proj.s, proj.lateral) == _project_numpy(path, q, hint, window)


def test_junction_corner_is_smooth_and_turns_through_the_heading_change():
    net = SimpleNetwork()
    net.add(StraightRoad(id="a", a=(0.0, 0.0), b=(50.0, 0.0), start_node="n0", end_node="n1"))
    net.add(StraightRoad(id="b", a=(50.0, 0.0), b=(50.0, 50.0), start_node="n1", end_node="n2"))
    path = LanePath([net.roads["a"], net.roads["b"]], [0, 0], ds=0.5, corner_length=8.0)
    assert np.all(np.diff(path.s) > 0) and np.max(np.diff(path.s)) < 0.6
    # the heading turns by pi/2 without jumps, and the curvature integrates to it (trapezoid rule, 0.5 m samples)
    h = np.unwrap(path.heading)
    assert h[-1] - h[0] == pytest.approx(math.pi / 2, abs=1e-9)
    assert np.max(np.abs(np.diff(h))) < 0.06
    turn = np.sum(0.5 * (path.kappa[1:] + path.kappa[:-1]) * np.diff(path.s))
    assert turn == pytest.approx(math.pi / 2, abs=0.05)
    # a right-lane left turn around the corner: radius ~ (corner_length + lane_width/2) for a Bezier arc
    assert 1 / path.kappa.max() == pytest.approx(8.0 + 1.75, rel=0.25)
    assert path.junction_s[0] == pytest.approx(50.0 - 8.0, abs=0.6)


def test_envelope_reaches_the_cap_at_its_distance_with_constant_deceleration():
    a, v_target = envelope_accel(15.0, np.array([0.0, 50.0]), np.array([20.0, 5.0]), gain=1.5, decel_plan=2.0,
                                 min_distance=2.0)
    assert a == pytest.approx((5.0 ** 2 - 15.0 ** 2) / (2 * 50.0))
    assert v_target == pytest.approx(math.sqrt(25 + 200))


def test_idm_plus_equilibrium_gap_is_s0_plus_vT():
    v, s0, T = 10.0, 2.0, 1.5
    assert idm_plus_accel(v, v, s0 + v * T, s0=s0, time_headway=T, accel=1.5, decel=2.0) == pytest.approx(0.0)
    assert idm_plus_accel(v, v, 0.9 * (s0 + v * T), s0=s0, time_headway=T, accel=1.5, decel=2.0) < 0
    assert idm_plus_accel(v, v, 1.1 * (s0 + v * T), s0=s0, time_headway=T, accel=1.5, decel=2.0) > 0


def test_kinematic_car_follows_curvy_lane_and_respects_speed_profile():
    net = s_curve_network(speed_limit=15.0)
    cfg = DriverConfig(cruise_fraction_range=(1.0, 1.0), stop_probability=0.0, lateral_accel_max=A_LAT)
    run = run_kinematic(net, SEDAN, cfg, [Route(roads=("a", "b", "c", "d", "e"))], 45.0)
    lat, v_curve, v_road = _lane_limits(net, run)
    v = run.speed[:, 0]
    assert np.percentile(np.abs(lat), 95) < 0.3
    assert np.max(np.abs(lat)) < 0.5
    # tolerance: 2 % + 0.15 m/s (speed tracking lag of the 40 Hz driver)
    assert np.all(v <= 1.02 * np.minimum(v_curve, v_road) + 0.15)
    # and it is not crawling: reaches >= 90 % of the tighter bend's limit on d (R = 25 m right turn, lane R = 23.25 m)
    on_d = np.array([r[0] == "d" for r in run.road])
    assert v[on_d].max() >= 0.9 * math.sqrt(A_LAT * 23.25)
    assert any(e["type"] == "car_route_end" for e in run.events)
    assert run.stopped[-1, 0] and v[-1] < 0.05


def test_stops_at_listed_junctions_and_leaves_after_the_dwell():
    net = s_curve_network()
    cfg = DriverConfig(cruise_fraction_range=(1.0, 1.0), dwell_range=(3.0, 6.0), cruise_change_period=0.0)
    run = run_kinematic(net, SEDAN, cfg, [Route(roads=("a", "b", "c", "d", "e"), stops=("n1", "n3"))], 70.0, seed=3)
    stops = [e for e in run.events if e["type"] == "car_stop"]
    goes = [e for e in run.events if e["type"] == "car_go"]
    assert [e["node"] for e in stops] == ["n1", "n3"]
    assert len(goes) == 2
    for st, go in zip(stops, goes, strict=True):
        assert 3.0 <= st["dwell"] <= 6.0
        assert (go["tick"] - st["tick"]) / 240 == pytest.approx(st["dwell"], abs=1 / 40 + 1e-9)
        # standing still at the stop line during the dwell
        assert np.all(run.speed[st["tick"] + 24:go["tick"], 0] < 0.05)
        # and driving again afterwards
        assert run.speed[min(go["tick"] + 240 * 3, len(run.speed) - 1), 0] > 2.0
    # stopped within a few metres before the node
    for st in stops:
        node_end = net.roads[st["road"]].point(net.roads[st["road"]].length)
        dist = np.linalg.norm(run.p_xy[st["tick"], 0] - node_end)
        assert 6.0 < dist < 16.0


def test_two_cars_keep_the_idm_gap_and_never_collide():
    net = SimpleNetwork()
    net.add(StraightRoad(id="long", a=(0.0, 0.0), b=(1500.0, 0.0), start_node="s", end_node="t", speed_limit=20.0))
    lead = DriverConfig(cruise_fraction_range=(0.5, 0.5), cruise_change_period=0.0)
    follow = DriverConfig(cruise_fraction_range=(1.0, 1.0), cruise_change_period=0.0)
    routes = [Route(roads=("long",), start_s=60.0), Route(roads=("long",), start_s=0.0)]
    run = run_kinematic_multi(net, SEDAN, [lead, follow], routes, 70.0)
    gap = (run.p_xy[:, 0, 0] - run.p_xy[:, 1, 0]) - SEDAN.length
    assert gap.min() > 0.75 * follow.idm_s0
    v_f = run.speed[:, 1]
    late = slice(len(gap) - 240 * 10, len(gap))
    want = follow.idm_s0 + v_f[late] * follow.idm_time_headway
    assert np.all(np.abs(run.speed[late, 0] - 10.0) < 0.1)  # leader at half the 20 m/s limit
    assert np.max(np.abs(gap[late] - want)) < 0.05 * want.mean()


def test_random_walk_on_a_grid_stays_on_roads_and_is_reproducible():
    net = grid_network(3, 120.0)
    cfg = DriverConfig(dwell_range=(1.0, 3.0), stop_probability=0.5, cruise_change_period=10.0)
    route = Route(random_walk=True, start_road="h0_0.f", start_s=10.0)
    run = run_kinematic(net, SEDAN, cfg, [route], 150.0, seed=11)
    again = run_kinematic(net, SEDAN, cfg, [route], 150.0, seed=11)
    assert np.array_equal(run.p_xy, again.p_xy)
    roads = {r[0] for r in run.road}
    assert len(roads) >= 5
    lat = np.array([net.nearest(run.p_xy[k, 0])[2] for k in range(0, len(run.speed), 12)])
    # on the right-hand carriageway almost always; junction corners may graze the (square) kerb corner by < 0.5 m
    assert np.mean((lat < 0.0) & (lat > -3.5)) > 0.97
    assert np.max(np.abs(lat)) < 3.5 + 0.5
    kinds = {e["type"] for e in run.events}
    assert {"car_stop", "car_go", "car_enter_road"} <= kinds


@pytest.mark.parametrize("field, value", [
    ("rate_hz", 0), ("lateral_accel_max", -1.0), ("decel_max", 1.0), ("stop_probability", 1.5),
    ("dwell_range", (5.0, 2.0)), ("cruise_fraction_range", (0.0, 1.0)), ("idm_time_headway", 0.0),
    ("random_walk_chunk", 0), ("cruise_change_period", -1.0),
])
def test_invalid_driver_config_names_the_field(field, value):
    with pytest.raises(ValueError, match=rf"(?s)validation error for DriverConfig\n.*\b{field}\b"):
        DriverConfig(**{field: value})


@pytest.mark.parametrize("kwargs, field", [
    (dict(), "roads"), (dict(random_walk=True), "start_road"), (dict(roads=("a",), start_s=-1.0), "start_s"),
    (dict(random_walk=True, start_road="a", roads=("a",)), "roads"), (dict(roads=("a",), lane=-1), "lane"),
])
def test_invalid_route_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=rf"Route\.{field}"):
        Route(**kwargs)


def test_route_must_be_connected_and_known():
    from vehicles.car.driver import Driver

    net = s_curve_network()
    with pytest.raises(ValueError, match="does not start where"):
        Driver(config=DriverConfig(), params=SEDAN, route=Route(roads=("a", "c")), network=net,
               rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="unknown road id 'zz'"):
        Driver(config=DriverConfig(), params=SEDAN, route=Route(roads=("zz",)), network=net,
               rng=np.random.default_rng(0))


def test_network_route_with_listed_stops_on_a_real_grid():
    net = grid_network(3, 120.0)
    roads = tuple(net.route("0_0", "2_2"))
    assert len(roads) == 4
    nodes = [net.roads[r].end_node for r in roads[:-1]]
    cfg = DriverConfig(dwell_range=(1.0, 2.0), cruise_change_period=0.0)
    run = run_kinematic(net, SEDAN, cfg, [Route(roads=roads, stops=(nodes[1],))], 90.0, seed=4)
    assert [e["node"] for e in run.events if e["type"] == "car_stop"] == [nodes[1]]
    assert [e["road"] for e in run.events if e["type"] == "car_enter_road"] == list(roads[1:])
    assert run.events[-1]["type"] == "car_route_end"
    end = net.nodes["2_2"]
    assert 2.0 < np.linalg.norm(run.p_xy[-1, 0] - end) < 8.0  # parked on its lane just before the last node


def test_cruise_speed_changes_form_a_poisson_process_within_the_range():
    from vehicles.car.driver import Driver

    period, seconds = 4.0, 400.0
    cfg = DriverConfig(cruise_change_period=period, cruise_fraction_range=(0.6, 0.9))
    drv = Driver(config=cfg, params=SEDAN, route=Route(roads=("a",)), network=s_curve_network(),
                 rng=np.random.default_rng(7))
    p0, yaw0 = drv.spawn_pose()
    fractions = []
    for tick in range(0, int(seconds * 240), 6):
        drv.update(p0, yaw0, 0.0, tick)
        fractions.append(drv.cruise_fraction)
    changes = int(np.count_nonzero(np.diff(fractions)))
    mean = seconds / period  # Poisson count; 4-sigma band
    assert abs(changes - mean) < 4 * math.sqrt(mean)
    assert 0.6 <= min(fractions) and max(fractions) <= 0.9


def _drive_with_light(light, seconds=40.0, physics_hz=240):
    """One car from 0_0 east along h0_0.f, h1_0.f, h2_0.f of a 4 x 1 grid (junctions at x = 120, 240 m), no planned
    stops, the light of junction 1_0 (h0_0.f -> h1_0.f) given by ``light(t)``: (times, x, speed, stopped, events)."""
    from vehicles.car.bicycle import KinematicBicycle
    from vehicles.car.driver import Driver

    net = grid_network(n=4, spacing=120.0)
    route = Route(roads=("h0_0.f", "h1_0.f", "h2_0.f"), stops=())
    cfg = DriverConfig()
    d = Driver(config=cfg, params=SEDAN, route=route, network=net, rng=np.random.default_rng(3),
               physics_hz=physics_hz)
    tick = [0]
    if light is not None:
        d.signal = lambda a, b: light(tick[0] / physics_hz) if (a, b) == ("h0_0.f", "h1_0.f") else ""
    p, yaw = d.spawn_pose()
    car = KinematicBicycle(SEDAN, p, yaw, 0.0)
    every = cfg.ticks_per_update(physics_hz)
    t, x, v, stopped, events = [], [], [], [], []
    for k in range(int(seconds * physics_hz)):
        tick[0] = k
        car.step(d.command, 1.0 / physics_hz)
        if k % every == 0:
            d.update(car.p_xy, car.yaw, car.speed, k, None, car.yaw_rate)
            events += d.pop_events()
        t.append(k / physics_hz)
        x.append(car.p_xy[0])
        v.append(car.speed)
        stopped.append(d.stopped)
    return np.array(t), np.array(x), np.array(v), np.array(stopped), events


def test_a_red_light_stops_the_car_at_the_stop_line_until_green():
    """Red until 25 s: the car stops before the junction at x = 120 m (its stop line within the stop window), stays
    while red and goes at green; without a light, or with green throughout, it drives through without stopping."""
    t, x, v, stopped, events = _drive_with_light(lambda s: "r" if s < 25.0 else "G")
    at = (t > 18.0) & (t < 25.0)
    assert np.all(stopped[at]) and np.all(v[at] < 0.3)
    assert 100.0 < x[at].min() and x[at].max() < 120.0  # before the junction, within 20 m of it
    assert not stopped[(t > 26.0) & (x < 300.0)].any() and x[-1] > 180.0  # gone at green, through the junction
    stops = [e for e in events if e["type"] == "car_stop"]
    assert len(stops) == 1 and stops[0]["light"] and stops[0]["node"] == "1_0"
    go = [e for e in events if e["type"] == "car_go"]
    assert len(go) == 1 and 25.0 <= go[0]["tick"] / 240 < 25.1
    for light in (None, lambda s: "G"):
        t2, x2, v2, stopped2, events2 = _drive_with_light(light)
        assert not stopped2[x2 < 300.0].any() and not [e for e in events2 if e["type"] == "car_stop"]  # (route end)
        assert np.all(v2[(t2 > 8.0) & (x2 < 200.0)] > 5.0)  # through the junction at speed


def test_yellow_stops_only_a_car_that_can_stop_comfortably():
    """Yellow from the moment the car is 60 m (can stop) or 8 m (cannot, at cruise speed) before the junction."""
    def reach(limit):
        t, x, *_ = _drive_with_light(None, seconds=30.0)
        return t[np.argmax(x > 120.0 - limit)]
    for before, stops in ((60.0, True), (8.0, False)):
        t_yellow = reach(before)
        t, x, v, stopped, events = _drive_with_light(lambda s, ty=t_yellow: "y" if s >= ty else "G", seconds=30.0)
        assert bool(stopped.any()) == stops, before
        if stops:
            assert x[stopped].max() < 120.0
