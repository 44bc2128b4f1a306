"""The kinematic car: its bicycle model against closed form, its box where its state says, and its drive against the
physics car's on the same route. (Lane keeping, stops and car following of both dynamics: ``test_car_physics.py``.)"""

import math

import numpy as np
import pybullet as p
import pytest

from car_fixtures import bullet_client, curvy_network, grid_network, run_fleet
from vehicles.car.driver_config import DriveCommand, DriverConfig
from vehicles.car.dynamics import KinematicDynamics
from vehicles.car.fleet import CarFleet
from vehicles.car.params import load_car
from vehicles.car.route import Route

SEDAN, VAN = load_car("sedan"), load_car("van")


@pytest.fixture
def client():
    c = bullet_client(240)
    yield c
    p.disconnect(c)


def _unit(yaw: float) -> tuple[np.ndarray, np.ndarray]:
    """(forward, left) unit vectors in the ground plane for heading ``yaw``."""
    return np.array([math.cos(yaw), math.sin(yaw), 0.0]), np.array([-math.sin(yaw), math.cos(yaw), 0.0])


@pytest.mark.parametrize("delta", [0.3, -0.15])
def test_constant_command_drives_the_closed_form_circle(client, delta):
    """Steady turn: yaw rate v cos(beta) tan(delta) / L, COM on a circle of radius L / (cos(beta) tan(delta)) moving
    along psi + beta, forward speed v cos(beta); the speed ramp is exact (constant acceleration)."""
    car = KinematicDynamics(client, SEDAN, np.array([5.0, -3.0]), 0.4, 240)
    for _ in range(3 * 240):  # 2 m/s^2 for 3 s
        car.actuate(DriveCommand(accel=2.0, steer=0.0))
    assert car.model.speed == pytest.approx(6.0, abs=1e-9)
    for _ in range(2 * 240):  # steering ramps at 0.6 rad/s, then holds
        car.actuate(DriveCommand(accel=0.0, steer=delta))
    v, beta = 6.0, math.atan(0.5 * math.tan(delta))
    omega = v * math.cos(beta) * math.tan(delta) / SEDAN.wheelbase
    radius = abs(SEDAN.wheelbase / (math.cos(beta) * math.tan(delta)))
    points, yaws = [], []
    for _ in range(int(2 * math.pi / abs(omega) * 240)):  # one lap
        car.actuate(DriveCommand(accel=0.0, steer=delta))
        row = car.state_row()
        p_W, v_W, w_z = np.array(row[0:3]), np.array(row[7:10]), row[12]
        assert np.linalg.norm(v_W) == pytest.approx(v, abs=1e-9)
        assert w_z == pytest.approx(omega, rel=1e-12)
        yaw = 2 * math.atan2(row[5], row[6])
        fwd, left = _unit(yaw)
        assert v_W @ fwd == pytest.approx(v * math.cos(beta), rel=1e-9)  # forward speed
        assert math.atan2(v_W @ left, v_W @ fwd) == pytest.approx(beta, abs=1e-9)  # slip angle
        points.append(p_W[:2])
        yaws.append(yaw)
        assert p_W[2] == pytest.approx(SEDAN.cog_height) and row[3:5] == (0.0, 0.0)
    # the positions lie on one circle (least-squares fit x^2 + y^2 = 2 a x + 2 b y + c) of the closed-form radius:
    # explicit Euler at 1/240 s puts them on the regular polygon with chords v dt turning by omega dt, inscribed in a
    # circle of radius v dt / (2 sin(omega dt / 2)), larger than v / omega by (omega dt)^2 / 24 relative (< 1e-6)
    xy = np.array(points)
    a, b, c = np.linalg.lstsq(np.c_[2 * xy, np.ones(len(xy))], (xy ** 2).sum(axis=1), rcond=None)[0]
    r = np.linalg.norm(xy - [a, b], axis=1)
    assert np.ptp(r) < 1e-9 * radius
    assert r.mean() / radius - 1.0 == pytest.approx((omega / 240) ** 2 / 24, rel=1e-3)
    assert np.all(np.abs(np.diff(np.unwrap(yaws)) - omega / 240) < 1e-12)


