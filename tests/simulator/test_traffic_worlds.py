"""Worlds with generated traffic (``traffic:``): the built-in fleet's cars placed and driven, SUMO co-simulation run
for real (the ``traffic`` extra is part of ``make test``), one seed one run, and the clear refusals."""

import numpy as np
import pytest

from simulator.api import run
from worlds.errors import WorldError
from worlds.loader import load_world

BUILTIN = ["traffic.cars=40", "traffic.rate_hz=20"]
SUMO = ["traffic.engine=sumo", "traffic.cars=40", "traffic.rate_hz=10"]


def _truth(res):
    vt = res.stream("vehicle_truth")
    return vt


def test_builtin_traffic_cars_join_the_ground_vehicles_and_drive_their_lanes(tmp_path):
    res = run("road_standoff", duration=8.0, seed=4, out_dir=tmp_path / "a", overrides=BUILTIN)
    assert res.status == "completed"
    vt = _truth(res)
    ids = sorted(set(vt["vehicle"].tolist()))
    assert len(ids) == 41  # the target and 40 generated cars
    first, last = vt["t"] == vt["t"].min(), vt["t"] == vt["t"].max()
    moved = np.hypot(vt["x"][last] - vt["x"][first], vt["y"][last] - vt["y"][first])
    assert np.mean(moved > 10.0) > 0.75  # driving (the rest stopped at a junction, 2-8 s dwells)
    assert not [e for e in res.record.events if e["type"] == "car_left_road"]  # centres within the carriageways
    assert np.max(np.abs(vt["lateral"])) < 7.0  # (the town's widest roads: two lanes each way, 3.5 m)
    xy = np.column_stack([vt["x"][first], vt["y"][first]])
    gaps = np.linalg.norm(xy[:, None] - xy[None], axis=2) + np.eye(len(xy)) * 1e9
    assert gaps.min() >= 12.0 - 1e-6  # traffic.min_spacing_m


def test_traffic_that_does_not_fit_is_refused_before_the_run(tmp_path):
    with pytest.raises(WorldError) as info:
        run("road_standoff", duration=1.0, out_dir=tmp_path / "b",
            overrides=["traffic.cars=5000", "traffic.min_spacing_m=200"])
    msg = str(info.value)
    assert "traffic.cars = 5000" in msg and "found no room for more" in msg
    assert not (tmp_path / "b").exists()


def test_sumo_traffic_runs_and_one_seed_gives_one_run(tmp_path):
    runs = [run("road_standoff", duration=6.0, seed=3, out_dir=tmp_path / f"s{k}", overrides=SUMO) for k in range(2)]
    assert all(r.status == "completed" for r in runs)
    a, b = (_truth(r) for r in runs)
    for key in ("x", "y", "speed", "vehicle"):
        assert np.array_equal(a[key], b[key]), key
    # SUMO's vehicles are on the road, on skytrack's lanes: the recorded lateral offsets from the centre-lines of the
    # roads they are on stay within the carriageway (inside junctions, the nearest road)
    on = np.isin(a["vehicle"], np.arange(1, 41)) & (a["road"] != "")
    lat = np.abs(a["lateral"][on])
    off_lane = np.abs(lat - 3.5 * (np.maximum(np.round(lat / 3.5 - 0.5), 0) + 0.5))  # from the nearest lane centre
    # on lane centres but inside junctions (there measured from the nearest road): median and 3rd quartile
    assert on.sum() > 100 and np.median(off_lane) < 0.01 and np.percentile(off_lane, 75) < 0.1 and lat.max() < 7.5
    other = run("road_standoff", duration=6.0, seed=4, out_dir=tmp_path / "s2", overrides=SUMO)
    assert not np.array_equal(_truth(other)["x"], a["x"])


def test_a_sumo_world_without_sumo_is_refused_with_the_install_hint(monkeypatch, tmp_path):
    import vehicles.sumo as sumo

    monkeypatch.setattr(sumo, "sumo_available", lambda: False)
    with pytest.raises(WorldError) as info:
        run("road_standoff", duration=1.0, out_dir=tmp_path / "c", overrides=SUMO)
    assert "traffic.engine = 'sumo'" in str(info.value) and "pip install 'skytrack[traffic]'" in str(info.value)


def test_the_traffic_section_is_checked():
    with pytest.raises(WorldError) as info:
        load_world("road_standoff", ["traffic.rate_hz=7", "traffic.cars=3"])
    assert "traffic.rate_hz = 7" in str(info.value)
    with pytest.raises(WorldError) as info:
        load_world("road_standoff", ["traffic.engine=carla"])
    assert "traffic.engine" in str(info.value)


