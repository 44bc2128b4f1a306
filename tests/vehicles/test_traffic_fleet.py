"""The compiled traffic fleet: the Python drivers' trajectories to the last bit, car following across physics and
kinematic cars both ways, and boxes where the cars are whenever a sensor looks."""

import math

import numpy as np
import pybullet as p
import pytest

from car_fixtures import bullet_client, grid_network
from vehicles.car.driver import Driver
from vehicles.car.driver_config import DriverConfig
from vehicles.car.dynamics import KinematicDynamics
from vehicles.car.fleet import SYNC_RADIUS, CarFleet
from vehicles.car.params import load_car
from vehicles.car.route import Route
from vehicles.car.traffic import find_leaders
from vehicles.car.traffic_fleet import TrafficFleet
from vehicles.car.traffic_kernel import R_VFWD, R_X, R_Y, R_YAWREAD, drive_all
from vehicles.car.traffic_source import OtherCars

SEDAN, VAN = load_car("sedan"), load_car("van")


@pytest.fixture
def client():
    c = bullet_client(240)
    yield c
    p.disconnect(c)


def _reference(client, drivers, params, seconds, physics_hz=240):
    """The Python drivers and kinematic bicycles stepped every physics tick, as the car fleet stepped kinematic cars
    before the compiled fleet: per tick (x, y, heading read from the quaternion, forward speed) and the events; and,
    at every whole second, where each driver locates its car (road, arc length, lateral offset) and whether it
    stands."""
    dyn = [KinematicDynamics(client, par, *d.spawn_pose(), physics_hz) for d, par in zip(drivers, params, strict=True)]
    every = drivers[0].config.ticks_per_update(physics_hz)
    lengths = [par.length for par in params]
    out, events, located = [], [], {}
    for tick in range(1, int(seconds * physics_hz) + 1):
        for d, car in zip(drivers, dyn, strict=True):
            car.actuate(d.command)
        rows = [car.state_row() for car in dyn]
        yaw = np.array([math.atan2(2 * (r[6] * r[5] + r[3] * r[4]), 1 - 2 * (r[4] * r[4] + r[5] * r[5])) for r in rows])
        speed = np.array([r[7] * math.cos(h) + r[8] * math.sin(h) for r, h in zip(rows, yaw, strict=True)])
        xy = np.array([r[0:2] for r in rows])
        if tick % every == 0:
            leaders = find_leaders(drivers, xy, yaw, speed, lengths)
            for i, d in enumerate(drivers):
                d.update(xy[i], float(yaw[i]), float(speed[i]), tick, leaders[i], rows[i][12])
                events += [dict(e, car=i) for e in d.pop_events()]
        out.append(np.column_stack([xy, yaw, speed]))
        if tick % physics_hz == 0:
            located[tick] = ([d.locate(xy[i]) for i, d in enumerate(drivers)], [d.stopped for d in drivers])
    return np.array(out), events, located


def _drivers(net, n, seed, cfg):
    params = [SEDAN if i % 3 else VAN for i in range(n)]
    roads = list(net.roads)
    routes = [Route(random_walk=True, start_road=roads[(5 * i) % len(roads)], start_s=10.0 + 15.0 * (i % 3))
              for i in range(n)]
    gens = np.random.default_rng(seed).spawn(n)
    return [Driver(config=cfg, params=par, route=rt, network=net, rng=g) for par, rt, g in
            zip(params, routes, gens, strict=True)], params