def test_box_is_where_the_state_says_and_rays_see_its_shape(client):
    cfg = DriverConfig(cruise_fraction_range=(1.0, 1.0), stop_probability=0.0)
    fleet = CarFleet(client, [SEDAN, VAN], [cfg, cfg],
                     [Route(roads=("curvy.f", "tail.f"), start_s=30.0), Route(roads=("curvy.f",))], curvy_network(),
                     240, np.random.default_rng(0), dynamics=["kinematic", "kinematic"])
    tick = 1
    for stop in (240, 240 * 8, 240 * 20):
        while tick <= stop:
            fleet.apply_actuation()
            p.stepSimulation(physicsClientId=client)
            fleet.after_step(tick)
            tick += 1
        st = fleet.state
        assert st.speed.min() > 1.0  # moving
        # the boxes move only when something looks (no UAV or physics car near them: none placed since the start)
        for i, body in enumerate(fleet.body_ids):
            pos, _ = p.getBasePositionAndOrientation(int(body), physicsClientId=client)
            assert np.linalg.norm(np.array(pos) - st.p_W[i]) > 0.1
        fleet.sync_scene()
        for i, (par, body) in enumerate(zip((SEDAN, VAN), fleet.body_ids, strict=True)):
            pos, q = p.getBasePositionAndOrientation(int(body), physicsClientId=client)
            assert np.array_equal(pos, st.p_W[i]) and np.allclose(q, st.q_WB[i], rtol=0, atol=1e-15)
            fwd, left = _unit(float(st.yaw[i]))
            c = st.p_W[i]
            # straight down just inside the roof's corners: the roof at the car's height
            starts, ends = [], []
            for a, b in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
                xy = c + a * (0.5 * par.length - 0.03) * fwd + b * (0.5 * par.width - 0.03) * left
                starts.append(xy + [0, 0, 10.0 - c[2]]), ends.append(xy - [0, 0, c[2] + 1.0])
            # ... and just outside its sides and ends: the ground
            for a, b in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                xy = c + a * (0.5 * par.length + 0.03) * fwd + b * (0.5 * par.width + 0.03) * left
                starts.append(xy + [0, 0, 10.0 - c[2]]), ends.append(xy - [0, 0, c[2] + 1.0])
            hits = p.rayTestBatch(starts, ends, physicsClientId=client)
            for h in hits[:4]:
                assert h[0] == body and h[3][2] == pytest.approx(par.height, abs=1e-3)
            for h in hits[4:]:
                assert h[0] != body and h[3][2] == pytest.approx(0.0, abs=1e-3)
            # from the side at the centre of mass: the side face, half a width from the centre
            side = p.rayTest((c + 5 * left).tolist(), c.tolist(), physicsClientId=client)[0]
            assert side[0] == body and np.linalg.norm(np.array(side[3]) - c) == pytest.approx(0.5 * par.width, abs=1e-3)


def test_a_falling_body_lands_on_the_box_and_does_not_move_it(client):
    """Contacts (what the run loop's collision check reads) see the box; the box, kinematic, is not pushed."""
    car = KinematicDynamics(client, VAN, np.array([0.0, 0.0]), 0.0, 240)
    r = 0.2
    ball = p.createMultiBody(1.0, p.createCollisionShape(p.GEOM_SPHERE, radius=r, physicsClientId=client),
                             basePosition=[0.5, 0.3, 4.0], physicsClientId=client)
    for _ in range(480):
        car.actuate(DriveCommand(accel=0.0, steer=0.0, hold=True))
        p.stepSimulation(physicsClientId=client)
    assert p.getContactPoints(bodyA=ball, bodyB=car.body_id, physicsClientId=client)
    assert p.getBasePositionAndOrientation(ball, physicsClientId=client)[0][2] == pytest.approx(VAN.height + r,
                                                                                                abs=0.01)
    assert car.state_row()[:7] == (0.0, 0.0, VAN.cog_height, 0.0, 0.0, 0.0, 1.0)


