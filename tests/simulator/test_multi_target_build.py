"""When a UAV tracks many cars, what its tracker is told about the target, and what is refused."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.estimation.tracking.gated import TargetGatedEstimator
from autonomy.estimation.tracking.multi import MultiTargetTracker
from simulator.builders.multi_target import TRACK_BAND_M, identity_config, multi_target, tracking_mode
from simulator.registry import build_estimator
from worlds.build import build_geometry
from worlds.catalog import CAR_COLOURS, CAR_TYPES
from worlds.errors import WorldError
from worlds.loader import load_world


def test_auto_mode_tracks_many_cars_only_where_there_are_several():
    demo = load_world("demo").world
    assert tracking_mode(demo, demo.uavs[0]) == "multi"
    one = load_world("road_standoff").world
    assert tracking_mode(one, one.uavs[0]) == "single"
    forced = load_world("road_standoff", ["uavs[0].autonomy.estimator.tracking.mode=multi"]).world
    assert tracking_mode(forced, forced.uavs[0]) == "multi"
    search = load_world("search_decoys").world  # set-membership holds every target as sets
    assert tracking_mode(search, search.uavs[0]) == "single"


def test_the_tracker_is_told_the_targets_classes_and_the_traffics():
    loaded = load_world("demo")
    world = loaded.world
    network = build_geometry(world, loaded.path, np.random.default_rng(1)).network
    cfg = identity_config(world, world.uavs[0], network)
    assert cfg.target_classes == {"colour": CAR_COLOURS.index("red"), "body": CAR_TYPES.index("sedan"),
                                  "length": 0}
    # three traffic cars (white van, blue and black sedans), one pseudo-count per class
    np.testing.assert_allclose(cfg.background["body"], np.array([1 + 2, 1 + 1]) / 5)
    assert cfg.background["colour"][CAR_COLOURS.index("red")] == pytest.approx(1 / 10)
    assert cfg.background_density == pytest.approx(3 / (network.street_length() * TRACK_BAND_M))


def test_built_in_trackers_become_multi_target_and_plugins_are_wrapped():
    loaded = load_world("demo", ["uavs[0].autonomy.estimator.type=ecukf"])
    world = loaded.world
    network = build_geometry(world, loaded.path, np.random.default_rng(1)).network
    est = multi_target(build_estimator(world.uavs[0], 0, network), world, world.uavs[0], network)
    assert isinstance(est, MultiTargetTracker)

    class Mine:
        def step(self, t, detections):
            return None

    wrapped = multi_target(Mine(), world, world.uavs[0], network)
    assert isinstance(wrapped, TargetGatedEstimator) and isinstance(wrapped.inner, Mine)


@pytest.mark.parametrize("associator", ["gnn", "jpda"])
def test_class_readings_weigh_in_association_unless_the_world_says_not(associator):
    sets = [f"uavs[0].autonomy.estimator.tracking.associator={associator}"]
    for extra, aided in (([], True), (["uavs[0].autonomy.estimator.tracking.class_aided=false"], False)):
        loaded = load_world("demo", sets + extra)
        world = loaded.world
        network = build_geometry(world, loaded.path, np.random.default_rng(1)).network
        est = multi_target(build_estimator(world.uavs[0], 0, network), world, world.uavs[0], network)
        affinity = est.associator.affinity
        assert (affinity is not None) == aided
        if aided:  # the traffic census the identity belief uses, and its swap hazard
            assert affinity.background.keys() == est.identity.config.background.keys()
            assert affinity.swap_probability == est.identity.config.swap_probability


def test_base_station_fusion_among_traffic_is_refused_with_the_key_path(tmp_path):
    from simulator.api import run

    sets = [f"uavs[{i}].autonomy.estimator.type=scif" for i in (0, 1)]
    sets += [f"uavs[{i}].autonomy.fusion={{method: base_station}}" for i in (0, 1)]
    sets += ["comms.model=rayleigh", "comms.base_station=[0, 0, 10]"]
    with pytest.raises(WorldError, match=r"uavs\[0\]\.autonomy\.estimator\.tracking\.mode.*single"):
        run("demo", duration=1.0, out_dir=tmp_path, overrides=sets)


@pytest.mark.slow
def test_hcmci_among_traffic_runs_on_the_target_tracks(tmp_path):
    """Paper 000's consensus among the demo's traffic: each node's target track, fused with the nodes whose target
    track is the same car. UAV 2 first sees the target after ~20 s (it is stopped, in the radars' Doppler notch, at
    the start); from then on the two fuse."""
    from simulator.api import run

    sets = [f"uavs[{i}].autonomy.estimator.type=scif" for i in (0, 1)]
    sets += [f"uavs[{i}].autonomy.fusion={{method: hcmci}}" for i in (0, 1)]
    result = run("demo", duration=30.0, seed=1, out_dir=tmp_path, overrides=sets)
    assert result.status == "completed"
    m = result.metrics
    assert m["consensus"]["team_steps"] > 0
    assert m["targets"]["car1"]["uav1"]["identity_fraction"] > 0.9
    for u in ("uav1", "uav2"):
        assert m["uavs"][u]["consensus_linked_steps"] > 50


def test_search_detection_probability_auto_only_where_radars_see_stopped_cars_all_around():
    from simulator.builders.multi_target import SEARCH_DETECTION_PROBABILITY, search_detection_probability
    from worlds.loader import load_world

    traffic = load_world("road_standoff_traffic").world  # radars without a Doppler notch or a sector
    assert [search_detection_probability(u) for u in traffic.uavs] == [SEARCH_DETECTION_PROBABILITY] * 2
    demo = load_world("demo").world  # its radars have the default 1 m/s notch: a stopped target is unseen
    assert all(search_detection_probability(u) == 0.0 for u in demo.uavs)
    notch = load_world("road_standoff_traffic", overrides=["uavs[0].sensors[0].min_detectable_velocity=1.0"]).world
    assert search_detection_probability(notch.uavs[0]) == 0.0
    assert search_detection_probability(notch.uavs[1]) == SEARCH_DETECTION_PROBABILITY
    given = load_world("demo", overrides=["uavs[0].autonomy.estimator.tracking.search_detection_probability=0.5"])
    assert search_detection_probability(given.world.uavs[0]) == 0.5
    with pytest.raises(WorldError, match="search_detection_probability"):
        load_world("demo", overrides=["uavs[0].autonomy.estimator.tracking.search_detection_probability=1.5"])
