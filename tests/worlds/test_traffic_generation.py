"""Generated background traffic (worlds/traffic.py): seeded placement on the roads, min spacing from every car,
cycled types and colours, ids after the listed cars, and the refusals."""

import numpy as np
import pytest

from worlds.roads.network import RoadNetwork
from worlds.schema import World
from worlds.traffic import TrafficPlacementError, start_point, with_traffic


def _grid(n=4, spacing=100.0):
    nodes = {f"{i}_{j}": [i * spacing, j * spacing] for i in range(n) for j in range(n)}
    streets = [{"id": f"h{i}_{j}", "nodes": [f"{i}_{j}", f"{i + 1}_{j}"]} for i in range(n - 1) for j in range(n)]
    streets += [{"id": f"v{i}_{j}", "nodes": [f"{i}_{j}", f"{i}_{j + 1}"]} for i in range(n) for j in range(n - 1)]
    return RoadNetwork.from_spec({"nodes": nodes, "streets": streets})


def _world(**traffic):
    return World(name="t", ground_vehicles=[{"id": "car1", "route": {"random_walk_from": "h1_1.f", "start_s": 50}}],
                 traffic=traffic)


def test_cars_are_placed_apart_on_the_roads_with_cycled_types_and_colours():
    net = _grid()
    w = with_traffic(_world(cars=30, types=["sedan", "van"], colours=["red", "blue", "green"]), net,
                     np.random.default_rng(3))
    gen = w.ground_vehicles[1:]
    assert [g.id for g in gen] == [f"traffic_{k}" for k in range(1, 31)]
    assert [g.type for g in gen[:4]] == ["sedan", "van", "sedan", "van"]
    assert [g.colour for g in gen[:4]] == ["red", "blue", "green", "red"]
    assert all(g.role == "traffic" and g.dynamics == "kinematic" and g.driver.rate_hz == 20 for g in gen)
    pts = np.array([start_point(net, g.route.random_walk_from or g.route.roads[0], g.route.start_s)
                    for g in w.ground_vehicles])
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2) + np.eye(len(pts)) * 1e9
    assert d.min() >= 12.0 - 2e-3  # min_spacing_m (starts rounded to the millimetre)
    for g in gen:  # on a road, off its ends
        road = net.roads[g.route.random_walk_from]
        assert 5.0 <= g.route.start_s <= road.length - 5.0


def test_one_seed_one_placement_and_none_asked_none_added():
    net = _grid()
    a, b = (with_traffic(_world(cars=10), net, np.random.default_rng(7)) for _ in range(2))
    c = with_traffic(_world(cars=10), net, np.random.default_rng(8))
    assert a.ground_vehicles == b.ground_vehicles != c.ground_vehicles
    w = _world()
    assert with_traffic(w, net, np.random.default_rng(0)) is w


def test_refusals():
    net = _grid(3, 40.0)
    with pytest.raises(TrafficPlacementError, match=r"traffic.cars = 500: placed \d+ cars 12 m apart"):
        with_traffic(_world(cars=500), net, np.random.default_rng(0))
    with pytest.raises(TrafficPlacementError, match=r"gives ids the world already uses: \['car1'\]"):
        with_traffic(_world(cars=2, id_prefix="car"), net, np.random.default_rng(0))
    with pytest.raises(ValueError, match="give the rate once, as traffic.rate_hz"):
        _world(cars=2, rate_hz=20, driver={"rate_hz": 40})


def test_sumo_entries_only_name_the_slots():
    w = with_traffic(_world(cars=5, engine="sumo", types=["van"]), _grid(), np.random.default_rng(0))
    assert [g.id for g in w.ground_vehicles[1:]] == [f"traffic_{k}" for k in range(1, 6)]
    assert {g.type for g in w.ground_vehicles[1:]} == {"van"}
