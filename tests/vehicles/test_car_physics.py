"""The PyBullet car body and the fleet: stability, actuation, road following, stops and car following.

The fleet tests run every car as a physics multibody and as a kinematic box (``dynamics``), and mixed fleets."""

import math

import numpy as np
import pybullet as p
import pytest

from car_fixtures import SimpleNetwork, StraightRoad, bullet_client, curvy_network, run_fleet
from vehicles.car.body import CarBody, ackermann_angles, wheel_speeds
from vehicles.car.driver_config import DriverConfig
from vehicles.car.fleet import CarFleet
from vehicles.car.longitudinal import curve_speed
from vehicles.car.params import load_car
from vehicles.car.route import Route

SEDAN, VAN = load_car("sedan"), load_car("van")
DYNAMICS = ("physics", "kinematic")


@pytest.fixture
def client():
    c = bullet_client(240)
    yield c
    p.disconnect(c)


@pytest.mark.parametrize("delta", [-0.5, -0.1, 0.05, 0.3, 0.6])
def test_ackermann_relation(delta):
    left, right = ackermann_angles(delta, SEDAN.wheelbase, SEDAN.track)
    # cot(outer) - cot(inner) = track / wheelbase, and the bicycle angle lies between them
    assert 1 / math.tan(right) - 1 / math.tan(left) == pytest.approx(SEDAN.track / SEDAN.wheelbase, rel=1e-9)
    assert min(left, right) < delta < max(left, right)
    w = wheel_speeds(10.0, delta, SEDAN)
    inner_rear = w[2] if delta > 0 else w[3]
    assert inner_rear == pytest.approx(min(w))


@pytest.mark.parametrize("params", [SEDAN, VAN], ids=["sedan", "van"])
def test_car_rests_on_its_wheels_without_sinking_or_jitter(client, params):
    car = CarBody(client, params, np.array([3.0, -2.0]), 0.7)
    for _ in range(480):
        car.apply(0.0, 0.0, braking=True)
        p.stepSimulation(physicsClientId=client)
    p_W, q_WB, v_W, w_W = car.read()
    assert p_W[2] == pytest.approx(params.cog_height, abs=0.005)
    assert np.linalg.norm(v_W) < 1e-3 and np.linalg.norm(w_W) < 1e-3
    roll, pitch, yaw = p.getEulerFromQuaternion(q_WB)
    assert abs(roll) < 1e-3 and abs(pitch) < 1e-3 and yaw == pytest.approx(0.7, abs=1e-3)
    # weight carried by the four wheel contacts
    contacts = p.getContactPoints(bodyA=car.body_id, physicsClientId=client)
    assert {c[3] for c in contacts} == {1, 3, 4, 5}
    assert sum(c[9] for c in contacts) == pytest.approx(params.mass * 9.81, rel=0.01)


def test_steady_turn_matches_the_bicycle_yaw_rate_and_ackermann_knuckles(client):
    car = CarBody(client, SEDAN, np.zeros(2), 0.0)
    delta, v = 0.12, 8.0
    v_ref = 0.0
    for _ in range(240 * 10):
        v_ref = min(v_ref + 2.0 / 240, v)
        car.apply(delta, v_ref, braking=False)
        p.stepSimulation(physicsClientId=client)
    _, q, v_W, w_W = car.read()
    beta = math.atan(0.5 * math.tan(delta))
    assert np.linalg.norm(v_W[:2]) == pytest.approx(v, rel=0.01)
    assert w_W[2] == pytest.approx(v * math.cos(beta) * math.tan(delta) / SEDAN.wheelbase, rel=0.02)
    left, right = car.steer_angles()
    assert (left, right) == pytest.approx(ackermann_angles(delta, SEDAN.wheelbase, SEDAN.track), abs=2e-3)
    assert abs(p.getEulerFromQuaternion(q)[0]) < 0.02  # little roll (rigid body, no suspension)