@pytest.mark.parametrize("rate_hz", [40, 20])
def test_compiled_fleet_drives_the_python_drivers_trajectories_to_the_last_bit(client, rate_hz):
    """14 cars on random walks over a 4 x 4 grid for 40 s: stops, dwells, turns, cruise changes and car following.
    Every physics tick's position, heading and speed equal the Python drivers' bit for bit, the events too; most
    driver steps run compiled."""
    net = grid_network(4, 100.0)
    cfg = DriverConfig(rate_hz=rate_hz, cruise_change_period=8.0)
    n, seconds = 14, 40.0
    ref_drivers, params = _drivers(net, n, 7, cfg)
    ref, ref_events, ref_located = _reference(client, ref_drivers, params, seconds)
    drivers, _ = _drivers(net, n, 7, cfg)
    fleet = TrafficFleet(client, drivers, params, [f"t{i}" for i in range(n)], 240)
    events = []
    for tick in range(1, int(seconds * 240) + 1):
        fleet.advance(tick, OtherCars.none())
        events += fleet.pop_events()
        now, _ = fleet.readings(tick)
        got = np.column_stack([now[:, R_X], now[:, R_Y], now[:, R_YAWREAD], now[:, R_VFWD]])
        assert np.array_equal(got, ref[tick - 1]), f"tick {tick}: max diff {np.abs(got - ref[tick - 1]).max()}"
        if tick in ref_located:  # the compiled road positions are the drivers' own
            ids, s_on, lateral, stopped = fleet.road_positions(tick)
            where, stands = ref_located[tick]
            assert ids == [w[0] for w in where] and stopped.tolist() == stands
            assert np.array_equal(s_on, [w[1] for w in where]) and np.array_equal(lateral, [w[2] for w in where])
    assert [e["type"] for e in ref_events].count("car_stop") >= 10  # the walk exercised the rare steps
    key = lambda e: (e["tick"], e["car"], e["type"])  # noqa: E731 - the order within a tick is per car
    assert sorted(events, key=key) == sorted(ref_events, key=key)
    assert fleet.compiled_steps > 10 * fleet.python_steps
    # the run left some cars following others: the leader search was exercised, not only free driving
    assert any(d.command.accel < 0 for d in ref_drivers) or ref[-1, :, 3].min() < 1.0


def _compiled_leader(fleet: TrafficFleet, others_xy: np.ndarray) -> np.ndarray:
    """The compiled leader (gap, speed, index) of the fleet's one car among still cars at ``others_xy``."""
    X = np.ascontiguousarray(fleet.buf[:, fleet.every])
    ox = np.column_stack([others_xy, np.zeros(len(others_xy)), np.full(len(others_xy), 5.0)])
    flag, leader, off = np.zeros(1, dtype=np.bool_), np.zeros((1, 3)), fleet.off_road.copy()
    drive_all(fleet.every, X, ox, np.full(len(others_xy), SEDAN.length), fleet.P_xy, fleet.P_t, fleet.P_seg,
              fleet.P_s, fleet.P_head, fleet.P_kappa, fleet.P_cap, fleet.P_ridx, fleet.P_corner, fleet.P_lanew,
              fleet.P_laneoff, fleet.P_n, fleet.R_code, fleet.R_width, fleet.J_s, fleet.J_flag, fleet.J_n,
              fleet.ends_route, fleet.proj.copy(), fleet.last_code, fleet.mode, fleet.release_tick,
              fleet.next_cruise, fleet.cfg, 2.0, np.zeros((1, 3)), flag, leader, off)
    return leader[0]


def test_the_leader_search_passes_over_only_cars_provably_beside_the_path(client):
    """Cars scattered around a car's lane path through a turn: beside it, on it, and on the extension of the last
    segment the search looks at (where a car far from the path can still lie within half a lane of that segment's
    line). The compiled search, which passes over cars it can prove lie beside the path without projecting them, finds
    find_leaders' leader every time."""
    net = grid_network(3, 100.0)
    rng = np.random.default_rng(4)
    found = 0
    for trial in range(60):
        cfg = DriverConfig(rate_hz=20)
        route = Route(roads=("h0_0.f", "v1_0.f", "h1_1.f"), start_s=float(rng.uniform(5.0, 90.0)))  # a left turn
        drv = Driver(config=cfg, params=SEDAN, route=route, network=net, rng=np.random.default_rng(trial))
        fleet = TrafficFleet(client, [drv], [SEDAN], ["t0"], 240)
        car = fleet.buf[0, fleet.every]
        path = drv.path
        own = path.project(np.array([car[R_X], car[R_Y]]))
        half_window = int(cfg.follow_range / (2 * cfg.path_ds)) + 2
        end = min(len(path.s) - 1, own.index + 2 * half_window + 2)  # the last point the search looks at
        tangent = path.xy[end] - path.xy[end - 1]
        tangent /= np.linalg.norm(tangent)
        k = rng.integers(0, len(path.s), 40)
        beside = path.xy[k] + rng.normal(0.0, 6.0, (40, 2))
        beyond = path.xy[end] + np.outer(rng.uniform(0.5, 30.0, 10), tangent) + rng.normal(0.0, 0.8, (10, 2))
        others = np.vstack([beside, beyond])[rng.permutation(50)[: int(rng.integers(1, 50))]]
        got = _compiled_leader(fleet, others)
        xy = np.vstack([[car[R_X], car[R_Y]], others])
        want = find_leaders([drv] + [drv] * len(others), xy, np.r_[car[R_YAWREAD], np.zeros(len(others))],
                            np.r_[car[R_VFWD], np.full(len(others), 5.0)], [SEDAN.length] * len(xy), followers=[0])[0]
        if want is None:
            assert got[2] < 0, trial
        else:
            found += 1
            assert (got[0], got[1], int(got[2])) == (want.gap, want.speed, want.index), trial
    assert 10 < found < 60  # both outcomes exercised


