"""What a replay reads from the run's world file, through the schema: names, standoff radii, body sizes."""

import numpy as np
import pytest

from simulator.render.world_view import ReplayWorld, read_world
from vehicles.car.params import load_car
from vehicles.quadrotor.airframes import load_airframe

WORLD = """\
uavs:
  - {id: hawk, airframe: survey_quad, initial: {position: [0, 0, 60]},
     autonomy: {guidance: {type: nmpc, standoff_m: 140}}}
  - {id: kite, initial: {position: [10, 0, 60]}}
roads:
  nodes: {a: [0, 0], b: [300, 0]}
  streets: [{id: south, nodes: [a, b]}]
ground_vehicles:
  - {id: car, type: van, route: {random_walk_from: south.f}}
decoys:
  - {id: d0, position: [5, 5, 0.7], yaw_deg: 90}
"""


@pytest.mark.filterwarnings("error")
def test_reads_the_typed_world(tmp_path):
    (tmp_path / "world.yaml").write_text(WORLD)
    w = ReplayWorld(read_world(tmp_path))
    assert [w.uav_name(u) for u in range(3)] == ["hawk", "kite", "uav2"]
    assert w.standoff(0) == 140.0 and w.standoff(1) is None and w.standoff(2) is None  # hold draws no circle
    van, sedan = load_car("van"), load_car("sedan")
    assert w.vehicle_size(0) == (van.length, van.width, van.height)
    assert w.vehicle_size(1) == (sedan.length, sedan.width, sedan.height)  # unlisted: the schema's default type
    assert w.uav_arm_length() == load_airframe("survey_quad").arm_length
    [d] = w.decoys()
    assert d.size == (sedan.length, sedan.width, sedan.height) and d.yaw == pytest.approx(np.pi / 2)
    np.testing.assert_array_equal(d.position, [5.0, 5.0, 0.7])


def test_a_world_that_does_not_validate_is_replayed_as_the_empty_world(tmp_path):
    (tmp_path / "world.yaml").write_text("uavs: [{id: a}]\n")  # no initial pose
    with pytest.warns(UserWarning, match="current schema"):
        w = ReplayWorld(read_world(tmp_path))
    assert w.uav_name(0) == "uav0" and w.standoff(0) is None and w.decoys() == []
    with pytest.warns(UserWarning):
        read_world(tmp_path / "missing")
