"""World files of paper 001's pieces (guidance infoplan, fusion base_station, comms.routing): good ones load and build
what their keys say, and every bad key is named with its path, its value and what was expected, before anything runs."""

import math

import pytest

from worlds.errors import WorldError
from worlds.loader import load_world
from world_files import write

RADAR = "{type: radar, rate_hz: 1, sigma_range: 2, sigma_azimuth_deg: 3, min_detectable_velocity: 0}"
PLAN = "infoplan: {d_safe: 30, horizon: 2, heading_rates: 5}"


def _uav(uid: str, x: float, altitude: float) -> str:
    return f"""\
  - id: {uid}
    initial: {{position: [{x:g}, 0, {altitude:g}]}}
    sensors:
      - {RADAR}
    autonomy:
      rate_hz: 1
      estimator: {{type: scif, params: {{q: 0.01}}}}
      fusion: {{method: base_station}}
      guidance: {{type: infoplan, speed: 15, altitude: {altitude:g}, {PLAN}}}
"""


TEAM = """\
name: team
comms: {model: rayleigh, block_by_buildings: false, base_station: [-500, -800, 20], gamma: 20}
uavs:
""" + _uav("u1", 0, 50) + _uav("u2", 50, 60)
U2_PLAN = f"altitude: 60, {PLAN}"


def test_the_new_keys_load_with_their_defaults(tmp_path):
    world = load_world(write(tmp_path, TEAM)).world
    a = world.uavs[0].autonomy
    assert a.fusion.method == "base_station" and world.comms.routing == "mst"
    plan = a.guidance.infoplan
    assert (plan.d_safe, plan.horizon, plan.heading_rates) == (30, 2, 5)
    assert (plan.routing, plan.objective, plan.criterion, plan.max_heading_rate_deg_s) == (None, "team", "logdet", 30)


def test_the_factory_builds_the_planner_from_the_world(tmp_path):
    from simulator.registry import build_guidance

    world = load_world(write(tmp_path, TEAM)).world
    law = build_guidance(world.uavs[1], 1, 2, (), world.comms)
    cfg = law.config
    assert law.uav_id == 1
    assert cfg.base_p_W == (-500.0, -800.0) and cfg.dt == 1.0 and cfg.speed == 15 and cfg.altitude == 60
    assert (cfg.horizon, cfg.n_heading_rates, cfg.d_safe, cfg.routing) == (2, 5, 30, "mst")  # routing: the radio's
    assert cfg.sigma_range == 2 and cfg.sigma_bearing == pytest.approx(math.radians(3))  # from the radar
    assert cfg.max_heading_rate == pytest.approx(math.radians(30))
    # the planner weighs links by the radio's own model: Pr(d) = exp(−N γ d³ / (C P)) with γ = 20
    assert cfg.channel.delivery_probability(1000.0) == pytest.approx(math.exp(-2.0))


@pytest.mark.parametrize("old, new, path, value, expected", [
    ("base_station: [-500, -800, 20], ", "", "comms.base_station", None, "the base station's position"),
    ("model: rayleigh", "model: perfect", "comms.model", "perfect", "a radio model ('rayleigh')"),
    ("estimator: {type: scif, params: {q: 0.01}}\n      fusion", "estimator: {type: ekf, params: {q: 0.01}}\n"
     "      fusion", "uavs[0].autonomy.estimator.type", "ekf", "scif: fusion method base_station"),
    ("estimator: {type: scif, params: {q: 0.01}}\n      fusion: {method: base_station}\n      guidance: {type: "
     "infoplan, speed: 15, altitude: 60", "estimator: {type: scif, params: {q: 0.02}}\n      fusion: {method: "
     "base_station}\n      guidance: {type: infoplan, speed: 15, altitude: 60", "uavs[1].autonomy.estimator.params",
     {"q": 0.02}, "the base station predicts with one model"),
    ("method: base_station}\n      guidance: {type: infoplan, speed: 15, altitude: 60",
     "method: bases}\n      guidance: {type: infoplan, speed: 15, altitude: 60", "uavs[1].autonomy.fusion.method",
     "bases", "'base_station'"),
    (U2_PLAN, U2_PLAN.replace("d_safe: 30", "d_safe: 40"), "uavs[1].autonomy.guidance.infoplan",
     {"d_safe": 40.0, "horizon": 2, "heading_rates": 5}, "every UAV plans the whole team"),
    (U2_PLAN, U2_PLAN.replace("heading_rates: 5", "heading_rates: 6"),
     "uavs[1].autonomy.guidance.infoplan.heading_rates", 6, "an odd number"),
    (U2_PLAN, U2_PLAN.replace("horizon: 2", "horizon: 0"), "uavs[1].autonomy.guidance.infoplan.horizon", 0,
     "greater than or equal to 1"),
    (U2_PLAN, U2_PLAN.replace("d_safe: 30", "routing: chain, d_safe: 30"),
     "uavs[1].autonomy.guidance.infoplan.routing", "chain", "'mst' (the radio's comms.routing)"),
    (U2_PLAN, U2_PLAN.replace("d_safe: 30", "routing: tree, d_safe: 30"),
     "uavs[1].autonomy.guidance.infoplan.routing", "tree", "'mst', 'chain' or 'none'"),
    (U2_PLAN, U2_PLAN.replace("d_safe: 30", "dsafe: 30"), "uavs[1].autonomy.guidance.infoplan.dsafe", 30,
     "no such key"),
    ("{type: infoplan, speed: 15, altitude: 60", "{type: hold, speed: 15, altitude: 60",
     "uavs[1].autonomy.guidance.infoplan", {"d_safe": 30.0, "horizon": 2, "heading_rates": 5},
     "unless the type is infoplan"),
    ("speed: 15, altitude: 60", "speed: 12, altitude: 60", "uavs[1].autonomy.guidance.speed", 12,
     "the team plan flies one speed"),
    ("rate_hz: 1\n      estimator: {type: scif, params: {q: 0.01}}\n      fusion: {method: base_station}\n      "
     "guidance: {type: infoplan, speed: 15, altitude: 60", "rate_hz: 2\n      estimator: {type: scif, params: {q: "
     "0.01}}\n      fusion: {method: base_station}\n      guidance: {type: infoplan, speed: 15, altitude: 60",
     "uavs[1].autonomy.rate_hz", 2, "the team plan's step T_s is the agents' period"),
    ("gamma: 20}", "gamma: 20, routing: star}", "comms.routing", "star", "'mst' or 'chain'"),
])
def test_bad_keys_are_named(tmp_path, old, new, path, value, expected):
    assert old in TEAM
    file = write(tmp_path, TEAM.replace(old, new, 1))
    with pytest.raises(WorldError) as info:
        load_world(file)
    issue = next((i for i in info.value.issues if i.path == path), None)
    assert issue is not None, [i.path for i in info.value.issues]
    assert issue.value == value
    assert expected in issue.expected and str(file) in str(info.value)


