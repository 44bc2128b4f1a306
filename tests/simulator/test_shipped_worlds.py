"""Every shipped world runs: a short run of each completes with a record of every UAV and its target."""

import pytest

from simulator.api import run
from worlds.loader import load_world, shipped_worlds


@pytest.mark.parametrize("name", sorted(shipped_worlds()))
def test_shipped_world_runs(tmp_path, name):
    world = load_world(name).world
    res = run(name, duration=2.0, seed=1, out_dir=tmp_path)
    assert res.status == "completed", res.error
    assert res.metrics["sim_time_s"] == pytest.approx(2.0)
    assert set(res.metrics["uavs"]) == {u.id for u in world.uavs}
    truth = res.stream("uav_truth")
    assert set(truth["uav"].tolist()) == set(range(len(world.uavs)))
    assert (abs(truth["z"]) < 1e4).all()
    for i, u in enumerate(world.uavs):  # the solver health of MPC guidance reaches the metrics
        m = res.metrics["uavs"][u.id]
        if u.autonomy.guidance.type == "nmpc":
            assert {"solver_calls", "solver_failures", "solver_retries", "solver_escalations"} <= set(m), (i, m)
