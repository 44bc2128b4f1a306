"""Monte Carlo campaigns: seeds from the campaign seed and run index, every finished run journalled at once, a killed
campaign resumed to exactly N runs, crashes recorded, aggregates with Student-t intervals, Ray when installed."""

import hashlib
import json
import os
import shutil
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


def test_a_campaign_extends_to_more_runs_keeping_its_first_and_is_never_cut(tmp_path, capsys):
    args = ["campaign", "demo", "--duration", "1", "--seed", "5", "--quiet", "--out", str(tmp_path)]
    assert main([*args, "--runs", "1"]) == 0
    first = _journal(tmp_path)[0]
    assert main([*args, "--runs", "3"]) == 0
    lines = _journal(tmp_path)
    assert sorted(r["index"] for r in lines) == [0, 1, 2]  # run 0 kept (not redone), runs 1–2 added
    assert lines[0] == first
    assert {r["index"]: r["seed"] for r in lines} == {i: run_seed(5, i) for i in range(3)}
    assert json.loads((tmp_path / "campaign.json").read_text())["runs"] == 3
    assert json.loads((tmp_path / "summary.json").read_text())["metrics"]["real_time_factor"]["n"] == 3
    capsys.readouterr()
    assert main([*args, "--runs", "2"]) == 2  # cutting would drop stored runs: refused
    assert "can be extended with more runs, not cut" in capsys.readouterr().err
    assert len(_journal(tmp_path)) == 3


def test_a_campaign_directory_in_use_by_another_process_is_refused_untouched(tmp_path, capsys):
    # two processes on one directory ran the same pending runs into the same run directories, each moving the other's
    # aside, and journaled them twice (one as an error): the second is now refused while the first holds the lock
    from simulator.campaign.config import CampaignParams
    from simulator.campaign.journal import CampaignJournal
    from worlds.loader import load_world

    config = CampaignConfig(world="demo", runs=1, out_dir=tmp_path, duration_s=1.0)
    holder = CampaignJournal(tmp_path, CampaignParams.resolve(config, load_world("demo")))
    try:
        assert main(["campaign", "demo", "--runs", "1", "--duration", "1", "--quiet", "--out", str(tmp_path)]) == 2
        err = capsys.readouterr().err
        assert f"is in use by another campaign process (pid {os.getpid()})" in err
        assert _journal(tmp_path) == [] and not (tmp_path / "runs").exists()
    finally:
        holder.close()
    assert main(["campaign", "demo", "--runs", "1", "--duration", "1", "--quiet", "--out", str(tmp_path)]) == 0
    assert [r["status"] for r in _journal(tmp_path)] == ["completed"]


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


def test_a_diverged_run_is_a_failed_run_for_good():
    """A run the watchdog stopped (status diverged) is journaled, not redone on resume, and counted as a failure."""
    from simulator.campaign.aggregate import summarize
    from simulator.campaign.config import RunReport

    reports = [RunReport(index=0, seed=1, status="completed", error=None, wall_time_s=1.0, metrics={"x": 1.0}),
               RunReport(index=1, seed=2, status="diverged", error="uav1 below the ground at tick 9", wall_time_s=1.0)]
    assert reports[1].finished
    summary = summarize(reports)
    assert summary.completed == 1 and summary.failed == 1
    assert summary.failures == ((1, "uav1 below the ground at tick 9"),)
    with pytest.raises(ValueError, match="diverged"):
        RunReport(index=2, seed=3, status="exploded", error=None, wall_time_s=1.0)


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


def _stored_runs_campaign(out: Path, runs: int = 4) -> CampaignConfig:
    from tests.simulator.user_modules.stored_runs import write_run

    return CampaignConfig(world="demo", runs=runs, out_dir=out, seed=9, duration_s=1.0, workers=1, progress=False,
                          run_fn=write_run)


