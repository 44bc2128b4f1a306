"""How a user tests their own autonomy module against physics ground truth (the README's example)."""

import numpy as np
import pytest

from simulator.api import run
from tests.simulator.user_modules.centroid import CentroidEstimator


def test_user_estimator_passed_in_code(tmp_path):
    result = run("demo", duration=8.0, seed=2, out_dir=tmp_path, estimator=CentroidEstimator)
    assert result.status == "completed"
    est = result.stream("estimates", uav=0)
    ok = est["valid"].astype(bool)
    assert ok.mean() > 0.5
    truth = result.target_truth_at(est["t"][ok])
    err = np.hypot(est["x"][ok] - truth[:, 0], est["y"][ok] - truth[:, 1])
    # a 2-s sliding median of radar fixes of a car moving up to 12 m/s lags by at most ~12 m
    assert np.median(err) < 15.0
    # metrics.json's figure is the same error, computed live against the exact truth of each agent step
    assert result.metrics["targets"]["car1"]["uav1"]["position_error_mean_m"] == pytest.approx(err.mean(), abs=1.0)
    # demo has traffic: the single-target estimator was wrapped, fed the target track's detections by the built-in
    # multi-target tracker, whose tracks are recorded
    tracks = result.stream("tracks", uav=0)
    assert tracks["track"].size and tracks["is_target"].astype(bool).any()


def test_user_multi_target_tracker_is_used_as_it_is(tmp_path):
    from tests.simulator.user_modules.fix_tracks import FixTracks

    made = []

    def factory(i, uav):
        made.append(FixTracks())
        return made[-1]

    result = run("demo", duration=6.0, seed=2, out_dir=tmp_path, estimator=factory)
    assert result.status == "completed"
    assert all(m.cued == 1 for m in made)  # the hand-off reached it
    tracks = result.stream("tracks", uav=0)
    assert tracks["track"].size and tracks["track"].min() >= 1000  # its own tracks, not the built-in tracker's
    assert "mot" in result.metrics["uavs"]["uav1"]
    assert result.metrics["targets"]["car1"]["uav1"]["identity_fraction"] is not None


def test_user_modules_named_in_the_world_file(tmp_path):
    prefix = "uavs[0].autonomy"
    result = run("demo", duration=6.0, seed=2, out_dir=tmp_path, overrides=[
        f"{prefix}.estimator.type=plugin",
        f"{prefix}.estimator.plugin=tests.simulator.user_modules.centroid:CentroidEstimator",
        f"{prefix}.estimator.params={{window_s: 3.0}}",
        f"{prefix}.guidance.type=plugin",
        f"{prefix}.guidance.plugin=tests.simulator.user_modules.centroid:CircleGuidance",
        f"{prefix}.guidance.params={{centre: [-60, -60], radius: 30, speed: 6, altitude: 40}}",
    ])
    assert result.status == "completed"
    ut = result.stream("uav_truth", uav=0)
    # the user's guidance flew the UAV: it climbs/descends towards 40 m and stays near its circle centre
    assert abs(ut["z"][-1] - 40.0) < 5.0
    assert np.max(np.hypot(ut["x"] + 60, ut["y"] + 60)) < 45.0


def test_bad_plugin_path_is_a_world_error(tmp_path):
    from worlds.errors import WorldError

    with pytest.raises(WorldError, match=r"uavs\[0\]\.autonomy\.estimator.*cannot import module 'no_such_mod'"):
        run("demo", out_dir=tmp_path, overrides=["uavs[0].autonomy.estimator.type=plugin",
                                                 "uavs[0].autonomy.estimator.plugin=no_such_mod:X"])
