"""Whole runs through the real physics: determinism, the run record, interruption, errors, user plugins."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from simulator.api import run
from simulator.engine import RunOptions, run_world
from simulator.provenance import source_fingerprint
from simulator.runrecord import load_run
from tests.simulator.conftest import assert_records_equal
from worlds.loader import load_world

SKYTRACK = [sys.executable, "-m", "simulator.cli"]


def test_record_has_every_part(short_run):
    out = short_run.out_dir
    for name in ("world.yaml", "run.json", "metrics.json", "events.jsonl", "geometry.npz"):
        assert (out / name).is_file(), name
    assert json.loads((out / "run.json").read_text())["code"] == source_fingerprint()  # which source made it
    m = short_run.metrics
    for key in ("sim_time_s", "wall_time_s", "real_time_factor", "seed", "uavs", "targets"):
        assert key in m, key
    assert m["sim_time_s"] == pytest.approx(6.0) and m["seed"] == 5 and m["complete"] is True
    assert short_run.status == "completed" and short_run.record.status == "completed"
    ut = short_run.stream("uav_truth", uav=0)
    # 10 Hz recording over 6 s, and time stamps computed from integer ticks
    assert len(ut["t"]) == 60 and np.allclose(np.diff(ut["t"]), 0.1, atol=1e-12)
    assert np.array_equal(ut["tick"], np.arange(24, 24 * 61, 24))
    assert set(short_run.record.streams) >= {"uav_truth", "vehicle_truth", "estimates", "commands", "detections"}


def test_metrics_say_where_the_wall_time_went(short_run):
    m = short_run.metrics
    parts = m["wall_time_breakdown_s"]
    assert list(parts) == ["setup", "vehicles", "physics", "sensors", "autonomy", "record", "other"]
    assert all(v >= 0 for v in parts.values())
    assert sum(parts.values()) == pytest.approx(m["wall_time_s"], abs=2e-3)  # the parts add up to the whole
    # every phase of a run with quadrotors, a car, radars and agents took time; the tick dominates the remainder
    assert min(parts[k] for k in ("setup", "vehicles", "physics", "sensors", "autonomy", "record")) > 0
    assert parts["other"] < 0.5 * m["wall_time_s"]


def test_estimates_track_the_physics_truth(short_run):
    """The demo's EKF, fed by the radar, sits within a few radar sigmas of the car's true position."""
    est = short_run.stream("estimates", uav=0)
    ok = est["valid"].astype(bool)
    assert ok.sum() > 10
    truth = short_run.target_truth_at(est["t"][ok])
    err = np.hypot(est["x"][ok] - truth[:, 0], est["y"][ok] - truth[:, 1])
    assert np.median(err) < 10.0


def test_same_seed_same_record_and_different_seed_differs(short_run, tmp_path):
    again = run("demo", duration=6.0, seed=5, out_dir=tmp_path / "again")
    assert_records_equal(short_run, again)
    other = run("demo", duration=6.0, seed=6, out_dir=tmp_path / "other")
    a = short_run.record.stream("detections")
    b = other.record.stream("detections")
    assert a["z0"].shape != b["z0"].shape or not np.allclose(a["z0"], b["z0"])


def test_interrupt_leaves_partial_readable_record(tmp_path):
    def stop(tick):
        if tick == 2 * 240 + 100:
            raise KeyboardInterrupt

    loaded = load_world("demo")
    outcome = run_world(loaded, RunOptions(duration_s=20, out_dir=tmp_path, on_tick=stop, plots=False))
    assert outcome.status == "interrupted"
    rec = load_run(tmp_path)
    assert rec.status == "interrupted"
    assert rec.events[-1]["type"] == "run_end" and rec.events[-1]["tick"] == 580
    assert rec.metrics["complete"] is True and rec.metrics["status"] == "interrupted"
    assert rec.metrics["sim_time_s"] == pytest.approx(579 / 240)
    # everything recorded up to the interruption was flushed, not only the first chunk
    assert rec.stream("uav_truth")["tick"].max() == 576


def test_exception_in_user_code_is_recorded(tmp_path):
    class Broken:
        def step(self, t, detections):
            if t > 1.0:
                raise RuntimeError("estimator exploded")

    result = run("demo", duration=5.0, out_dir=tmp_path, estimator=Broken)
    assert result.status == "error" and "estimator exploded" in result.error
    exc = [e for e in result.record.events if e["type"] == "exception"]
    assert exc and "Traceback" in exc[0]["traceback"]
    assert result.record.status == "error"
    assert result.record.stream("uav_truth")["t"].max() == pytest.approx(1.0)


def test_killed_process_leaves_loadable_record(tmp_path):
    out = tmp_path / "killed"
    proc = subprocess.Popen(SKYTRACK + ["run", "demo", "--duration", "120", "--out", str(out), "--quiet", "--no-plots"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if (out / "metrics.json").exists() and list((out / "timeseries").glob("*/part-00001.npy")):
                break
            time.sleep(0.2)
        else:
            pytest.fail("the run never flushed its record")
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait(timeout=30)
    rec = load_run(out)
    assert rec.status == "unknown"  # no run_end: the process had no chance to write it
    assert rec.metrics["complete"] is False and rec.metrics["sim_time_s"] >= 2.0
    ut = rec.stream("uav_truth")
    assert len(ut["t"]) >= 40 and np.all(np.diff(ut["tick"][ut["uav"] == 0]) == 24)


def test_sigterm_ends_like_ctrl_c(tmp_path):
    out = tmp_path / "term"
    proc = subprocess.Popen(SKYTRACK + ["run", "demo", "--duration", "120", "--out", str(out), "--quiet", "--no-plots"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while not (out / "metrics.json").exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=60) == 130
    assert load_run(out).status == "interrupted"


def test_invalid_world_fails_before_physics(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(load_world("demo").path.read_text().replace("rate_hz: 2,", "rate_hz: 7,", 1))
    out = tmp_path / "never"
    res = subprocess.run(SKYTRACK + ["run", str(bad), "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert res.returncode == 2
    assert f"{bad}:" in res.stderr and "uavs[0].sensors[0].rate_hz = 7" in res.stderr
    assert "divides sim.physics_hz=240" in res.stderr
    assert "pybullet build time" not in res.stdout + res.stderr  # PyBullet was never imported
    assert not out.exists()


def test_bad_override_from_cli(tmp_path):
    res = subprocess.run(SKYTRACK + ["run", "demo", "--set", "sim.duration_s=-1", "--out", str(tmp_path / "x")],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "sim.duration_s = -1" in res.stderr and "greater than 0" in res.stderr


def test_bad_road_reference_names_the_key(tmp_path):
    from worlds.errors import WorldError

    with pytest.raises(WorldError, match=r"ground_vehicles\[0\]\.route\.random_walk_from = 'nowhere'"):
        run("demo", overrides=["ground_vehicles[0].route.random_walk_from=nowhere"], out_dir=tmp_path)


def test_radio_channel_carries_team_state_and_outages(tmp_path):
    """With the Rayleigh channel, team states go over the radio; a scheduled outage of the only link loses
    everything."""
    cut = run("demo", duration=4.0, out_dir=tmp_path / "cut", overrides=[
        "comms.model=rayleigh", "comms.outages=[{link: [uav1, uav2], start_s: 0, end_s: 100}]"])
    c = cut.metrics["comms"]
    # two UAVs, 40 agent steps each, each step a state and a track picture (demo's UAVs fuse their tracks)
    assert c["sent"] == 2 * 40 * 2 and c["delivered"] == 0 and c["lost"] == c["sent"]
    assert [e["type"] for e in cut.record.events].count("link_outage_start") == 1
    # UAVs ~590 m apart: Pr = exp(-(d/1000)^3) ≈ 0.81; delivery ratio over 160 packets within a binomial band
    ok = run("demo", duration=4.0, out_dir=tmp_path / "ok", overrides=["comms.model=rayleigh",
                                                                      "comms.block_by_buildings=false"])
    ratio = ok.metrics["comms"]["delivered"] / ok.metrics["comms"]["sent"]
    assert 0.62 < ratio < 0.97


def test_fused_estimate_beats_the_worse_uav(tmp_path):
    """Both UAVs fuse: the fused error is below the worse UAV's own error (the better UAV dominates the fusion)."""
    result = run("demo", duration=20.0, seed=3, out_dir=tmp_path, overrides=[
        "uavs[0].autonomy.fusion.method=convex", "uavs[1].autonomy.fusion.method=convex"])
    m = result.metrics["targets"]["car1"]
    worse = max(m["uav1"]["position_error_mean_m"], m["uav2"]["position_error_mean_m"])
    assert m["uav1_fused"]["position_error_mean_m"] < worse
    assert m["uav2_fused"]["position_error_mean_m"] < worse
    assert "fused_estimates" in result.record.streams
