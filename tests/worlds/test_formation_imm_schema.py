"""World files of paper 003's pieces (estimator imm, fusion measurements, guidance formation): good ones load with
their defaults, and every bad key is named with its path, its value and what was expected, before anything runs."""


import pytest

from worlds.errors import WorldError
from worlds.loader import load_world
from world_files import write

TEAM = """\
name: team
uavs:
  - id: u1
    initial: {position: [0, 0, 50]}
    sensors:
      - {type: bearing, rate_hz: 10, sigma_azimuth_deg: 5}
    autonomy:
      rate_hz: 10
      estimator: {type: imm, model: cv, imm: {turn_rate_deg_s: 20, p_stay: 0.9}}
      fusion: {method: measurements}
      guidance: {type: formation, speed: 15, altitude: 50, formation: {ranges: [100, 100]}}
  - id: u2
    initial: {position: [50, 0, 60]}
    sensors:
      - {type: bearing, rate_hz: 10, sigma_azimuth_deg: 5}
    autonomy:
      rate_hz: 10
      estimator: {type: imm}
      fusion: {method: measurements}
      guidance: {type: formation}
"""


def test_the_new_keys_load_with_their_defaults(tmp_path):
    world = load_world(write(tmp_path, TEAM)).world
    a, b = (u.autonomy for u in world.uavs)
    assert (a.estimator.type, a.estimator.imm.turn_rate_deg_s, a.estimator.imm.p_stay) == ("imm", 20, 0.9)
    assert a.estimator.imm.q_turn == 0.05 and b.estimator.imm is None
    assert a.fusion.method == b.fusion.method == "measurements"
    assert a.guidance.formation.ranges == [100, 100] and a.guidance.formation.geometry == "optimal"
    assert b.guidance.formation is None


def test_the_factories_build_what_the_keys_say(tmp_path):
    import math

    from simulator.registry import build_estimator, build_guidance

    world = load_world(write(tmp_path, TEAM)).world
    trk = build_estimator(world.uavs[0], 0)
    assert (trk.config.filter, trk.config.stack_scans) == ("imm", True)
    assert trk.config.imm_turn_rate == pytest.approx(math.radians(20)) and trk.config.imm_p_stay == 0.9
    law = build_guidance(world.uavs[1], 1, len(world.uavs), ())
    cfg = law.config
    assert (law.agent_id, cfg.team_size, cfg.dt, cfg.ranges) == (1, 2, 0.1, None)
    assert cfg.sigma_bearing == pytest.approx(math.radians(5))  # from the UAV's bearing sensor
    assert (cfg.max_speed, cfg.altitude) == (12.0, 60.0)  # the guidance section's defaults


U2_EST = "estimator: {type: imm}\n      fusion: {method: measurements}\n      guidance: {type: formation}\n"


