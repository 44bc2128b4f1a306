"""SUMO co-simulation as a traffic source: shared geometry, determinism, interpolation, lazy scene sync, slots, the
physics car seen by SUMO's car following, and the refusal when SUMO is missing or already running."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from vehicles.car.box_body import yaw_quaternion
from vehicles.car.traffic_source import OtherCars
from vehicles.sumo._runtime import sumo_available
from vehicles.sumo.source import SumoTrafficConfig, make_sumo_traffic
from worlds.roads.network import RoadNetwork

needs_sumo = pytest.mark.skipif(not sumo_available(), reason="SUMO is not installed (pip install 'skytrack[traffic]')")

PHYSICS_HZ = 240
RATE_HZ = 10
PERIOD = PHYSICS_HZ // RATE_HZ
LANE_TOL = 0.01  # m; distance of a slot's centre of mass from its lane's centre-line, outside junctions
JUNCTION_CLEAR = 10.0  # m; slots this close to a junction node are inside or turning through it (not checked)


def _grid(n: int = 4, spacing: float = 150.0) -> RoadNetwork:
    nodes = {f"{i}_{j}": [i * spacing, j * spacing] for i in range(n) for j in range(n)}
    streets = [{"id": f"h{i}_{j}", "nodes": [f"{i}_{j}", f"{i + 1}_{j}"]} for i in range(n - 1) for j in range(n)]
    streets += [{"id": f"v{i}_{j}", "nodes": [f"{i}_{j}", f"{i}_{j + 1}"]} for i in range(n) for j in range(n - 1)]
    return RoadNetwork.from_spec({"nodes": nodes, "streets": streets})


@pytest.fixture(scope="module")
def work_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("sumo_work")


@pytest.fixture
def client():
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(physicsClientId=cid)


def _traffic(net, client, work_dir, seed=7, n_vehicles=20, n_slots=24, **kw):
    return make_sumo_traffic(net, n_vehicles=n_vehicles, n_slots=n_slots, rate_hz=RATE_HZ, physics_hz=PHYSICS_HZ,
                             client_id=client, rng=np.random.default_rng(seed), work_dir=work_dir, **kw)


def _record(seed: int, seconds: float, work_dir, roads: bool = True) -> tuple[list, list, RoadNetwork]:
    """Poses (and road positions) at every SUMO step of one run, its events, and its network."""
    net, cid = _grid(), p.connect(p.DIRECT)
    tr = _traffic(net, cid, work_dir, seed=seed)
    try:
        out, events = [tr.poses(0)], []
        for tick in range(1, int(seconds * PHYSICS_HZ) + 1):
            tr.advance(tick, OtherCars.none())
            if tick % PERIOD == 0:
                out.append((tr.poses(tick), tr.road_positions(tick) if roads else None))
            events += tr.pop_events()
        return out[1:], events, net
    finally:
        tr.close()
        p.disconnect(physicsClientId=cid)


@pytest.fixture(scope="module")
def recorded(work_dir):
    return _record(7, 60.0, work_dir)


@needs_sumo
def test_vehicles_stay_on_skytrack_lane_centres(recorded) -> None:
    steps, _, net = recorded
    nodes = np.array(list(net.nodes.values()))
    checked, worst = 0, 0.0
    for ps, (roads, s, lat, _) in steps:
        for k in np.flatnonzero(ps.active):
            road = net.roads[roads[k]]
            assert 0.0 <= s[k] <= road.length
            if np.min(np.hypot(*(nodes - ps.xy[k]).T)) < JUNCTION_CLEAR:
                continue
            off = min(abs(lat[k] - road.lane_offset(i)) for i in range(road.lanes))
            worst = max(worst, off)
            checked += 1
    assert checked > 5000  # 20 cars x 600 steps, less those near junctions
    assert worst < LANE_TOL


@needs_sumo
def test_vehicles_kept_on_the_road_and_slots_change_hands(recorded) -> None:
    steps, events, _ = recorded
    on_road = np.array([ps.active.sum() for ps, _ in steps])
    assert on_road.max() <= 20 and np.median(on_road) >= 18
    kinds = {e["type"] for e in events}
    assert kinds == {"traffic_depart", "traffic_arrive"}
    assert sum(e["type"] == "traffic_arrive" for e in events) > 5  # trips end and are replaced
    by_tick = {ps.tick: ps for ps, _ in steps}
    for e in events:
        assert set(e) == {"type", "car", "slot", "tick", "vehicle"} and e["car"] == e["slot"]
        if e["tick"] in by_tick:
            assert by_tick[e["tick"]].active[e["slot"]] == (e["type"] == "traffic_depart") or \
                any(f["slot"] == e["slot"] and f["tick"] == e["tick"] and f is not e for f in events)


@needs_sumo
def test_one_seed_one_run_bit_for_bit(recorded, work_dir) -> None:
    again, _, _ = _record(7, 30.0, work_dir, roads=False)
    other, _, _ = _record(8, 30.0, work_dir, roads=False)
    first = recorded[0][:len(again)]
    for (a, _), (b, _) in zip(first, again, strict=True):
        for f in ("xy", "yaw", "speed", "active"):
            assert np.array_equal(getattr(a, f), getattr(b, f)), (a.tick, f)
    assert any(not np.array_equal(a.xy, c.xy) for (a, _), (c, _) in zip(first, other, strict=True))


@needs_sumo
def test_poses_interpolate_between_sumo_steps(client, work_dir) -> None:
    with _traffic(_grid(), client, work_dir) as tr:
        for tick in range(1, 10 * PERIOD + 1):
            tr.advance(tick, OtherCars.none())
        t0 = 10 * PERIOD
        a = tr.poses(t0)
        b = tr.poses(t0 + PERIOD)
        m = tr.poses(t0 + PERIOD // 2)
        q = tr.poses(t0 + PERIOD // 4)
        both = a.active & b.active
        moving = both & (a.speed > 1.0)
        assert moving.sum() >= 10
        assert np.allclose(m.xy[both], 0.5 * (a.xy[both] + b.xy[both]), rtol=0, atol=1e-9)
        assert np.allclose(q.xy[both], 0.75 * a.xy[both] + 0.25 * b.xy[both], rtol=0, atol=1e-9)
        assert np.allclose(m.speed[both], 0.5 * (a.speed[both] + b.speed[both]), rtol=0, atol=1e-12)
        assert np.all(np.hypot(*(m.xy[moving] - a.xy[moving]).T) > 0.04)  # really between, not held
        dyaw = np.angle(np.exp(1j * (b.yaw - a.yaw)))
        assert np.allclose(np.angle(np.exp(1j * (m.yaw - a.yaw)))[both], 0.5 * dyaw[both], atol=1e-12)
        assert np.allclose(m.v_xy[both], m.speed[both, None] * np.c_[np.cos(m.yaw), np.sin(m.yaw)][both])
        # the acceleration is the derivative of those velocities: the central difference over two physics ticks
        lo, hi = tr.poses(t0 + PERIOD // 2 - 1), tr.poses(t0 + PERIOD // 2 + 1)
        central = (hi.v_xy - lo.v_xy) * PHYSICS_HZ / 2.0
        assert np.allclose(m.a_xy[both], central[both], rtol=0, atol=1e-3)
        along = np.sum(m.a_xy * np.c_[np.cos(m.yaw), np.sin(m.yaw)], axis=1)
        assert np.allclose(along[both], ((b.speed - a.speed) * RATE_HZ)[both], rtol=0, atol=1e-9)
        assert np.any(np.abs(along[both]) > 0.1) and np.all(m.a_xy[~m.active] == 0.0)
        with pytest.raises(ValueError, match=rf"poses\({t0 + 2 * PERIOD}\): SUMO's states cover ticks "
                                             rf"{t0}..{t0 + PERIOD}; advance\(\) it first"):
            tr.poses(t0 + 2 * PERIOD)


@needs_sumo
def test_sync_places_bodies_exactly_and_parks_inactive_slots(client, work_dir) -> None:
    with _traffic(_grid(), client, work_dir, n_vehicles=10, n_slots=16) as tr:
        for tick in range(1, 5 * PERIOD + 1):
            tr.advance(tick, OtherCars.none())
        tick = 5 * PERIOD + 7
        ps = tr.poses(tick)
        assert ps.active.sum() == 10 and not ps.active[10:].any()
        far = int(np.argmax(np.hypot(*(ps.xy[:10] - ps.xy[0]).T)))
        before = p.getBasePositionAndOrientation(int(tr.body_ids[far]), physicsClientId=client)[0]
        tr.sync_near(tick, ps.xy[:1], 1.0)
        pos0, q0 = p.getBasePositionAndOrientation(int(tr.body_ids[0]), physicsClientId=client)
        assert pos0 == (ps.xy[0, 0], ps.xy[0, 1], tr.ground_z[0])
        assert abs(np.dot(q0, yaw_quaternion(float(ps.yaw[0])))) == pytest.approx(1.0, abs=1e-12)
        assert p.getBasePositionAndOrientation(int(tr.body_ids[far]), physicsClientId=client)[0] == before
        tr.sync_scene(tick)
        for k in range(16):
            pos, q = p.getBasePositionAndOrientation(int(tr.body_ids[k]), physicsClientId=client)
            if ps.active[k]:
                assert pos == (ps.xy[k, 0], ps.xy[k, 1], tr.ground_z[k])
                assert abs(np.dot(q, yaw_quaternion(float(ps.yaw[k])))) == pytest.approx(1.0, abs=1e-12)
            else:
                assert pos[2] == -50.0
        assert tr.ground_z[0] == pytest.approx(0.55) and tr.lengths[0] == pytest.approx(4.77)


@needs_sumo
def test_sync_near_places_exactly_the_bodies_near_the_points(client, work_dir) -> None:
    """Before the poses of a tick are asked (as before a physics step), sync_near poses only the slots whose step
    can bring them near the points; the bodies it places are where poses() then says, it places every active slot
    within the radius at every tick of four SUMO steps, and leaves the bodies far from the points where they were,
    also when the points move on (the candidates are found again when a point has moved 10 m)."""
    with _traffic(_grid(), client, work_dir, n_vehicles=20, n_slots=24) as tr:
        for tick in range(1, 4 * PERIOD + 1):
            tr.advance(tick, OtherCars.none())
        placed = left = extra = 0
        for tick in range(4 * PERIOD + 1, 8 * PERIOD + 1):
            tr.advance(tick, OtherCars.none())
            before = [p.getBasePositionAndOrientation(int(b), physicsClientId=client) for b in tr.body_ids]
            ref = tr._slots.poses(tick, (tick - tr._t_prev) / PERIOD, 1.0 / RATE_HZ)  # not through the cache
            pts = ref.xy[[0, 5]] + [10.0, 0.0] + [1.5 * (tick - 4 * PERIOD), 0.0]  # the points fly on east
            tr.sync_near(tick, pts, 40.0)
            ps = tr.poses(tick)
            np.testing.assert_array_equal(ps.xy, ref.xy)
            some = np.flatnonzero(ps.active)[::3]  # a pose's position and heading alone, as sync_near reads them
            xy, yaw = tr._slots.positions((tick - tr._t_prev) / PERIOD, some)
            np.testing.assert_array_equal(xy, ref.xy[some])
            np.testing.assert_array_equal(yaw, ref.yaw[some])
            near = ps.active & (((ps.xy[:, None, :] - pts[None]) ** 2).sum(axis=2).min(axis=1) <= 40.0 ** 2)
            for k, b in enumerate(tr.body_ids):
                pos, q = p.getBasePositionAndOrientation(int(b), physicsClientId=client)
                moved = (pos, q) != before[k]
                if near[k] or moved:  # every one near, and any other placed is placed exactly too
                    assert ps.active[k] and pos == (ps.xy[k, 0], ps.xy[k, 1], tr.ground_z[k])
                    assert abs(np.dot(q, yaw_quaternion(float(ps.yaw[k])))) == pytest.approx(1.0, abs=1e-12)
                    placed += near[k]
                    extra += moved and not near[k]
                if ps.active[k] and (((ps.xy[k] - pts) ** 2).sum(axis=1).min() > (40.0 + 10.0 + 2 * 20.0) ** 2):
                    assert (pos, q) == before[k]  # beyond radius, margin and two steps' moves: never placed
                    left += 1
        assert placed > 4 * PERIOD and left > 4 * PERIOD and extra < placed


@needs_sumo
def test_physics_car_stopped_in_lane_stops_the_traffic_behind(client, work_dir) -> None:
    net = RoadNetwork.from_spec({"nodes": {"a": [0, 0], "b": [1000, 0]},
                                 "streets": [{"id": "s", "nodes": ["a", "b"]}]})
    car = OtherCars(xy=np.array([[500.0, -1.75]]), yaw=np.zeros(1), speed=np.zeros(1), length=np.array([4.77]))
    rear = 500.0 - 0.5 * 4.77
    with _traffic(net, client, work_dir, seed=3, n_vehicles=10, n_slots=10) as tr:
        seen_behind: set[str] = set()
        for tick in range(1, 90 * PHYSICS_HZ + 1):
            tr.advance(tick, car)
            if tick % PERIOD:
                continue
            ps = tr.poses(tick)
            roads = tr.road_positions(tick)[0]
            for k in np.flatnonzero(ps.active):
                if roads[k] != "s.f":
                    continue
                vid, front = tr._slots.vehicle[k], ps.xy[k, 0] + 0.5 * tr.lengths[k]
                if front < rear:
                    seen_behind.add(vid)
                else:
                    assert vid not in seen_behind, f"{vid} drove through the stopped physics car"
        ps, (roads, _, _, stopped) = tr.poses(tick), tr.road_positions(tick)
        queue = [k for k in np.flatnonzero(ps.active) if roads[k] == "s.f" and ps.xy[k, 0] < 500.0]
        first = max(queue, key=lambda k: ps.xy[k, 0])
        gap = rear - (ps.xy[first, 0] + 0.5 * tr.lengths[first])
        assert stopped[first] and 0.0 < gap < 5.0  # SUMO's 2.5 m minimum gap
        assert len(seen_behind) >= 3


@needs_sumo
def test_physics_cars_are_remote_controlled_copies_that_come_and_go(client, work_dir) -> None:
    net = RoadNetwork.from_spec({"nodes": {"a": [0, 0], "b": [1000, 0]},
                                 "streets": [{"id": "s", "nodes": ["a", "b"]}]})
    with _traffic(net, client, work_dir, seed=4, n_vehicles=2, n_slots=2) as tr:
        lib = tr._lib
        for tick in range(1, 5 * PERIOD + 1):
            x = 100.0 + 10.0 * tick / PHYSICS_HZ  # 10 m/s along s.f's lane, and a second car parked on s.r's
            cars = OtherCars(xy=np.array([[x, -1.75], [300.0, 1.75]]), yaw=np.array([0.0, np.pi]),
                             speed=np.array([10.0, 0.0]), length=np.array([4.77, 6.0]))
            tr.advance(tick, cars)
        ids = sorted(v for v in lib.vehicle.getIDList() if v.startswith("skytrack_physics_"))
        assert ids == ["skytrack_physics_0", "skytrack_physics_1"]
        # at SUMO's time for tick 6 * PERIOD: the front bumper where the car will be then, at its speed
        x_next = 100.0 + 10.0 * 6 * PERIOD / PHYSICS_HZ + 0.5 * 4.77
        assert lib.vehicle.getPosition("skytrack_physics_0") == pytest.approx((x_next, -1.75), abs=1e-6)
        assert lib.vehicle.getSpeed("skytrack_physics_0") == pytest.approx(10.0, abs=1e-6)
        assert lib.vehicle.getRoadID("skytrack_physics_1") == "s.r"
        assert lib.vehicle.getLength("skytrack_physics_1") == 6.0
        assert not any(vid.startswith("skytrack_physics_") for vid in tr._slots.vehicle)  # never a slot
        tr.advance(6 * PERIOD, OtherCars(xy=cars.xy[:1], yaw=cars.yaw[:1], speed=cars.speed[:1],
                                         length=cars.length[:1]))
        assert sorted(v for v in lib.vehicle.getIDList() if v.startswith("skytrack_physics_")) == [
            "skytrack_physics_0"]


@needs_sumo
def test_one_simulation_per_process(client, work_dir) -> None:
    net = _grid(3)
    tr = _traffic(net, client, work_dir, n_vehicles=2, n_slots=2)
    try:
        with pytest.raises(RuntimeError, match=r"^a SUMO traffic simulation is already running in this process "
                                               r"\(libsumo holds one\); close\(\) it before starting another$"):
            _traffic(net, client, work_dir, n_vehicles=2, n_slots=2)
    finally:
        tr.close()
    tr.close()  # idempotent
    with pytest.raises(RuntimeError, match="this SUMO traffic source is closed"):
        tr.advance(PERIOD, OtherCars.none())
    with _traffic(net, client, work_dir, n_vehicles=2, n_slots=2) as again:
        again.advance(PERIOD, OtherCars.none())


def test_missing_sumo_is_refused_with_an_install_hint(monkeypatch) -> None:
    import sys

    from vehicles.sumo._runtime import SumoUnavailable
    from vehicles.sumo.source import SumoTraffic

    monkeypatch.setitem(sys.modules, "libsumo", None)
    assert not sumo_available()
    with pytest.raises(SumoUnavailable) as err:
        SumoTraffic(_grid(2), SumoTrafficConfig(n_vehicles=1, n_slots=1), client_id=0, seed=1,
                    rng=np.random.default_rng(0), work_dir="unused")
    assert str(err.value) == ("SUMO traffic needs the libsumo package, which is not installed; install it with: "
                              "pip install 'skytrack[traffic]'")
    assert isinstance(err.value, ImportError)
    monkeypatch.setitem(sys.modules, "sumo", None)
    with pytest.raises(SumoUnavailable, match=r"^SUMO traffic needs the eclipse-sumo package, which is not installed; "
                                              r"install it with: pip install 'skytrack\[traffic\]'$"):
        make_sumo_traffic(_grid(2), n_vehicles=1, client_id=0, rng=np.random.default_rng(0), work_dir="unused")


def test_config_checks() -> None:
    with pytest.raises(ValueError, match=r"SumoTrafficConfig.rate_hz 7 Hz must divide physics_hz 240 Hz"):
        SumoTrafficConfig(n_vehicles=1, n_slots=1, rate_hz=7, physics_hz=240)
    with pytest.raises(ValueError, match=r"SumoTrafficConfig.n_slots must be >= n_vehicles \(5\) and >= 1, got 4"):
        SumoTrafficConfig(n_vehicles=5, n_slots=4)
    assert SumoTrafficConfig(n_vehicles=1, n_slots=1, rate_hz=20, physics_hz=240).period == 12


@needs_sumo
def test_flows_depart_as_poisson_processes_along_their_route(client, work_dir) -> None:
    """Flow 0 sends 1200 vehicles/h (Poisson) from h0_0.f to h2_3.f over 120 s, flow 1 2400/h within [30, 60) s (a
    lane takes some 1800/h): departure counts within the 99.9 % Poisson bands of means 40 and 20, every vehicle
    departs (a few may still wait to enter at the end) and is first seen on its flow's origin."""
    from vehicles.sumo.demand import DemandConfig, Flow

    flows = (Flow(origin="h0_0.f", destination="h2_3.f", per_hour=1200.0),
             Flow(origin="v3_0.f", destination="h0_3.r", per_hour=2400.0, begin_s=30.0, end_s=60.0))
    net = _grid()
    tr = _traffic(net, client, work_dir, n_vehicles=0, n_slots=300, demand=DemandConfig(flows=flows))
    try:
        first_road: dict[str, str] = {}
        events, waiting = [], {}  # departed vehicles not yet on a road at a SUMO tick (SUMO runs a step ahead)
        for tick in range(1, 120 * PHYSICS_HZ + 1):
            tr.advance(tick, OtherCars.none())
            ev = tr.pop_events()
            events += ev
            waiting.update({e["vehicle"]: (e["slot"], e["tick"]) for e in ev if e["type"] == "traffic_depart"})
            if tick % PERIOD == 0:
                ids, *_ = tr.road_positions(tick)
                for v, (k, since) in list(waiting.items()):
                    if tick >= since and ids[k]:  # the event comes a step ahead, with the tick the vehicle is on
                        first_road[v] = ids[k]
                        del waiting[v]
        departs = [e["vehicle"] for e in events if e["type"] == "traffic_depart"]
        n0, n1 = sum(v.startswith("f0_") for v in departs), sum(v.startswith("f1_") for v in departs)
        assert 40 - 3.3 * 40**0.5 < tr._flows.departed[0] < 40 + 3.3 * 40**0.5
        assert 20 - 3.3 * 20**0.5 < tr._flows.departed[1] < 20 + 3.3 * 20**0.5
        assert tr._flows.refused == [0, 0] and n0 >= tr._flows.departed[0] - 2 and n1 == tr._flows.departed[1]
        assert len(first_road) >= len(departs) - 2
        assert all(road == ("h0_0.f" if v.startswith("f0_") else "v3_0.f") for v, road in first_road.items())
    finally:
        tr.close()


