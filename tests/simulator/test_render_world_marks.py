"""World-derived overlay marks of a replay: radar fields of regard and radio links with their delivery probability."""

import numpy as np
import pytest

from simulator.render.world_marks import RadioLinks, RegardOutline, probability_rgb, radar_regards
from worlds.geometry import Building
from worlds.loader import load_world
from worlds.schema import World


def _world(tmp_path, comms: str):
    path = tmp_path / "w.yaml"
    path.write_text(
        "uavs:\n"
        "  - {id: a, initial: {position: [0, 0, 50]}}\n"
        "  - {id: b, initial: {position: [600, 0, 50]}}\n"
        f"comms: {comms}\n")
    return load_world(path).world


def test_link_probability_follows_the_distance_law_and_a_building_cuts_it(tmp_path):
    world = _world(tmp_path, "{model: rayleigh, block_by_buildings: true}")
    a, b = np.array([0.0, 0.0, 50.0]), np.array([600.0, 0.0, 50.0])
    clear = RadioLinks(world, [])
    [(pa, pb, pr)] = clear.at(1.0, [a, b])
    assert pr == pytest.approx(np.exp(-(0.6**3)), rel=1e-9)  # Pr(d) = exp(-(d / 1000 m)^3), paper 001's Table 1
    tower = Building(footprint=np.array([[290.0, -20.0], [310.0, -20.0], [310.0, 20.0], [290.0, 20.0]]), height=80.0)
    blocked = RadioLinks(world, [tower])
    assert blocked.at(1.0, [a, b])[0][2] == 0.0
    low = Building(footprint=tower.footprint, height=30.0)  # below the link: no blockage
    assert RadioLinks(world, [low]).at(1.0, [a, b])[0][2] == pytest.approx(pr)


def test_scheduled_outage_and_perfect_radio(tmp_path):
    world = _world(tmp_path, "{model: rayleigh, outages: [{link: [a, b], start_s: 2, end_s: 4}]}")
    links = RadioLinks(world, [])
    pos = [np.array([0.0, 0.0, 50.0]), np.array([100.0, 0.0, 50.0])]
    assert links.at(1.0, pos)[0][2] > 0.99 and links.at(3.0, pos)[0][2] == 0.0 and links.at(4.5, pos)[0][2] > 0.99
    assert not RadioLinks(_world(tmp_path, "{model: perfect}"), []).active


def test_probability_colours_run_from_red_to_green():
    assert probability_rgb(0.0) == (1.0, 0.0, 0.1)
    assert probability_rgb(1.0) == (0.0, 1.0, 0.1)
    assert probability_rgb(0.5) == (1.0, 1.0, 0.1)


def test_sector_regard_turns_with_the_heading_and_ends_at_max_range():
    r = RegardOutline(uav=0, frame="heading", azimuth_limits=(-np.pi / 6, np.pi / 6), max_range=500.0)
    p = np.array([10.0, 20.0, 80.0])
    pts = r.outline(p, yaw=np.pi / 2, z=0.0)
    assert np.allclose(pts[0], [10.0, 20.0, 0.0])  # the sector's apex is below the UAV
    rel = pts[1:, :2] - p[:2]
    assert np.allclose(np.hypot(rel[:, 0], rel[:, 1]), 500.0)
    ang = np.arctan2(rel[:, 1], rel[:, 0])
    assert ang.min() == pytest.approx(np.pi / 2 - np.pi / 6) and ang.max() == pytest.approx(np.pi / 2 + np.pi / 6)
    world_frame = RegardOutline(uav=0, frame="world", azimuth_limits=(0.0, 0.5), max_range=100.0)
    assert np.allclose(world_frame.outline(p, yaw=2.0, z=0.0)[1, :2] - p[:2], [100.0, 0.0])  # yaw ignored


def test_regards_come_from_radars_with_a_maximum_range():
    radar = {"type": "radar", "rate_hz": 10, "sigma_range": 1.0, "sigma_azimuth_deg": 1.0}
    world = World.model_validate({"uavs": [{"id": "a", "initial": {"position": [0, 0, 60]}, "sensors": [
        {**radar, "max_range": 800, "fov": {"frame": "world", "azimuth_limits_deg": [0, 90]}},
        radar, {"type": "camera", "rate_hz": 10, "far": 5}]}]})
    [r] = radar_regards(world)
    assert r.frame == "world" and r.max_range == 800.0 and r.azimuth_limits == pytest.approx((0.0, np.pi / 2))