def test_a_box_moved_while_asleep_is_where_rays_and_contacts_find_it(client):
    """Car boxes sleep (Bullet leaves their bounding boxes alone between moves); placing one still moves what rays
    and contacts see at once: a ray at the old spot meets nothing, one at the new spot meets the roof, and a ball
    dropped there comes to rest on it."""
    from vehicles.car.box_body import CarBoxBody, yaw_quaternion

    box = CarBoxBody(client, VAN, np.array([0.0, 0.0]), 0.0)
    for _ in range(10):
        p.stepSimulation(physicsClientId=client)
    box.place(40.0, -7.0, yaw_quaternion(0.5))
    old, new = p.rayTestBatch([[0.0, 0.0, 10.0], [40.0, -7.0, 10.0]], [[0.0, 0.0, 0.5], [40.0, -7.0, 0.5]],
                              physicsClientId=client)
    assert old[0] != box.body_id
    assert new[0] == box.body_id and new[3][2] == pytest.approx(VAN.height, abs=1e-3)
    r = 0.2
    ball = p.createMultiBody(1.0, p.createCollisionShape(p.GEOM_SPHERE, radius=r, physicsClientId=client),
                             basePosition=[40.0, -7.0, 4.0], physicsClientId=client)
    for _ in range(480):
        p.stepSimulation(physicsClientId=client)
    assert p.getContactPoints(bodyA=ball, bodyB=box.body_id, physicsClientId=client)
    assert p.getBasePositionAndOrientation(ball, physicsClientId=client)[0][2] == pytest.approx(VAN.height + r,
                                                                                                abs=0.01)


def _travelled(p_xy: np.ndarray) -> np.ndarray:
    return np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p_xy, axis=0), axis=1))]


def test_kinematic_car_drives_a_route_like_the_physics_car():
    """Same route (three turns, two stops, 500 m), driver and seed: the kinematic car's path lies within 0.15 m of the
    physics car's, its speed at equal distance driven within 0.3 m/s (95 %) / 0.6 m/s (max) of it, and it passes
    the same events within 0.25 s and stops within 0.3 m of where the physics car stops. (Measured: 0.06 m,
    0.22 / 0.39 m/s, 0.1 s, < 0.1 m: the physics car lags its speed reference by about 0.05 m/s.)"""
    net = grid_network(3, 120.0)
    route = Route(roads=("h0_0.f", "h1_0.f", "v2_0.f", "h1_1.r", "v1_1.f"), stops=("1_0", "1_1"))
    cfg = DriverConfig(cruise_fraction_range=(1.0, 1.0), cruise_change_period=0.0, dwell_range=(3.0, 3.0))
    runs = {}
    for dyn in ("physics", "kinematic"):
        c = bullet_client(240)
        fleet = CarFleet(c, [SEDAN], [cfg], [route], net, 240, np.random.default_rng(4), dynamics=[dyn])
        runs[dyn] = run_fleet(fleet, c, 72.0, stride=1)
        p.disconnect(c)
    phys, kin = runs["physics"], runs["kinematic"]
    xy_p, xy_k = phys.p_W[:, 0, :2], kin.p_W[:, 0, :2]
    s_p, s_k = _travelled(xy_p), _travelled(xy_k)
    assert s_p[-1] > 480.0 and s_k[-1] > 480.0
    # path: distance of each kinematic position (over the stretch both drove) from the physics polyline
    from scipy.spatial import cKDTree

    common = s_k <= s_p[-1] - 1.0
    dev, _ = cKDTree(xy_p).query(xy_k[common])
    assert dev.max() < 0.15
    # speed profile over distance driven (moving samples; the stops are compared below)
    moving = common & (kin.speed[:, 0] > 0.5)
    dv = np.abs(np.interp(s_k[moving], s_p, phys.speed[:, 0]) - kin.speed[moving, 0])
    assert np.percentile(dv, 95) < 0.3 and dv.max() < 0.6
    # the same events in the same order, at nearly the same times; the stops at the same places
    assert [(e["type"], e.get("road")) for e in kin.events] == [(e["type"], e.get("road")) for e in phys.events]
    assert len([e for e in kin.events if e["type"] == "car_stop"]) == 2
    for ek, ep in zip(kin.events, phys.events, strict=True):
        assert abs(ek["tick"] - ep["tick"]) / 240 < 0.25
        if ek["type"] == "car_stop":
            assert np.linalg.norm(xy_k[ek["tick"] - 1] - xy_p[ep["tick"] - 1]) < 0.3