@pytest.mark.parametrize("dynamics", DYNAMICS)
@pytest.mark.parametrize("params", [SEDAN, VAN], ids=["sedan", "van"])
def test_car_on_a_curvy_spline_road_keeps_its_lane_and_speed_profile(client, params, dynamics):
    net = curvy_network()
    a_lat = 3.5
    cfg = DriverConfig(cruise_fraction_range=(1.0, 1.0), stop_probability=0.0, lateral_accel_max=a_lat)
    fleet = CarFleet(client, [params], [cfg], [Route(roads=("curvy.f", "tail.f"))], net, 240, np.random.default_rng(1),
                     dynamics=[dynamics])
    run = run_fleet(fleet, client, 60.0)
    road = net.roads["curvy.f"]
    on = np.array([r[0] == "curvy.f" for r in run.road])
    lat, v_lim = [], []
    d = road.lane_offset(0)
    for k in np.flatnonzero(on):
        s, off = road.project(run.p_W[k, 0, :2])
        kap = road.curvature(s)
        lat.append(off - d)
        v_lim.append(min(road.speed_limit, float(curve_speed(np.array([kap / (1 - d * kap)]), a_lat)[0])))
    lat, v_lim, v = np.array(lat), np.array(v_lim), run.speed[on, 0]
    assert on.sum() * 6 / 240 > 30.0  # drove the curvy road for over 30 s
    assert np.percentile(np.abs(lat), 95) < 0.5
    assert np.max(np.abs(lat + d)) < road.lanes * road.lane_width  # never left its carriageway
    assert v.max() > 14.0  # close to the 15 m/s limit on the straighter parts
    # speed never above the curvature / road limit; tolerance 3 % + 0.2 m/s (tracking lag, curvature at the centre)
    assert np.all(v <= 1.03 * v_lim + 0.2)
    assert np.abs(run.roll_pitch).max() < 0.05
    assert not any(e["type"] == "car_left_road" for e in run.events)


@pytest.mark.parametrize("dynamics", DYNAMICS)
def test_car_stops_at_listed_junction_and_drives_on_after_dwell(client, dynamics):
    net = SimpleNetwork()
    net.add(StraightRoad(id="a", a=(0.0, 0.0), b=(80.0, 0.0), start_node="n0", end_node="n1", speed_limit=12.0))
    net.add(StraightRoad(id="b", a=(80.0, 0.0), b=(80.0, 80.0), start_node="n1", end_node="n2", speed_limit=12.0))
    cfg = DriverConfig(cruise_fraction_range=(1.0, 1.0), dwell_range=(2.0, 4.0), cruise_change_period=0.0)
    fleet = CarFleet(client, [SEDAN], [cfg], [Route(roads=("a", "b"), stops=("n1",))], net, 240,
                     np.random.default_rng(5), dynamics=[dynamics])
    run = run_fleet(fleet, client, 40.0, stride=1)  # row k holds tick k + 1
    ev = run.events
    stop = next(e for e in ev if e["type"] == "car_stop")
    go = next(e for e in ev if e["type"] == "car_go")
    assert stop["node"] == "n1" and 2.0 <= stop["dwell"] <= 4.0
    assert (go["tick"] - stop["tick"]) / 240 == pytest.approx(stop["dwell"], abs=1 / 40 + 1e-9)
    assert np.all(run.speed[stop["tick"] + 12:go["tick"] - 1, 0] < 0.05)
    assert 70.0 < run.p_W[stop["tick"] - 1, 0, 0] < 80.0 - 4.0
    assert any(e["type"] == "car_enter_road" and e["road"] == "b" for e in ev)
    end = next(e for e in ev if e["type"] == "car_route_end")
    assert end["tick"] > go["tick"] and run.p_W[-1, 0, 1] > 60.0
    assert run.stopped[-1, 0]


@pytest.mark.parametrize("dynamics", [(a, b) for a in DYNAMICS for b in DYNAMICS], ids="-".join)
def test_two_cars_keep_the_idm_gap(client, dynamics):
    """Leader and follower each physics or kinematic: mixed fleets follow one another like uniform ones."""
    net = SimpleNetwork()
    net.add(StraightRoad(id="long", a=(0.0, 0.0), b=(1200.0, 0.0), start_node="s", end_node="t", speed_limit=18.0))
    lead = DriverConfig(cruise_fraction_range=(0.5, 0.5), cruise_change_period=0.0)
    follow = DriverConfig(cruise_fraction_range=(1.0, 1.0), cruise_change_period=0.0)
    fleet = CarFleet(client, [VAN, SEDAN], [lead, follow], [Route(roads=("long",), start_s=40.0),
                                                            Route(roads=("long",), start_s=5.0)],
                     net, 240, np.random.default_rng(2), dynamics=dynamics)
    run = run_fleet(fleet, client, 60.0)
    gap = run.p_W[:, 0, 0] - run.p_W[:, 1, 0] - 0.5 * (VAN.length + SEDAN.length)
    assert gap.min() > 0.75 * follow.idm_s0
    late = slice(len(gap) - 400, len(gap))  # last 10 s
    v_f = run.speed[late, 1]
    want = follow.idm_s0 + v_f * follow.idm_time_headway
    assert np.all(np.abs(run.speed[late, 0] - 9.0) < 0.15)
    assert np.max(np.abs(gap[late] - want)) < 0.05 * want.mean()