def _queue_fleet(client, dynamics):
    """Two cars on one straight road, the front one stopping for 30 s at the junction 1_0; 20 m behind, the other."""
    net = grid_network(3, 120.0)
    front = Route(roads=("h0_0.f", "h1_0.f"), start_s=30.0, stops=("1_0",))
    back = Route(roads=("h0_0.f", "h1_0.f"), start_s=5.0, stops=())
    cfg = DriverConfig(cruise_fraction_range=(1.0, 1.0), cruise_change_period=0.0, dwell_range=(30.0, 30.0))
    return CarFleet(client, [SEDAN, SEDAN], [cfg, cfg], [front, back], net, 240, np.random.default_rng(1),
                    dynamics=dynamics)


@pytest.mark.parametrize("dynamics", [("physics", "kinematic"), ("kinematic", "physics")])
def test_car_following_sees_physics_and_kinematic_cars_both_ways(client, dynamics):
    """A car behind a car stopped at a junction stops behind it at the IDM+ standstill gap (s0 = 2 m), whichever of
    the two is the physics car and which the compiled kinematic one."""
    fleet = _queue_fleet(client, list(dynamics))
    for tick in range(1, 240 * 25 + 1):
        fleet.apply_actuation()
        p.stepSimulation(physicsClientId=client)
        fleet.after_step(tick)
    st = fleet.state
    assert st.stopped[0] and abs(st.speed[1]) < 0.05
    gap = float(np.linalg.norm(st.p_W[0, :2] - st.p_W[1, :2])) - SEDAN.length
    assert 1.0 < gap < 3.5  # s0 = 2 m; without car following the back car would have driven through the front one


def test_boxes_are_where_the_cars_are_whenever_a_sensor_looks(monkeypatch, tmp_path):
    """road_standoff_traffic, 6 s: at every radar scan each car's box (the body the radar's truth names) is exactly
    where the ground truth puts the car; between scans most boxes are left where they were (placed lazily)."""
    from autonomy.sensing.radar import Radar
    from simulator.api import run

    seen = {"scans": 0, "stale_between": 0}
    original = Radar.measure

    def checked(self, t, pose, truth, scene, rng):
        cars = [k for k, kind in enumerate(truth.kind) if kind == "car"]
        for k in cars:
            pos, q = p.getBasePositionAndOrientation(int(truth.seg_ids[k]), physicsClientId=scene.client_id)
            assert np.array_equal(pos, truth.p_W[k]), f"car {k} box at {pos}, the car at {truth.p_W[k]} (t={t})"
            assert math.isclose(2 * math.atan2(q[2], q[3]), truth.yaw[k], abs_tol=1e-9) or abs(
                abs(2 * math.atan2(q[2], q[3]) - truth.yaw[k]) - 2 * math.pi) < 1e-9
        seen["scans"] += 1
        return original(self, t, pose, truth, scene, rng)

    from vehicles.car.traffic_fleet import TrafficFleet as Fleet
    advance = Fleet.advance

    def counting(self, tick, others):
        if tick % 240 == 120:  # half-way between two radar scans (2 Hz): boxes left where the last scan put them
            rows = self._rows(tick)
            seen["stale_between"] += int(np.sum(np.hypot(rows[:, R_X] - self._box_xy[:, 0],
                                                         rows[:, R_Y] - self._box_xy[:, 1]) > 0.5))
        advance(self, tick, others)

    monkeypatch.setattr(Radar, "measure", checked)
    monkeypatch.setattr(Fleet, "advance", counting)
    res = run("road_standoff_traffic", duration=6.0, seed=2, out_dir=tmp_path / "run")
    assert res.status == "completed"
    assert seen["scans"] >= 2 * 2 * 6 - 2  # two radars at 2 Hz
    assert seen["stale_between"] > 10  # moving cars' boxes lag between scans: the scans' exactness is the sync's


