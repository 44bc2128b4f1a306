"""Paper 004's world on PyBullet quadrotors: set-membership UAVs scan with box sensors, decoys are seen only from
inside their visibility cones, buildings cut the links between UAVs, and every true target stays inside ``X ∪ X̄``
of every UAV (the guarantee, judged against the physics truth)."""

import numpy as np
import pytest

from simulator.api import run

HOVER = """\
name: decoy_test
sim: {duration_s: 3, record_hz: 10}
terrain: {size: [800, 400]}
roads:
  nodes: {a: [250, -30], b: [400, -30]}
  streets:
    - {id: s, nodes: [a, b], speed_limit: 1.2}
buildings:
  - {center: [150, 0], size: [20, 40, 110]}
ground_vehicles:
  - {id: car, route: {roads: [s.f], start_s: 50}}
decoys:
  # straight below-right of uav1, its cone's axis pointing at uav1 (tilt atan(10 / 99.3) = 5.75 deg): seen
  - {id: seen, position: [10, 0, 0.72], yaw_deg: 180, tilt_deg: 5.75, cone_half_angle_deg: 10}
  # below-left of uav1, its cone pointing east, 40 deg from the vertical: uav1 lies 32 deg off its axis, unseen
  - {id: unseen, position: [-10, 10, 0.72], yaw_deg: 0, tilt_deg: 40, cone_half_angle_deg: 10}
comms: {model: perfect, block_by_buildings: true}
uavs:
  - id: uav1
    initial: {position: [0, 0, 100]}
    sensors: &box
      - {type: box, rate_hz: 1, noise_bound: 5}
    autonomy: &hover
      rate_hz: 1
      estimator: {type: set_membership, set_membership: {area: [-100, -100, 400, 100], max_target_speed: 1.4}}
      fusion: {method: sets}
      guidance: {type: hold}
  - id: uav2
    initial: {position: [300, 0, 100]}
    sensors: *box
    autonomy: *hover
"""
N_CARS = 1  # the truth rows of the decoys follow the ground vehicles'


@pytest.fixture(scope="module")
def hover(tmp_path_factory):
    path = tmp_path_factory.mktemp("hover") / "w.yaml"
    path.write_text(HOVER)
    out = tmp_path_factory.mktemp("hover_run")
    return path, run(path, seed=3, out_dir=out, plots=True)


def test_a_decoy_is_detected_only_from_inside_its_cone_and_enters_X(hover):
    _, res = hover
    assert res.status == "completed", res.error
    det = res.stream("detections")
    mine = det["uav"] == 0
    seen = set(det["truth_id"][mine].tolist())
    assert seen == {N_CARS + 0}  # the decoy whose cone holds uav1, at every scan; never the other one
    assert mine.sum() == 3
    assert set(det["truth_id"][det["uav"] == 1].tolist()) == {0}  # uav2 sees the car below it
    s = res.stream("search")
    assert (s["decoys_in_X"][s["uav"] == 0] == 1).all()  # the seen decoy is taken for a target; the unseen erased
    assert (s["decoys_in_X"][s["uav"] == 1] == 0).all()


def test_the_building_between_the_uavs_cuts_their_link(hover, tmp_path):
    path, res = hover
    s = res.stream("search")
    assert (s["links"] == 0).all() and (s["fused_with"] == 0).all()
    clear = run(path, seed=3, out_dir=tmp_path, overrides=["comms.block_by_buildings=false"])
    c = clear.stream("search")
    assert (c["links"] == 1).all() and (c["fused_with"] == 1).all()
    # fused: both UAVs hold one X̄, smaller than either alone by the other's footprint
    by = {u: c["area_Xbar"][c["uav"] == u] for u in (0, 1)}
    np.testing.assert_array_equal(by[0], by[1])
    alone = s["area_Xbar"][s["uav"] == 0]
    assert (by[0] < alone - 0.05).all()


def test_the_guarantee_holds_and_reaches_the_metrics(hover):
    _, res = hover
    m = res.metrics["search"]
    assert m["steps"] == 3 and m["guarantee_checks"] == 3 * 2 and m["guarantee_violations"] == 0
    assert m["guarantee_rate"] == 1.0 and m["late_scans"] == 0
    s = res.stream("search")
    assert (s["targets_inside"] == 1).all() and (s["targets"] == 1).all()
    assert "targets" not in res.metrics  # searchers hold sets, not point estimates: no error against a car
    assert (res.out_dir / "plots" / "search.png").exists()


@pytest.mark.slow
def test_the_shipped_search_keeps_every_target_in_its_sets_and_shrinks_the_unknown(tmp_path):
    """40 s of ``search_decoys``: 4 UAVs × 2 cars × 40 steps of guarantee checks against the physics cars, all held;
    the team's undetected set shrinks as the UAVs sweep; no UAV touches anything and every decision had a safe
    candidate once the quadrotors are up to speed."""
    res = run("search_decoys", duration=40.0, seed=2, out_dir=tmp_path)
    assert res.status == "completed", res.error
    m = res.metrics["search"]
    assert m["guarantee_checks"] == 40 * 4 * 2 and m["guarantee_violations"] == 0
    s = res.stream("search")
    mean = np.array([s["area_Xbar"][s["t"] == t].mean() for t in np.unique(s["t"])])
    assert mean[0] < 0.95 and mean[-1] < mean[0] - 0.1
    assert all(u["collisions"] == 0 for u in res.metrics["uavs"].values())
    assert (s["fused_with"] > 0).any()  # the team fuses where it sees each other