@pytest.mark.parametrize("dynamics", [("physics", "physics"), ("kinematic", "kinematic"), ("kinematic", "physics")],
                         ids="-".join)
def test_fleet_state_and_validation(client, dynamics):
    net = curvy_network()
    cfg = DriverConfig()
    with pytest.raises(ValueError, match="spawn"):
        CarFleet(client, [SEDAN, SEDAN], [cfg, cfg], [Route(roads=("curvy.f",)), Route(roads=("curvy.f",))], net,
                 240, np.random.default_rng(0), dynamics=dynamics)
    with pytest.raises(ValueError, match="DriverConfig.rate_hz = 50 Hz does not divide physics_hz = 240 Hz"):
        CarFleet(client, [SEDAN], [DriverConfig(rate_hz=50)], [Route(roads=("curvy.f",))], net, 240,
                 np.random.default_rng(0), dynamics=dynamics[:1])
    with pytest.raises(ValueError, match="one params, driver config, route and dynamics per car"):
        CarFleet(client, [SEDAN], [cfg], [Route(roads=("curvy.f",))], net, 240, np.random.default_rng(0),
                 dynamics=dynamics)
    with pytest.raises(ValueError, match=r"car dynamics must be one of \['kinematic', 'physics'\], got 'hover'"):
        CarFleet(client, [SEDAN], [cfg], [Route(roads=("curvy.f",))], net, 240, np.random.default_rng(0),
                 dynamics=["hover"])
    fleet = CarFleet(client, [SEDAN, VAN], [cfg, cfg],
                     [Route(roads=("curvy.f",)), Route(random_walk=True, start_road="tail.r", start_s=3.0)],
                     net, 240, np.random.default_rng(0), dynamics=dynamics)
    assert np.array_equal(fleet.state.a_W, np.zeros((2, 3))) and np.array_equal(fleet.state.v_W, np.zeros((2, 3)))
    run_fleet(fleet, client, 3.0)
    st = fleet.state
    fleet.apply_actuation()  # one more tick: a_W is the finite difference of v_W over it
    p.stepSimulation(physicsClientId=client)
    fleet.after_step(3 * 240 + 1)
    assert np.array_equal(fleet.state.a_W, (fleet.state.v_W - st.v_W) * 240) and fleet.state.tick == 3 * 240 + 1
    assert st.p_W.shape == (2, 3) and st.q_WB.shape == (2, 4) and st.v_W.shape == (2, 3) and st.a_W.shape == (2, 3)
    assert np.allclose(np.linalg.norm(st.q_WB, axis=1), 1.0)
    assert st.road_id == ["curvy.f", "tail.r"]
    assert np.all(st.speed > 1.0)  # accelerating from rest
    assert np.allclose(st.a_W[:, 2], 0.0, atol=0.5)
    assert np.all(np.abs(st.lateral - np.array([net.roads[r].lane_offset(0) for r in st.road_id])) < 0.5)
    assert len(fleet.body_ids) == 2


@pytest.mark.parametrize("dynamics", DYNAMICS)
def test_fleet_is_deterministic_for_a_seed(dynamics):
    net = curvy_network()
    cfg = DriverConfig(stop_probability=0.5)
    routes = [Route(random_walk=True, start_road="curvy.f", start_s=5.0),
              Route(random_walk=True, start_road="curvy.r", start_s=5.0)]
    runs = []
    for _ in range(2):
        c = bullet_client(240)
        fleet = CarFleet(c, [SEDAN, VAN], [cfg, cfg], routes, net, 240, np.random.default_rng(123),
                         dynamics=[dynamics, "physics"])
        runs.append(run_fleet(fleet, c, 2.0))
        p.disconnect(c)
    assert np.array_equal(runs[0].p_W, runs[1].p_W)
    assert runs[0].events == runs[1].events
