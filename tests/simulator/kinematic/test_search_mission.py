"""The kinematic set-membership search mission (the paper's section V on a smaller area): line-of-sight links, the
MPC team shrinking the unexplored set with its guarantee kept, against random turns, and decoys erased."""

import numpy as np
import pytest
import shapely

from autonomy.guidance.search.planner import SearchConfig
from simulator.kinematic.search_mission import MissionConfig, SearchMission, line_of_sight_graph

CFG = SearchConfig()


def test_line_of_sight_graph():
    obst = shapely.box(40, -10, 60, 10)
    A = line_of_sight_graph(np.array([[0.0, 0.0], [100.0, 0.0], [50.0, 50.0]]), obst)
    assert not A[0, 1] and A[0, 2] and A[1, 2] and not A[0, 0]


SMALL = dict(area_size=(250.0, 250.0), n_uavs=3, n_targets=2, n_decoys=2, n_obstacles=2,
             obstacle_sides=(20.0, 40.0), steps=80)


@pytest.fixture(scope="module")
def mpc_mission():
    return SearchMission(MissionConfig(control="mpc", **SMALL), np.random.default_rng(0)).run()


def test_mission_mpc_shrinks_xbar_keeps_guarantee(mpc_mission):
    r = mpc_mission
    assert r.guarantee.all()
    assert r.collisions(CFG.d_col) == 0
    xbar = r.area_Xbar.mean(axis=1)
    assert xbar[0] > 0.7
    assert xbar[40:].mean() < 0.15  # the team holds the unexplored set below 15 % of the area
    assert xbar.min() < 0.1


def test_mission_mpc_beats_random_turns(mpc_mission):
    rnd = SearchMission(MissionConfig(control="random", **SMALL), np.random.default_rng(0)).run()
    assert rnd.guarantee.all()
    assert mpc_mission.area_Xbar[40:].mean() < 0.6 * rnd.area_Xbar[40:].mean()


def test_mission_decoys_taken_then_erased(mpc_mission):
    """Each decoy that entered X (taken for a target) is later erased by a view from outside its cone."""
    d = mpc_mission.decoy_in_X
    assert d.any()
    for j in np.flatnonzero(d.any(axis=0)):
        first = int(np.argmax(d[:, j]))
        assert not d[first:, j].all(), f"decoy {j} never erased after step {first + 1}"


def _streams(seed: int) -> dict:
    world, motion, noise, control = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(4))
    return {"rng": world, "motion_rng": motion, "noise_rng": noise, "control_rng": control}


def test_own_motion_stream_gives_the_same_movers_whatever_the_control():
    small = {**SMALL, "steps": 6}
    cfgs = [MissionConfig(control="mpc", **small), MissionConfig(control="random", **small),
            MissionConfig(control="mpc", search=SearchConfig(max_turn=np.pi / 2), start_turn=np.pi / 4, **small)]
    seen = []

    def run(cfg):
        s = _streams(11)
        m = SearchMission(cfg, s.pop("rng"), **s)
        starts = m.uav_xy.copy()
        res = m.run(on_step=lambda mm: seen.append((cfg.control, mm.k, len(mm.last_scans))))
        return starts, res

    (s0, a), (s1, b), (s2, c) = (run(cfg) for cfg in cfgs)
    assert np.array_equal(a.mover_xy, b.mover_xy) and np.array_equal(a.mover_xy, c.mover_xy)
    assert np.array_equal(s0, s1) and np.array_equal(s0, s2)  # starts pinned by start_turn
    assert not np.array_equal(a.uav_xy, b.uav_xy)
    assert seen[:6] == [("mpc", k, 3) for k in range(1, 7)]


def test_start_turn_is_validated():
    with pytest.raises(ValueError, match=r"MissionConfig.start_turn must be in \(0, pi\] rad, got 0.0"):
        MissionConfig(start_turn=0.0)