@needs_sumo
def test_flow_departures_beyond_the_free_slots_are_refused_and_counted(client, work_dir) -> None:
    from vehicles.sumo.demand import DemandConfig, Flow

    flows = (Flow(origin="h0_0.f", destination="h2_3.f", per_hour=36000.0),)
    tr = _traffic(_grid(), client, work_dir, n_vehicles=2, n_slots=5, demand=DemandConfig(flows=flows))
    try:
        refused = 0
        for tick in range(1, 10 * PHYSICS_HZ + 1):
            tr.advance(tick, OtherCars.none())
            refused += sum(e["type"] == "traffic_flow_refused" for e in tr.pop_events())
            assert len(tr._flows.alive) <= 3 and tr.vehicles_on_road <= 5
        assert refused == tr._flows.refused[0] > 0
        total = refused + tr._flows.departed[0]  # the draws: Poisson of mean 100
        assert 100 - 3.3 * 10 < total < 100 + 3.3 * 10
    finally:
        tr.close()


@needs_sumo
def test_a_flow_on_an_unknown_road_is_refused_and_sumo_closed(client, work_dir) -> None:
    from vehicles.sumo.demand import DemandConfig, Flow

    bad = DemandConfig(flows=(Flow(origin="h0_0.f", destination="nope", per_hour=60.0),))
    with pytest.raises(ValueError, match="flow 0: destination 'nope' is not a road of the network"):
        _traffic(_grid(), client, work_dir, n_vehicles=0, n_slots=4, demand=bad)
    _traffic(_grid(), client, work_dir, n_vehicles=2, n_slots=4).close()  # libsumo was released
    with pytest.raises(ValueError, match="Flow.per_hour must be finite and > 0"):
        Flow(origin="a", destination="b", per_hour=0.0)
    with pytest.raises(ValueError, match="0 <= begin_s < end_s required"):
        Flow(origin="a", destination="b", per_hour=1.0, begin_s=5.0, end_s=5.0)


