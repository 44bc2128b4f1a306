"""World files of paper 004's pieces (estimator set_membership, fusion sets, guidance search, decoys): a good team
loads with its settings, and every bad key is named with its path, its value and what was expected, before anything
runs; a YAML alias is one place per use, so an override changes only the entry it names."""


import pytest

from worlds.errors import WorldError
from worlds.loader import load_world
from world_files import write

TEAM = """\
name: team
roads:
  nodes: {a: [0, 0], b: [300, 0]}
  streets:
    - {id: s, nodes: [a, b], speed_limit: 1.2}
ground_vehicles:
  - {id: car, route: {roads: [s.f]}}
decoys:
  - {id: d1, position: [50, 50, 0.7], yaw_deg: 30, cone_half_angle_deg: 10}
comms: {model: perfect, block_by_buildings: true}
uavs:
  - id: u1
    initial: {position: [0, 0, 100]}
    sensors: &box
      - {type: box, rate_hz: 1, noise_bound: 5}
    autonomy:
      rate_hz: 1
      estimator: &sets {type: set_membership, set_membership: {area: [0, 0, 400, 400], max_target_speed: 1.4}}
      fusion: {method: sets}
      guidance: &search {type: search, speed: 16, altitude: 100, search: {max_turn_deg: 30, clearance_margin: 3}}
  - id: u2
    initial: {position: [100, 0, 95]}
    sensors: *box
    autonomy:
      rate_hz: 1
      estimator: *sets
      fusion: {method: sets}
      guidance: *search
"""


def test_a_search_team_loads_with_its_settings(tmp_path):
    w = load_world(write(tmp_path, TEAM)).world
    u = w.uavs[0]
    assert u.autonomy.estimator.set_membership.area == (0, 0, 400, 400)
    assert u.autonomy.guidance.search.max_turn_deg == 30 and u.autonomy.guidance.search.alpha_m == 1.3
    assert w.decoys[0].tilt_deg is None and w.decoys[0].cone_half_angle_deg == 10


def test_an_override_of_an_aliased_entry_changes_only_that_uav(tmp_path):
    w = load_world(write(tmp_path, TEAM), overrides=["uavs[1].autonomy.guidance.search.max_turn_deg=20",
                                                     "uavs[0].sensors[0].noise_bound=3"]).world
    assert [u.autonomy.guidance.search.max_turn_deg for u in w.uavs] == [30, 20]
    assert [u.sensors[0].noise_bound for u in w.uavs] == [3, 5]


@pytest.mark.parametrize("old, new, path, value, expected", [
    ("estimator: &sets {type: set_membership, set_membership: {area: [0, 0, 400, 400], max_target_speed: 1.4}}",
     "estimator: &sets {type: set_membership}",
     "uavs[0].autonomy.estimator.set_membership", "None", "the search area and the targets' speed bound"),
    ("area: [0, 0, 400, 400]", "area: [0, 0, -400, 400]",
     "uavs[0].autonomy.estimator.set_membership", "-400", "max > min"),
    ("max_target_speed: 1.4}", "max_target_speed: 1.0}",
     "uavs[0].autonomy.estimator.set_membership.max_target_speed", "1.0", "fastest street's speed limit (1.2 m/s"),
    ("{type: box, rate_hz: 1, noise_bound: 5}", "{type: box, rate_hz: 2, noise_bound: 5}",
     "uavs[0].sensors[0].rate_hz", "2", "the agent's rate_hz (1)"),
    ("{type: box, rate_hz: 1, noise_bound: 5}", "{type: bearing, rate_hz: 1, sigma_azimuth_deg: 2}",
     "uavs[0].sensors", "bearing", "a box sensor"),
    ("search: {max_turn_deg: 30, clearance_margin: 3}", "search: {n_controls: 6}",
     "uavs[0].autonomy.guidance.search.n_controls", "6", "an odd number"),
    ("cone_half_angle_deg: 10}", "cone_half_angle_deg: 10, tilt_deg: 200}",
     "decoys[0].tilt_deg", "200", "less than or equal to 180"),
])
def test_bad_search_settings_are_named(tmp_path, old, new, path, value, expected):
    assert old in TEAM
    with pytest.raises(WorldError) as err:
        load_world(write(tmp_path, TEAM.replace(old, new, 1)))
    text = str(err.value)
    assert path in text and value in text and expected in text, text


@pytest.mark.parametrize("overrides, path, expected", [
    (["uavs[1].autonomy.estimator={type: ekf}"], "uavs[1].autonomy.fusion.method",
     "estimator type set_membership: 'sets' works on that estimator's sets (the estimator type is 'ekf')"),
    (["uavs[1].autonomy.estimator={type: ekf}", "uavs[1].autonomy.fusion.method=none"],
     "uavs[1].autonomy.guidance.type", "'search' works on that estimator's sets"),
    (["uavs[0].autonomy.fusion.method=convex"], "uavs[0].autonomy.fusion.method",
     "'sets' or 'none': the set_membership estimator shares sets"),
    (["uavs[0].autonomy.guidance={type: hold, search: {}}"], "uavs[0].autonomy.guidance.search",
     "no 'search' settings unless the type is search"),
    (["uavs[1].autonomy.estimator.set_membership.area=[0, 0, 500, 500]"], "uavs[1].autonomy.estimator.set_membership",
     "the area, max_target_speed and agent rate_hz of uavs[0]"),
    (["uavs[1].autonomy.estimator={type: ekf, set_membership: {area: [0, 0, 1, 1]}}",
      "uavs[1].autonomy.fusion.method=none", "uavs[1].autonomy.guidance.type=hold"],
     "uavs[1].autonomy.estimator.set_membership", "no 'set_membership' settings unless the type is set_membership"),
])
def test_inconsistent_search_teams_are_named(tmp_path, overrides, path, expected):
    with pytest.raises(WorldError) as err:
        load_world(write(tmp_path, TEAM), overrides=overrides)
    text = str(err.value)
    assert path in text and expected in text, text


def test_search_guidance_without_a_box_sensor_is_an_error_before_the_run(tmp_path):
    """The UAV's world entry names the missing sensor; nothing is built."""
    text = TEAM.replace("    sensors: *box\n", "    sensors: []\n", 1)
    with pytest.raises(WorldError) as err:
        load_world(write(tmp_path, text))
    assert "uavs[1].sensors" in str(err.value) and "a box sensor" in str(err.value)
