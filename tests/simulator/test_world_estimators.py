"""Road-constrained estimators named in a world file: built on the world's road map, rejected without one."""

import numpy as np
import pytest

from autonomy.estimation.road.tracker import RoadConstrainedTracker
from simulator.api import run
from simulator.registry import build_estimator
from worlds.errors import WorldError
from worlds.loader import load_world


@pytest.mark.parametrize("kind", ["maekf", "ecukf"])
def test_road_standoff_runs_with_a_road_constrained_estimator(tmp_path, kind):
    sets = [f"uavs[{i}].autonomy.estimator.type={kind}" for i in (0, 1)]
    res = run("road_standoff", duration=20.0, seed=3, out_dir=tmp_path, overrides=sets)
    assert res.status == "completed"
    est = res.stream("estimates", uav=0)
    ok = est["valid"].astype(bool)
    assert ok.mean() > 0.8
    truth = res.target_truth_at(est["t"][ok])
    err = np.hypot(est["x"][ok] - truth[:, 0], est["y"][ok] - truth[:, 1])
    assert np.median(err) < 20.0  # σ = 20 m / 7° radar at ~150 m: a tracking-grade estimate, not a lost track


def test_road_constrained_estimator_is_built_on_the_road_network():
    loaded = load_world("road_standoff", ["uavs[0].autonomy.estimator.type=ecukf",
                                          "uavs[0].autonomy.estimator.road={spawn_distance: 25}"])
    from worlds.build import build_geometry

    geometry = build_geometry(loaded.world, loaded.path, np.random.default_rng(0))
    est = build_estimator(loaded.world.uavs[0], 0, geometry.network)
    assert isinstance(est, RoadConstrainedTracker)
    assert est.road_config.road.variant == "ecukf" and est.road_config.road.spawn_distance == 25
    assert est.config.filter == "ukf"  # the unconstrained fallback of the ECUKF


def test_road_estimator_without_roads_is_rejected_with_its_key_path(tmp_path):
    path = tmp_path / "w.yaml"
    path.write_text("uavs:\n  - id: a\n    initial: {position: [0, 0, 50]}\n"
                    "    autonomy: {estimator: {type: maekf}}\n")
    with pytest.raises(WorldError) as info:
        load_world(path)
    assert "uavs[0].autonomy.estimator.type = 'maekf'" in str(info.value)
    assert "this world has no roads" in str(info.value)


def test_record_and_video_show_the_road_the_filter_is_constrained_to(tmp_path):
    from simulator.render.config import RenderConfig
    from simulator.render.replay import Replayer
    from simulator.render.stage import load_geometry

    sets = [f"uavs[{i}].autonomy.estimator.type=maekf" for i in (0, 1)]
    res = run("road_standoff", duration=10.0, seed=3, out_dir=tmp_path, overrides=sets)
    est = res.stream("estimates", uav=0)
    on_road = est["road"] != ""
    assert on_road.mean() > 0.5
    geometry = load_geometry(tmp_path / "geometry.npz")
    assert set(est["road"][on_road]) <= set(geometry.road_ids)
    # the estimate lies near the centre-line of the road it is constrained to
    k = int(np.flatnonzero(on_road)[-1])
    line = geometry.roads[geometry.road_ids.index(est["road"][k])]
    assert np.min(np.hypot(line[:, 0] - est["x"][k], line[:, 1] - est["y"][k])) < 10.0
    rep = Replayer(tmp_path, RenderConfig(width=64, height=48, renderer="tiny", progress=False))
    try:
        marks = rep.overlay_frame(float(est["t"][k])).constrained_roads
    finally:
        rep.close()
    assert len(marks) >= 1 and np.allclose(marks[0][1][:, :2], line[:, :2])  # UAV 0's mark comes first