@needs_sumo
def test_signal_reads_the_lights_of_a_link_as_sumo_shows_them(client, work_dir) -> None:
    """A light at junction 1_1 of the grid: every link through it reads as SUMO's state string says (red, yellow or
    green: the most restrictive of the link's lanes), each goes through red and green within two minutes, links
    elsewhere read "" (no light)."""
    from vehicles.sumo.network import NetConfig

    net = _grid()
    with make_sumo_traffic(net, n_vehicles=20, n_slots=24, rate_hz=RATE_HZ, physics_hz=PHYSICS_HZ, client_id=client,
                           rng=np.random.default_rng(7), work_dir=work_dir,
                           net=NetConfig(tls="none", signals=("1_1",))) as tr:
        lib = tr._lib
        assert lib.trafficlight.getIDList() == ("1_1",)
        into = [r for r in net.roads.values() if r.end_node == "1_1"]
        links = [(a.id, b.id) for a in into for b in net.roads.values()
                 if b.start_node == "1_1" and b.end_node != a.start_node]
        assert len(links) == 12
        seen = {link: set() for link in links}
        for k in range(1, 1200):  # 120 s of SUMO steps
            tr.advance(k * PERIOD, OtherCars.none())
            state = lib.trafficlight.getRedYellowGreenState("1_1")
            for a, b in links:
                got = tr.signal(a, b)
                chars = {state[i] for i, group in enumerate(lib.trafficlight.getControlledLinks("1_1"))
                         for lane_in, lane_out, _ in group
                         if lib.lane.getEdgeID(lane_in) == a and lib.lane.getEdgeID(lane_out) == b}
                want = "r" if chars & set("rRu") else "y" if chars & set("yY") else "G"
                assert got == want
                seen[(a, b)].add(got)
        assert all({"r", "G"} <= s for s in seen.values())
        assert tr.signal("h0_0.f", "h1_0.f") == ""  # junction 1_0 has no light


