"""The traffic section's verdict rules, on constructed results that must pass and results that must fail, and its
campaigns' overrides."""

from __future__ import annotations

import numpy as np

from simulator.reproduce.paper_002_traffic import _world_overrides, identity_kept, ratio_within
from worlds.loader import load_world


def test_ratio_rule_uses_the_upper_end_of_the_interval():
    base = np.array([10.0, 12.0, 9.0, 11.0, 10.0])
    ok, ci = ratio_within(base * 1.2, base, 1.5)
    assert ok and abs(ci.mean - 1.2) < 1e-12
    # a mean ratio of 1.45 whose interval reaches past 1.5 fails
    noisy = base * np.array([1.0, 1.9, 1.2, 1.8, 1.35])
    ok, ci = ratio_within(noisy, base, 1.5)
    assert abs(ci.mean - 1.45) < 1e-12 and ci.mean + ci.half > 1.5 and not ok
    ok, _ = ratio_within(base * 1.6, base, 1.5)
    assert not ok
    ok, _ = ratio_within(np.array([np.nan]), np.array([1.0]), 1.5)  # nothing to judge: fails
    assert not ok


def test_identity_rule_needs_every_uav():
    assert identity_kept({"uav1": np.array([0.95, 0.92]), "uav2": np.array([0.9, 0.9])}, 0.9)
    assert not identity_kept({"uav1": np.array([0.95, 0.92]), "uav2": np.array([0.95, 0.84])}, 0.9)
    assert not identity_kept({"uav1": np.array([0.99]), "uav2": np.array([np.nan])}, 0.9)
    assert not identity_kept({}, 0.9)


def test_campaign_overrides_load_and_do_what_they_say():
    shipped = load_world("road_standoff_traffic").world
    alone = load_world("road_standoff_traffic", _world_overrides("alone")).world
    assert [g.id for g in alone.ground_vehicles] == ["car1"]
    assert alone.ground_vehicles[0] == shipped.ground_vehicles[0]
    assert all(u.autonomy.estimator.tracking.mode == "multi" for u in alone.uavs)
    assert [u.sensors for u in alone.uavs] == [u.sensors for u in shipped.uavs]
    same = load_world("road_standoff_traffic", _world_overrides("same_look")).world
    assert {(g.colour, g.type) for g in same.ground_vehicles} == {("red", "sedan")}
    radar = load_world("road_standoff_traffic", _world_overrides("radar_ecukf")).world
    paper = load_world("road_standoff").world
    for u, s, b in zip(radar.uavs, shipped.uavs, paper.uavs, strict=True):
        assert [x.type for x in u.sensors] == ["radar"] and u.sensors[0] == s.sensors[0]
        assert u.autonomy.estimator.type == "ecukf"
        # the paper's team flies road_standoff's start and altitude, not the traffic world's higher ones
        assert u.initial == b.initial and u.autonomy.guidance.altitude == b.autonomy.guidance.altitude
        assert s.autonomy.guidance.altitude > b.autonomy.guidance.altitude
    assert len(radar.ground_vehicles) == len(shipped.ground_vehicles)