def test_a_world_of_sumo_traffic_alone_runs(tmp_path):
    """No listed ground vehicle: the car fleet holds SUMO's slots only."""
    res = run("road_standoff", duration=3.0, seed=1, out_dir=tmp_path / "d", overrides=["ground_vehicles=[]", *SUMO])
    assert res.status == "completed"
    assert len(set(_truth(res)["vehicle"].tolist())) == 40


def test_the_maps_signals_become_sumos_traffic_lights(monkeypatch):
    """tls: auto lights the junctions the map's signals control (helsinki_traffic: OSM signals), else netconvert's
    guess; the world's geometry carries the junctions to SUMO's network options."""
    from simulator.factories import build_car_fleet, sumo_net_config
    from vehicles.sumo.network import NetConfig
    from worlds.build import build_geometry

    lit = ("a", "b")
    assert sumo_net_config("auto", lit) == NetConfig(tls="none", signals=lit)
    assert sumo_net_config("auto", ()) == NetConfig(tls="guess", signals=())
    assert sumo_net_config("map", lit) == NetConfig(tls="none", signals=lit)
    assert sumo_net_config("guess", lit) == NetConfig(tls="guess", signals=lit)
    assert sumo_net_config("none", lit) == NetConfig(tls="none", signals=())
    with pytest.raises(ValueError, match="traffic.tls must be 'auto', 'map', 'guess' or 'none', got 'osm'"):
        sumo_net_config("osm", lit)

    loaded = load_world("helsinki_traffic", ["traffic.cars=10"])
    geometry = build_geometry(loaded.world, loaded.path, np.random.default_rng(0))
    assert len(geometry.signals) > 30 and set(geometry.signals) <= set(geometry.network.nodes)
    seen = {}

    class Stop(Exception):
        pass

    def fake(network, **kw):
        seen.update(kw)
        raise Stop

    monkeypatch.setattr("vehicles.sumo.make_sumo_traffic", fake)
    with pytest.raises(Stop):
        build_car_fleet(loaded.world, geometry.network, 0, 240, np.random.default_rng(0), geometry.signals)
    assert seen["net"] == NetConfig(tls="none", signals=geometry.signals)
    with pytest.raises(Stop):
        build_car_fleet(load_world("helsinki_traffic", ["traffic.cars=10", "traffic.tls=guess"]).world,
                        geometry.network, 0, 240, np.random.default_rng(0), geometry.signals)
    assert seen["net"] == NetConfig(tls="guess", signals=geometry.signals)


FLOWS = ["traffic.engine=sumo", "traffic.cars=12", "traffic.rate_hz=10", "traffic.trips=4",
         "traffic.flows=[{from: h0_0.f, to: h5_0.f, per_hour: 1800}, {from: h5_0.r, to: h0_0.r, per_hour: 900}]"]


def test_a_world_with_sumo_flows_runs_them_beside_its_trips(tmp_path):
    res = run("road_standoff", duration=20.0, seed=2, out_dir=tmp_path / "f", overrides=FLOWS)
    assert res.status == "completed"
    departs = [e["vehicle"] for e in res.record.events if e["type"] == "traffic_depart"]
    n0, n1 = sum(v.startswith("f0_") for v in departs), sum(v.startswith("f1_") for v in departs)
    # Poisson means 10 and 5 over 20 s (99.9 % bands), a few still waiting to enter; the 4 trips besides them
    assert 1 <= n0 <= 21 and 0 <= n1 <= 13 and n0 + n1 >= 4
    assert sum(v.startswith("t") for v in departs) >= 4
    assert res.metrics["events"].get("traffic_flow_refused", 0) == 0  # 8 slots are plenty


def test_flows_and_trips_are_checked_against_the_engine_slots_and_roads():
    with pytest.raises(WorldError) as info:
        load_world("road_standoff", ["traffic.cars=4", "traffic.flows=[{from: h0_0.f, to: h5_0.f, per_hour: 60}]"])
    assert "traffic" in str(info.value) and "need engine: sumo" in str(info.value)
    with pytest.raises(WorldError) as info:
        load_world("road_standoff", [*SUMO, "traffic.trips=41"])
    assert "trips <= cars (40, the scene slots), got trips 41" in str(info.value)
    with pytest.raises(WorldError) as info:
        load_world("road_standoff", [*SUMO, "traffic.flows=[{from: a, to: b, per_hour: 60, begin_s: 9, end_s: 3}]"])
    assert "end_s > begin_s (9 s), got end_s 3" in str(info.value)
    with pytest.raises(WorldError) as info:
        run("road_standoff", duration=1.0, overrides=[*SUMO, "traffic.flows=[{from: h0_0.f, to: nope, per_hour: 60}]"])
    assert "traffic.flows[0].to" in str(info.value) and "'nope'" in str(info.value)
    with pytest.raises(WorldError) as info:
        run("road_standoff", duration=1.0,
            overrides=[*SUMO, "traffic.flows=[{from: h0_0.f, to: h5_0.f, via: [h1_0.f, gone], per_hour: 60}]"])
    assert "traffic.flows[0].via[1]" in str(info.value) and "'gone'" in str(info.value)