def _damage_three_runs(out: Path, truncate_chunk: bool = False) -> None:
    metrics = out / "runs" / "run-00001" / "metrics.json"
    metrics.write_text(metrics.read_text()[:10])  # truncated
    chunk = out / "runs" / "run-00002" / "timeseries" / "uav_truth" / "part-00000.npy"
    data = bytearray(chunk.read_bytes())
    if truncate_chunk:
        del data[len(data) // 2:]
    else:
        data[200:232] = b"\xff" * 32  # a corrupted record chunk, same size: it still loads, its hash differs
    chunk.write_bytes(bytes(data))
    shutil.rmtree(out / "runs" / "run-00003")  # a deleted run directory


def test_a_resume_redoes_the_runs_whose_stored_files_are_damaged(tmp_path, caplog):
    out = tmp_path / "c"
    first = run_campaign(_stored_runs_campaign(out))
    assert first.ran == 4 and not first.redone
    files = {r["index"]: r["files"] for r in _journal(out)}
    assert sorted(files[0]) == ["metrics.json", "run.json", "timeseries/uav_truth/part-00000.npy"]
    chunk = out / "runs" / "run-00000" / "timeseries" / "uav_truth" / "part-00000.npy"
    assert files[0]["timeseries/uav_truth/part-00000.npy"] == [chunk.stat().st_size,
                                                               hashlib.sha256(chunk.read_bytes()).hexdigest()]
    _damage_three_runs(out)
    chunk2 = out / "runs" / "run-00002" / "timeseries" / "uav_truth" / "part-00000.npy"
    damaged_sha = hashlib.sha256(chunk2.read_bytes()).hexdigest()
    with caplog.at_level("WARNING", logger="simulator.campaign.journal"):
        again = run_campaign(_stored_runs_campaign(out))
    assert again.ran == 3
    assert again.redone == {
        1: f"metrics.json has 10 bytes, {files[1]['metrics.json'][0]} when the run finished",
        2: "timeseries/uav_truth/part-00000.npy differs from the file the run wrote "
           f"(SHA-256 {damaged_sha[:12]}…, was {files[2]['timeseries/uav_truth/part-00000.npy'][1][:12]}…)",
        3: "its run directory run-00003 is missing"}
    assert f"run 3 of {out} is redone: its run directory run-00003 is missing" in caplog.text
    for i in range(4):  # every run whole again, its metrics loadable
        assert json.loads((out / "runs" / f"run-{i:05d}" / "metrics.json").read_text())["complete"] is True
    third = run_campaign(_stored_runs_campaign(out))
    assert third.ran == 0 and not third.redone  # the redone runs' new journal lines win over the damaged ones
    assert sorted(r.index for r in third.reports) == [0, 1, 2, 3]


def test_runs_journaled_without_file_hashes_are_checked_by_loading(tmp_path):
    out = tmp_path / "c"
    run_campaign(_stored_runs_campaign(out))
    lines = _journal(out)
    for line in lines:
        del line["files"]  # a journal written before the hashes existed
    (out / "campaign.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))
    _damage_three_runs(out, truncate_chunk=True)  # without hashes, a chunk must fail to load to be noticed
    again = run_campaign(_stored_runs_campaign(out))
    assert sorted(again.redone) == [1, 2, 3] and again.ran == 3
    assert again.redone[1].startswith("metrics.json does not load (JSONDecodeError")
    assert again.redone[2].startswith("timeseries/uav_truth/part-00000.npy does not load (ValueError: ")
    assert again.redone[3] == "its run directory run-00003 is missing"


@pytest.mark.parametrize("bad, why", [
    (b'{"index": 1, "seed": 5, "sta', "its last line was cut off (28 bytes, no newline)"),
    (b"\x00\x17garbage\n", "unreadable run record (JSONDecodeError: Expecting value: line 1 column 1 (char 0))"),
    (b'{"index": 99, "seed": 1, "status": "completed", "error": null, "wall_time_s": 0}\n',
     "unreadable run record (ValueError: run index 99 outside 0..3)"),
    (b'{"index": "1", "seed": 1, "status": "completed", "error": null, "wall_time_s": 0}\n',
     "unreadable run record (ValueError: RunReport.index must be int, got '1')"),
], ids=["torn-last-line", "garbage", "index-outside", "index-not-int"])
def test_unreadable_journal_lines_are_dropped_and_their_runs_redone(tmp_path, caplog, bad, why):
    out = tmp_path / "c"
    run_campaign(_stored_runs_campaign(out))
    journal = out / "campaign.jsonl"
    lines = journal.read_bytes().splitlines(keepends=True)
    kept = [line for line in lines if json.loads(line)["index"] != 1]
    journal.write_bytes(b"".join(kept[:2]) + (bad if bad.endswith(b"\n") else b"") + b"".join(kept[2:])
                        + (b"" if bad.endswith(b"\n") else bad))
    with caplog.at_level("WARNING", logger="simulator.campaign.journal"):
        again = run_campaign(_stored_runs_campaign(out))
    assert again.ran == 1 and sorted(r.index for r in again.reports) == [0, 1, 2, 3]
    assert "dropped, its run runs again" in caplog.text and why in caplog.text
    assert (out / "campaign.rejected.jsonl").read_bytes() == (bad if bad.endswith(b"\n") else bad + b"\n")
    assert sorted(r["index"] for r in _journal(out)) == [0, 1, 2, 3]  # the journal is whole again
    caplog.clear()
    with caplog.at_level("WARNING", logger="simulator.campaign.journal"):
        assert run_campaign(_stored_runs_campaign(out)).ran == 0
    assert not caplog.text  # warned once: the bad line is no longer in the journal


@pytest.mark.slow
def test_the_command_redoes_damaged_runs_of_the_demo_world_and_says_so(tmp_path, capsys):
    out = tmp_path / "c"
    args = ["campaign", "demo", "--runs", "4", "--duration", "1", "--workers", "2", "--seed", "3", "--quiet",
            "--out", str(out)]
    assert main(args) == 0
    capsys.readouterr()
    _damage_three_runs(out)
    assert main(args) == 0
    io = capsys.readouterr()
    assert f"campaign {out}: 4 of 4 runs recorded (3 run now, 3 of them redone: their stored files were damaged)" \
        in io.out
    assert "run 1 redone: metrics.json has 10 bytes" in io.err
    assert "run 2 redone: timeseries/uav_truth/part-00000.npy differs from the file the run wrote" in io.err
    assert "run 3 redone: its run directory run-00003 is missing" in io.err
    assert json.loads((out / "runs" / "run-00001" / "metrics.json").read_text())["complete"] is True
