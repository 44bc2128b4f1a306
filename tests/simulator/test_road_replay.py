"""Estimation-only replays of paper 002's estimators: recorded runs come back exactly, synthetic radars are exact."""

import json
import math

import numpy as np
import pytest

from simulator.cli import main
from simulator.reproduce.road_replay import (ReplayJob, car_accel_rms, drive, fused_errors, recorded_case, run_job,
                                             sine_network, synthetic_scans)


@pytest.fixture(scope="module")
def recorded_runs(tmp_path_factory):
    """Two 30 s ``road_standoff`` runs (the car passes a junction): the world's EKF, and the ECUKF on the road map."""
    out = {}
    for kind in ("ekf", "ecukf"):
        d = tmp_path_factory.mktemp(kind)
        sets = [] if kind == "ekf" else sum((["--set", f"uavs[{i}].autonomy.estimator.type={kind}"] for i in (0, 1)),
                                            [])
        assert main(["run", "road_standoff", "--duration", "30", "--quiet", "--no-plots", "--out", str(d), *sets]) == 0
        out[kind] = d
    return out


@pytest.mark.parametrize("kind", ["ekf", "ecukf"])
def test_replaying_a_run_with_its_own_estimator_gives_back_its_metrics(recorded_runs, kind):
    run = recorded_runs[kind]
    metrics = json.loads((run / "metrics.json").read_text())["targets"]["car1"]
    errors = fused_errors(recorded_case(run), kind)
    for i, uav in enumerate(("uav1", "uav2")):
        assert errors["local"][i] == pytest.approx(metrics[uav]["position_error_mean_m"], rel=1e-12)
        assert errors["fused"][i] == pytest.approx(metrics[f"{uav}_fused"]["position_error_mean_m"], rel=1e-12)


def test_a_replay_job_runs_every_estimator_on_the_same_detections(recorded_runs):
    run = recorded_runs["ekf"]
    res = run_job(ReplayJob("recorded", seed=0, run_dir=str(run), sigma_a=1.5))
    metrics = json.loads((run / "metrics.json").read_text())["targets"]["car1"]
    flown = np.mean([metrics[f"{u}_fused"]["position_error_mean_m"] for u in ("uav1", "uav2")])
    assert res["ekf"] == pytest.approx(flown, rel=1e-12)
    assert set(res) == {"ekf", "maekf", "ecukf", "ekf@sigma_a", "maekf@sigma_a", "ecukf@sigma_a", "accel_rms"}
    assert res["ekf@sigma_a"] != res["ekf"]  # the motion model was really replaced
    assert res["accel_rms"] == car_accel_rms(run) and 0.1 < res["accel_rms"] < 5.0


class _NoNoise:
    def normal(self, size):
        return np.zeros(size)


def test_synthetic_radars_measure_the_car_from_their_orbit():
    net = sine_network()
    ts, ps, _ = drive([net.roads["s.f"]], 20.0, ((0.0, 10.0),))
    scans = synthetic_scans(ts, ps, _NoNoise(), standoff=500.0, speed=40.0, altitude=100.0)
    assert len(scans) == 2
    for t, p in zip(ts, ps, strict=True):
        sensors = []
        for radar in scans:
            (m,) = radar[float(t)]
            d = np.array([p[0], p[1], 0.0]) - m.p_sensor_W
            assert m.z[0] == pytest.approx(math.hypot(500.0, 100.0)) and m.z[0] == pytest.approx(np.linalg.norm(d))
            assert m.z[1] == pytest.approx(math.atan2(d[1], d[0]))
            assert m.p_sensor_W[2] == 100.0 and m.t_meas == t
            sensors.append(m.p_sensor_W[:2] - p)
        assert np.dot(*sensors) == pytest.approx(-500.0**2)  # 180° apart
    # the orbit turns at speed / standoff
    a0, a1 = (math.atan2(*(scans[0][float(t)][0].p_sensor_W[:2] - p)[::-1])
              for t, p in ((ts[0], ps[0]), (ts[1], ps[1])))
    assert (a1 - a0) == pytest.approx(40.0 / 500.0 * (ts[1] - ts[0]))


def test_the_route_network_leaves_no_junction_to_choose_at(recorded_runs):
    from simulator.reproduce.road_replay import car_route, route_network, town_truth

    run = recorded_runs["ekf"]
    net, ts, ps, _ = town_truth(run)
    route = car_route(run)
    assert len(route) >= 2
    sub = route_network(net, route)
    assert set(route) <= set(sub.roads) and len(sub.roads) <= 2 * len(route)
    for a, b in zip(route[:-1], route[1:], strict=True):
        assert sub.successors(a) == [b] and b in net.successors(a) and len(net.successors(a)) > 1
    assert len(ts) == len(ps) and np.all(np.diff(ts) > 0)


def test_a_replay_that_fails_gives_nan_and_says_why(tmp_path):
    res = run_job(ReplayJob("recorded", seed=0, run_dir=str(tmp_path / "missing"), sigma_a=1.0))
    assert all(math.isnan(v) for k, v in res.items() if k != "error") and len(res) == 8
    assert "missing" in res["error"]
    with pytest.raises(ValueError, match="single_road, town_paper"):
        from simulator.reproduce.road_replay import _run_job

        _run_job(ReplayJob("somewhere", seed=0))


def test_the_single_road_car_drives_like_the_papers():
    from simulator.reproduce.road_replay import single_road_case

    case = single_road_case(seed=3, duration=150.0)
    assert 0.2 < case.accel_rms <= 1.0  # |a| <= 1 m/s² by construction, stops included in the RMS
    assert [len(s) for s in case.scans] == [len(case.truth)] * 2