def test_free_sumo_slots_are_not_scored_as_vehicles(tmp_path):
    """40 SUMO slots of which 10 carry trips: the 30 free ones are parked bodies, not vehicles. The MOT scores count
    at most the target and the 10 trips at each of the UAV's scored steps (with the free slots: 41 each); the record
    marks the free slots and a replay keeps them out of sight."""
    res = run("road_standoff_traffic", duration=10.0, seed=1, out_dir=tmp_path / "p",
              overrides=["ground_vehicles=[{id: car1, type: sedan, colour: red, role: target, "
                         "route: {random_walk_from: h2_0.f}}]", *SUMO, "traffic.trips=10"])
    assert res.status == "completed"
    mot = res.metrics["uavs"]["uav1"]["mot"]
    assert mot["steps"] > 5 and 0.6 * 11 * mot["steps"] <= mot["truth_instances"] <= 11 * mot["steps"]
    # the record says which slots hold a vehicle, and a replay keeps the free ones below the ground
    from simulator.render.timeline import HIDDEN_Z, Timeline

    vt = _truth(res)
    active = vt["active"].astype(bool)
    per_tick = np.bincount(np.unique(vt["tick"], return_inverse=True)[1], weights=active)
    assert per_tick.max() <= 11 and per_tick.min() >= 1 and (~active).sum() >= 29 * len(per_tick)
    assert active[vt["vehicle"] == 0].all()  # the target
    tl = Timeline(res.record.streams)
    t = float(vt["t"].max())
    free = sorted(set(vt["vehicle"][~active & (vt["t"] == t)].tolist()))
    on = sorted(set(vt["vehicle"][active & (vt["t"] == t)].tolist()))
    assert all(tl.vehicles[v].at(t)[0][2] == HIDDEN_Z for v in free)
    assert all(tl.vehicles[v].at(t)[0][2] > -1.0 for v in on)


def test_the_target_car_stops_at_sumos_red_lights_and_goes_at_green(tmp_path):
    """Lights at every junction of road_standoff's town (traffic.signals, SUMO traffic): within 60 s the physics
    target meets a red light and stops before the junction (a car_stop event marked light; its speed under 0.3 m/s
    while it waits, until the car_go when its link no longer shows red or yellow)."""
    from worlds.build import build_geometry
    from worlds.roads.signals import junctions

    loaded = load_world("road_standoff")
    nodes = sorted(junctions(build_geometry(loaded.world, loaded.path, np.random.default_rng(0)).network))
    res = run("road_standoff", duration=60.0, seed=2, out_dir=tmp_path / "l",
              overrides=[*SUMO, "traffic.tls=map", f"traffic.signals=[{', '.join(nodes)}]"])
    assert res.status == "completed"
    stops = [e for e in res.record.events if e["type"] == "car_stop" and e.get("car") == 0 and e.get("light")]
    assert stops  # (besides its planned dwell stops)
    first = stops[0]["tick"] / 240.0
    goes = [e["tick"] / 240.0 for e in res.record.events
            if e["type"] == "car_go" and e.get("car") == 0 and e["tick"] / 240.0 > first]
    until = goes[0] if goes else 60.0
    vt = _truth(res)
    target = vt["vehicle"] == 0
    assert until > first + 1.0
    waiting = target & (vt["t"] > first + 0.5) & (vt["t"] < until - 0.1)
    assert waiting.sum() > 5 and np.all(vt["speed"][waiting] < 0.3)


def test_signals_are_checked_against_the_engine_and_the_network():
    with pytest.raises(WorldError) as info:
        load_world("road_standoff", ["traffic.cars=4", "traffic.signals=[a]"])
    assert "need engine: sumo" in str(info.value)
    with pytest.raises(WorldError) as info:
        run("road_standoff", duration=1.0, overrides=[*SUMO, "traffic.signals=[nowhere]"])
    assert "traffic.signals[0]" in str(info.value) and "'nowhere'" in str(info.value)