@pytest.mark.parametrize("old, new, path, value, expected", [
    ("{type: imm, model: cv, imm:", "{type: imm, model: singer, imm:", "uavs[0].autonomy.estimator.model", "singer",
     "'cv'"),
    ("{type: imm, model: cv, imm:", "{type: ekf, model: cv, imm:", "uavs[0].autonomy.estimator.imm",
     {"modes": "cv_ct", "turn_rate_deg_s": 20.0, "q_turn": 0.05, "p_stay": 0.9, "mean_moving_s": 30.0,
      "mean_stopped_s": 10.0, "stopped_q": 0.01}, "unless the type is imm"),
    ("p_stay: 0.9", "p_stay: 1.5", "uavs[0].autonomy.estimator.imm.p_stay", 1.5, "less than 1"),
    ("turn_rate_deg_s: 20", "turn_rate_deg_s: -3", "uavs[0].autonomy.estimator.imm.turn_rate_deg_s", -3,
     "greater than 0"),
    ("turn_rate_deg_s: 20", "turn_rate: 20", "uavs[0].autonomy.estimator.imm.turn_rate", 20, "no such key"),
    (U2_EST, U2_EST.replace("measurements", "none"), "uavs[1].autonomy.fusion.method", "none", "'measurements'"),
    (U2_EST, U2_EST.replace("type: imm", "type: scif"), "uavs[1].autonomy.estimator.type", "scif",
     "fusion method measurements needs the built-in tracker"),
    ("formation: {ranges: [100, 100]}", "formation: {ranges: [100, 100, 100]}",
     "uavs[0].autonomy.guidance.formation.ranges", [100, 100, 100], "one range per UAV of the world (2 values"),
    ("formation: {ranges: [100, 100]}", "formation: {trail_fan_deg: 120}",
     "uavs[0].autonomy.guidance.formation.trail_fan_deg", 120, "less than or equal to 90"),
    ("formation: {ranges: [100, 100]}", "formation: {geometry: circle}",
     "uavs[0].autonomy.guidance.formation.geometry", "circle", "'optimal' or 'trail'"),
    ("formation: {ranges: [100, 100]}", "formation: {gains: {kp_shape: 0}}",
     "uavs[0].autonomy.guidance.formation.gains.kp_shape", 0, "greater than 0"),
    ("{type: formation, speed: 15", "{type: hold, speed: 15", "uavs[0].autonomy.guidance.formation",
     "ranges", "unless the type is formation"),
])
def test_bad_keys_are_named(tmp_path, old, new, path, value, expected):
    assert old in TEAM
    file = write(tmp_path, TEAM.replace(old, new))
    with pytest.raises(WorldError) as info:
        load_world(file)
    issue = info.value.issues[0]
    assert issue.path == path
    if isinstance(value, str) and isinstance(issue.value, dict):
        assert value in issue.value
    else:
        assert issue.value == value
    assert expected in issue.expected and str(file) in str(info.value)


def test_formation_without_a_bearing_sensor_needs_a_sigma(tmp_path):
    text = TEAM.replace("      - {type: bearing, rate_hz: 10, sigma_azimuth_deg: 5}\n    autonomy:\n      rate_hz: 10\n"
                        "      estimator: {type: imm}",
                        "      - {type: radar, rate_hz: 10, sigma_range: 5, sigma_azimuth_deg: 2}\n    autonomy:\n"
                        "      rate_hz: 10\n      estimator: {type: imm}")
    assert text != TEAM
    with pytest.raises(WorldError) as info:
        load_world(write(tmp_path, text))
    issue = info.value.issues[0]
    assert (issue.path, issue.value) == ("uavs[1].autonomy.guidance.formation.sigma_bearing_deg", None)
    fixed = text.replace("guidance: {type: formation}\n",
                         "guidance: {type: formation, formation: {sigma_bearing_deg: 2}}\n")
    assert load_world(write(tmp_path, fixed)).world.uavs[1].autonomy.guidance.formation.sigma_bearing_deg == 2


def test_a_formation_of_one_is_refused(tmp_path):
    one = TEAM[:TEAM.index("  - id: u2")].replace("ranges: [100, 100]", "ranges: [100]")
    with pytest.raises(WorldError) as info:
        load_world(write(tmp_path, one))
    assert info.value.issues[0].path == "uavs[0].autonomy.guidance.type"
    assert "team of >= 2 UAVs" in info.value.issues[0].expected


def test_the_shipped_world_and_its_case_variants_load():
    base = load_world("formation_imm").world
    assert [u.autonomy.fusion.method for u in base.uavs] == ["measurements"] * 3
    case4 = load_world("formation_imm", ["ground_vehicles[0].route.roads=[lead.f, sbend.f]"]).world
    assert case4.ground_vehicles[0].route.roads == ["lead.f", "sbend.f"]
    trail = load_world("formation_imm", [f"uavs[{i}].autonomy.guidance.formation={{geometry: trail}}"
                                         for i in range(3)]).world
    assert {u.autonomy.guidance.formation.geometry for u in trail.uavs} == {"trail"}
