"""Monte Carlo campaigns: seeds from the campaign seed and run index, every finished run journalled at once, a killed
campaign resumed to exactly N runs, crashes recorded, aggregates with Student-t intervals, Ray when installed."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from simulator.campaign.aggregate import metric_stats
from simulator.campaign.config import CampaignConfig, run_seed
from simulator.campaign.runner import run_campaign
from simulator.cli import main

ROOT = Path(__file__).resolve().parents[2]
METRIC = "targets.car1.uav1.position_error_mean_m"


def _journal(out: Path) -> list[dict]:
    path = out / "campaign.jsonl"
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def test_campaign_journals_every_run_with_its_seed_and_aggregates(tmp_path):
    res = run_campaign(CampaignConfig(world="demo", runs=3, out_dir=tmp_path, seed=7, duration_s=2.0, workers=2))
    lines = _journal(tmp_path)
    assert sorted(r["index"] for r in lines) == [0, 1, 2]
    assert {r["index"]: r["seed"] for r in lines} == {i: run_seed(7, i) for i in range(3)}
    assert all(r["status"] == "completed" for r in lines)
    for i in range(3):
        assert (tmp_path / "runs" / f"run-{i:05d}" / "metrics.json").exists()
    summary = json.loads((tmp_path / "summary.json").read_text())
    values = [r["metrics"]["real_time_factor"] for r in lines]
    m = summary["metrics"]["real_time_factor"]
    assert m["mean"] == pytest.approx(np.mean(values)) and m["n"] == 3
    assert res.summary.completed == 3 and res.ran == 3


def test_run_i_is_the_same_run_whatever_the_worker_count(tmp_path):
    a = run_campaign(CampaignConfig(world="demo", runs=2, out_dir=tmp_path / "a", seed=3, duration_s=2.0, workers=1))
    b = run_campaign(CampaignConfig(world="demo", runs=2, out_dir=tmp_path / "b", seed=3, duration_s=2.0, workers=2))
    for ra, rb in zip(a.reports, b.reports, strict=True):
        assert ra.index == rb.index and ra.seed == rb.seed
        same = {k: v for k, v in ra.metrics.items() if "wall" not in k and "real_time" not in k and "solve_ms" not in k}
        assert same == {k: rb.metrics[k] for k in same}


def test_confidence_interval_is_students_t():
    x = [2.0, 4.0, 9.0, 5.0, 5.0]
    m = metric_stats("x", x)
    lo, hi = stats.t.interval(0.95, df=4, loc=np.mean(x), scale=stats.sem(x))
    assert (m.ci_low, m.ci_high) == pytest.approx((lo, hi))
    assert metric_stats("one", [3.0]).ci_low is None


def test_killed_campaign_resumes_to_exactly_n_runs_without_duplicates(tmp_path):
    out = tmp_path / "c"
    cmd = [sys.executable, "-m", "simulator.campaign.cli", "campaign", "demo", "--runs", "5", "--duration", "3",
           "--workers", "1", "--seed", "11", "--quiet", "--out", str(out)]
    proc = subprocess.Popen(cmd, cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 240
    try:
        while len(_journal(out)) < 2 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.2)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the parent and its worker, mid-run
        proc.wait()
    done_before = {r["index"] for r in _journal(out)}
    assert 2 <= len(done_before) < 5
    code = main(["campaign", "demo", "--runs", "5", "--duration", "3", "--workers", "2", "--seed", "11", "--quiet",
                 "--out", str(out)])
    assert code == 0
    lines = _journal(out)
    finished = [r["index"] for r in lines if r["status"] == "completed"]
    assert sorted(finished) == [0, 1, 2, 3, 4]  # exactly N, no duplicates
    run_dirs = sorted(p.name for p in (out / "runs").iterdir())
    assert run_dirs == [f"run-{i:05d}" for i in range(5)]


def test_resume_with_other_parameters_is_refused(tmp_path, capsys):
    assert main(["campaign", "demo", "--runs", "1", "--duration", "1", "--quiet", "--out", str(tmp_path)]) == 0
    assert main(["campaign", "demo", "--runs", "1", "--duration", "2", "--quiet", "--out", str(tmp_path)]) == 2
    assert "skytrack campaign:" in capsys.readouterr().err


def test_crashing_runs_are_recorded_and_the_campaign_goes_on(tmp_path, monkeypatch, capsys):
    monkeypatch.syspath_prepend(str(ROOT))
    plugin = "tests.simulator.user_modules.raising:FailingEstimator"
    code = main(["campaign", "demo", "--runs", "2", "--duration", "2", "--workers", "1", "--quiet",
                 "--out", str(tmp_path), "--set", f"uavs[0].autonomy.estimator={{type: plugin, plugin: '{plugin}', "
                 "tracking: {mode: single}}"])
    assert code == 1  # every run failed (the plugin sees every detection: not wrapped, as it would be among traffic)
    lines = _journal(tmp_path)
    assert sorted(r["index"] for r in lines) == [0, 1]
    assert all(r["status"] == "error" and "estimator failed on purpose" in r["error"] for r in lines)
    assert "estimator failed on purpose" in capsys.readouterr().err


def test_invalid_world_is_refused_before_any_run(tmp_path, capsys):
    assert main(["campaign", "demo", "--runs", "2", "--quiet", "--out", str(tmp_path / "x"),
                 "--set", "sim.duration_s=-4"]) == 2
    assert not (tmp_path / "x" / "campaign.jsonl").exists()


def test_ray_auto_runs_the_campaign_on_a_local_ray(tmp_path):
    pytest.importorskip("ray", reason="ray is not installed (pip install 'skytrack[cluster]')")
    res = run_campaign(CampaignConfig(world="demo", runs=2, out_dir=tmp_path, seed=5, duration_s=1.0,
                                      ray_address="auto", workers=2))
    assert sorted(r.index for r in res.reports) == [0, 1]
    assert all(r.status == "completed" for r in res.reports)