def test_a_fleet_refuses_mixed_rates_and_an_out_of_period_tick(client):
    net = grid_network(3, 120.0)
    d40, par = _drivers(net, 1, 0, DriverConfig(rate_hz=40))
    d20, _ = _drivers(net, 1, 1, DriverConfig(rate_hz=20))
    with pytest.raises(ValueError, match=r"one rate; the drivers ask for \[20, 40\] Hz"):
        TrafficFleet(client, d40 + d20, par * 2, ["a", "b"], 240)
    fleet = TrafficFleet(client, d40, par, ["a"], 240)
    with pytest.raises(ValueError, match=r"tick 7 is outside the fleet's period \[0, 6\]"):
        fleet.poses(7)
    with pytest.raises(RuntimeError, match="tick 12 is not the fleet's next step"):
        fleet.advance(12, OtherCars.none())


@pytest.mark.parametrize("watched", [True, False])
def test_boxes_near_a_watched_point_follow_their_cars_every_step_so_contacts_see_them(client, watched):
    """A ball resting on the lane ahead of a kinematic car: with the ball's position among the fleet's watched points
    (as the run loop watches the UAVs) the car's box is placed before every physics step near it and the step's
    contacts meet it; unwatched, the box stays where it was last placed and the car passes through."""
    net = grid_network(3, 120.0)
    cfg = DriverConfig(cruise_fraction_range=(1.0, 1.0), cruise_change_period=0.0, stop_probability=0.0)
    fleet = CarFleet(client, [SEDAN], [cfg], [Route(roads=("h0_0.f", "h1_0.f"), start_s=5.0)], net, 240,
                     np.random.default_rng(0), dynamics=["kinematic"])
    lane = net.roads["h0_0.f"]
    spot = lane.point(60.0, lane.lane_offset(0))
    r = 0.3
    ball = p.createMultiBody(1.0, p.createCollisionShape(p.GEOM_SPHERE, radius=r, physicsClientId=client),
                             basePosition=[float(spot[0]), float(spot[1]), r], physicsClientId=client)
    if watched:
        fleet.near_points = lambda: np.array([p.getBasePositionAndOrientation(ball, physicsClientId=client)[0]])
    touched = False
    for tick in range(1, 240 * 12 + 1):
        fleet.apply_actuation()
        p.stepSimulation(physicsClientId=client)
        fleet.after_step(tick)
        touched |= bool(p.getContactPoints(bodyA=ball, bodyB=int(fleet.body_ids[0]), physicsClientId=client))
    assert float(np.linalg.norm(fleet.state.p_W[0, :2] - spot)) > 20.0  # the car drove past the spot
    assert touched == watched


@pytest.mark.parametrize("above_top_m, placed", [(SYNC_RADIUS - 0.5, True), (SYNC_RADIUS + 0.5, False)])
def test_a_watched_point_high_above_every_box_places_none(client, above_top_m, placed):
    """A point straight above a kinematic car (as a UAV flying over it): below ``SYNC_RADIUS`` over the box's top the
    box follows the car every step, higher up it is out of any contact's reach and stays where it was placed."""
    net = grid_network(3, 120.0)
    cfg = DriverConfig(cruise_fraction_range=(1.0, 1.0), cruise_change_period=0.0, stop_probability=0.0)
    fleet = CarFleet(client, [SEDAN], [cfg], [Route(roads=("h0_0.f", "h1_0.f"), start_s=5.0)], net, 240,
                     np.random.default_rng(0), dynamics=["kinematic"])
    body = int(fleet.body_ids[0])
    base = p.getBasePositionAndOrientation(body, physicsClientId=client)[0][2]
    top = p.getAABB(body, physicsClientId=client)[1][2]
    assert top - base == pytest.approx(SEDAN.height - SEDAN.cog_height, abs=1e-3)  # the box's roof above its centre
    spawn = np.array(p.getBasePositionAndOrientation(body, physicsClientId=client)[0][:2])
    fleet.near_points = lambda: np.append(fleet.state.p_W[0, :2], top + above_top_m)[None, :]
    for tick in range(1, 240 * 5 + 1):
        fleet.apply_actuation()
        p.stepSimulation(physicsClientId=client)
        fleet.after_step(tick)
    box = np.array(p.getBasePositionAndOrientation(body, physicsClientId=client)[0][:2])
    car = fleet.state.p_W[0, :2]
    assert float(np.linalg.norm(car - spawn)) > 5.0  # the car drove on
    if placed:  # placed before the last step at the pose of that tick: one tick's travel behind at most
        assert float(np.linalg.norm(box - car)) < 0.2
    else:
        assert np.array_equal(box, spawn)