@needs_sumo
def test_a_flow_via_roads_takes_them_in_order(client, work_dir) -> None:
    """From h0_0.f to h2_0.f the fastest route is straight along y = 0; via v1_1.f (x = 150, northbound above the
    first row) it detours north and back: the flow's route passes its via road, and its ends are the flow's."""
    from vehicles.sumo.demand import DemandConfig, Flow

    straight = (Flow(origin="h0_0.f", destination="h2_0.f", per_hour=60.0),)
    detour = (Flow(origin="h0_0.f", destination="h2_0.f", per_hour=60.0, via=("v1_1.f",)),)
    routes = []
    for flows in (straight, detour):
        with _traffic(_grid(), client, work_dir, n_vehicles=0, n_slots=4, demand=DemandConfig(flows=flows)) as tr:
            edges = list(tr._lib.route.getEdges("fr0"))
            routes.append([tr.net.edge_to_road[e] for e in edges])
    assert routes[0] == ["h0_0.f", "h1_0.f", "h2_0.f"]
    assert routes[1][0] == "h0_0.f" and routes[1][-1] == "h2_0.f" and "v1_1.f" in routes[1]
    assert len(routes[1]) > len(routes[0]) and len(set(routes[1])) == len(routes[1])
    with pytest.raises(ValueError, match="flow 0: via 'nope' is not a road of the network"):
        _traffic(_grid(), client, work_dir, n_vehicles=0, n_slots=4,
                 demand=DemandConfig(flows=(Flow(origin="h0_0.f", destination="h2_0.f", per_hour=60.0,
                                                 via=("nope",)),)))
