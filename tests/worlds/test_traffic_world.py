"""The traffic world (``road_standoff_traffic``): ``road_standoff`` with one designated target among at least 20
kinematic traffic cars, each on its own street of the town, no two starting close together."""

import itertools

import numpy as np

from worlds.build import build_geometry
from worlds.loader import load_world


def _street(road_id: str) -> str:
    return road_id.rsplit(".", 1)[0]  # a road and its twin (.f / .r) share a street


def test_one_target_among_kinematic_traffic_on_distinct_streets_spaced_apart():
    loaded = load_world("road_standoff_traffic")
    world = loaded.world
    cars = world.ground_vehicles
    assert [g.id for g in cars if g.role == "target"] == ["car1"]
    traffic = [g for g in cars if g.role == "traffic"]
    assert len(traffic) >= 20 and len(traffic) == len(cars) - 1
    assert all(g.dynamics == "kinematic" for g in traffic)
    assert {g.type for g in traffic} == {"sedan", "van"}
    streets = [_street(g.route.random_walk_from) for g in cars]
    assert len(set(streets)) == len(streets)
    network = build_geometry(world, loaded.path, np.random.default_rng(world.sim.seed)).network
    starts = [np.asarray(network.roads[g.route.random_walk_from].point(g.route.start_s)) for g in cars]
    closest = min(float(np.linalg.norm(a - b)) for a, b in itertools.combinations(starts, 2))
    assert closest >= 30.0, closest  # 35 m by construction (25–75 m into 100 m streets)
    # the rest is road_standoff's
    base = load_world("road_standoff").world
    assert world.roads == base.roads and world.sim == base.sim
    # the UAVs are road_standoff's, with class readings added to their sensors (and any sensor added after them), and
    # the estimator settings the world file declares for traffic: a target model that brakes as a car does (Singer
    # σa 2 m/s² for Table I's 0.66) and the iterated EKF for the cameras' bearings; the team's switch margin; and
    # 50 m more altitude (110 m and 120 m, for the cameras' view down the town's streets), from where they start too
    for u, b in zip(world.uavs, base.uavs, strict=True):
        est, base_est = u.autonomy.estimator, b.autonomy.estimator
        assert est.params == {**base_est.params, "singer_sigma_a": 2.0, "ekf_iterations": 3}
        assert u.autonomy.fusion.switch_margin == 0.1 and b.autonomy.fusion.switch_margin == 0.0
        assert u.autonomy.guidance.altitude == b.autonomy.guidance.altitude + 50.0 <= 120.0
        assert u.autonomy.model_copy(update={
            "estimator": est.model_copy(update={"params": base_est.params}),
            "fusion": u.autonomy.fusion.model_copy(update={"switch_margin": 0.0}),
            "guidance": u.autonomy.guidance.model_copy(update={"altitude": b.autonomy.guidance.altitude})}) \
            == b.autonomy
        assert u.initial.position[2] == u.autonomy.guidance.altitude
        assert u.initial.model_copy(update={"position": b.initial.position}) == b.initial
        assert list(u.initial.position[:2]) == list(b.initial.position[:2])
        for s, sb in zip(u.sensors, b.sensors, strict=False):
            assert s.model_copy(update={"classify": None}) == sb