def test_routing_none_needs_no_radio_but_base_station_fusion_does(tmp_path):
    text = TEAM.replace("model: rayleigh", "model: perfect").replace("d_safe: 30", "routing: none, d_safe: 30")
    with pytest.raises(WorldError) as info:
        load_world(write(tmp_path, text))
    assert [(i.path, i.value) for i in info.value.issues] == [("comms.model", "perfect")]
    assert "fusion method base_station" in info.value.issues[0].expected
    alone = text.replace("fusion: {method: base_station}", "fusion: {method: none}")
    assert load_world(write(tmp_path, alone)).world.comms.model == "perfect"


def test_infoplan_needs_a_radar_and_every_uav_in_the_team(tmp_path):
    no_radar = TEAM.replace(f"      - {RADAR}\n", "      - {type: bearing, rate_hz: 1, sigma_azimuth_deg: 3}\n", 1)
    with pytest.raises(WorldError) as info:
        load_world(write(tmp_path, no_radar))
    issue = next(i for i in info.value.issues if i.path == "uavs[0].sensors")
    assert issue.value == ["bearing"] and "a radar" in issue.expected
    third = TEAM + "  - {id: u3, initial: {position: [90, 0, 70]}}\n"
    with pytest.raises(WorldError) as info:
        load_world(write(tmp_path, third))
    issue = info.value.issues[0]
    assert (issue.path, issue.value) == ("uavs[2].autonomy.guidance.type", "hold")
    assert "every UAV of the world must fly it" in issue.expected


def test_links_may_name_the_base_station_only_when_there_is_one(tmp_path):
    linked = TEAM.replace("gamma: 20}", "gamma: 20, links: [[u1, u2], [u1, base]]}")
    assert load_world(write(tmp_path, linked)).world.comms.links == [("u1", "u2"), ("u1", "base")]
    no_base = TEAM.replace("comms: {model: rayleigh, block_by_buildings: false, base_station: [-500, -800, 20], "
                           "gamma: 20}", "comms: {model: rayleigh, links: [[u1, base]]}")
    no_base = no_base.replace("fusion: {method: base_station}", "fusion: {method: none}")
    no_base = no_base.replace("guidance: {type: infoplan, speed: 15", "guidance: {type: hold, speed: 15")
    no_base = no_base.replace(", infoplan: {d_safe: 30, horizon: 2, heading_rates: 5}", "")
    with pytest.raises(WorldError) as info:
        load_world(write(tmp_path, no_base))
    issue = info.value.issues[0]
    assert (issue.path, issue.value) == ("comms.links[0][1]", "base")


def test_a_tracker_passed_in_code_must_be_the_information_filter(tmp_path):
    from simulator.api import run
    from tests.simulator.user_modules.centroid import CentroidEstimator

    with pytest.raises(WorldError) as info:
        run(write(tmp_path, TEAM), duration=1.0, out_dir=tmp_path / "run", estimator=CentroidEstimator)
    issue = info.value.issues[0]
    assert issue.path == "uavs[0].autonomy.estimator" and "fusion method base_station" in issue.expected
    assert not (tmp_path / "run").exists()  # nothing ran


def test_the_shipped_world_and_its_variants_load():
    base = load_world("relay_tracking").world
    assert [u.autonomy.fusion.method for u in base.uavs] == ["base_station"] * 2
    assert [u.autonomy.guidance.type for u in base.uavs] == ["infoplan"] * 2
    assert base.comms.base_station == (-100.0, -160.0, 13.0)
    chain = load_world("relay_tracking", ["comms.routing=chain"]).world
    assert chain.comms.routing == "chain"
    none = load_world("relay_tracking", [f"uavs[{i}].autonomy.guidance.infoplan.routing=none"
                                         for i in range(2)]).world
    assert {u.autonomy.guidance.infoplan.routing for u in none.uavs} == {"none"}
    parked = load_world("relay_tracking", ["ground_vehicles[0].route={roads: [park2.f], start_s: 20}"]).world
    assert parked.ground_vehicles[0].route.roads == ["park2.f"]
