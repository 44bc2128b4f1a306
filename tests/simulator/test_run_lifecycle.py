"""How a run begins and ends under bad flags, a reused run directory, a crash before the loop, a physics blow-up,
a signal, a corrupt record and an interrupted video."""

from __future__ import annotations

import gzip
import json
import signal
import subprocess
import sys
import time

import numpy as np
import pybullet as p
import pytest

import simulator.engine as engine
from simulator.api import run
from simulator.cli import EXIT_DIVERGED, main
from simulator.engine import RunOptions, run_world
from simulator.record import RunRecorder
from simulator.render.encode import VideoEncoder
from simulator.rundir import RunDirError, fresh_run_dir, is_run_dir
from simulator.runrecord import RecordError, load_run, load_search_sets
from simulator.watchdog import Watchdog
from tests.simulator.conftest import sigint_as_in_a_terminal
from worlds.loader import load_world

QUICK = ["--duration", "0.05", "--no-plots", "--quiet"]


# -- flags ---------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("flags", "message"), [
    (["--duration", "nan"], "--duration nan: the simulated duration must be a finite number of seconds in (0, 1e+09]"),
    (["--duration", "0"], "--duration 0: the simulated duration must be a finite number of seconds in (0, 1e+09]"),
    (["--duration", "-1"], "--duration -1: the simulated duration must be a finite number of seconds in (0, 1e+09]"),
    (["--duration", "inf"], "--duration inf: the simulated duration must be a finite number of seconds in (0, 1e+09]"),
    (["--seed", "-1"], "--seed -1: a seed must be an integer >= 0"),
    (["--out", "/dev/null/x"], "--out /dev/null/x: /dev/null/x cannot be created: /dev/null is not a directory"),
], ids=["nan", "zero", "negative", "inf", "seed", "out"])
def test_bad_run_flags_exit_2_naming_the_flag(tmp_path, capsys, flags, message):
    args = ["run", "demo", *flags] + ([] if "--out" in flags else ["--out", str(tmp_path / "r")])
    assert main(args) == 2
    assert capsys.readouterr().err == f"skytrack: {message}\n"
    assert not (tmp_path / "r").exists()


def test_a_bad_flag_prints_no_traceback():
    res = subprocess.run([sys.executable, "-m", "simulator.cli", "run", "demo", "--duration", "nan"],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "Traceback" not in res.stderr and "--duration nan" in res.stderr


def test_run_options_refuse_what_the_flags_refuse(tmp_path):
    for bad in (float("nan"), float("inf"), 0.0, -1.0):
        with pytest.raises(ValueError, match="RunOptions.duration_s must be a finite number of seconds"):
            RunOptions(duration_s=bad, out_dir=tmp_path)
    with pytest.raises(ValueError, match="RunOptions.seed must be an integer >= 0, got -1"):
        RunOptions(seed=-1, out_dir=tmp_path)
    RunOptions(duration_s=np.float64(1.0), seed=np.int64(3), out_dir=tmp_path)


# -- the run directory ---------------------------------------------------------------------------------------------
def _old_run(path, world="search_decoys"):
    """A run directory as an earlier run of another world left it: its search sets and its search plot."""
    (path / "plots").mkdir(parents=True)
    (path / "run.json").write_text(json.dumps({"world": world, "seed": 1}))
    (path / "events.jsonl").write_text(json.dumps({"type": "run_start", "tick": 0}) + "\n")
    (path / "plots" / "search.png").write_bytes(b"png")
    line = {"tick": 24, "t": 0.1, "uavs": [{"uav": 0, "X": "POLYGON EMPTY", "Xbar": "POLYGON EMPTY"}]}
    (path / "search_sets.jsonl.gz").write_bytes(gzip.compress((json.dumps(line) + "\n").encode()))


def test_fresh_run_dir_moves_an_earlier_run_to_the_next_numbered_sibling(tmp_path):
    out = tmp_path / "demo"
    assert fresh_run_dir(out) is None and out.is_dir()  # a new directory
    assert fresh_run_dir(out) is None  # an empty one is used as it is
    _old_run(out)
    assert is_run_dir(out) and fresh_run_dir(out) == tmp_path / "demo.1"
    assert list(out.iterdir()) == [] and (tmp_path / "demo.1" / "run.json").is_file()
    _old_run(out)
    (tmp_path / "demo.7").mkdir()  # numbering continues after the highest
    assert fresh_run_dir(out) == tmp_path / "demo.8"


@pytest.mark.parametrize("content", ["file", "dir", "foreign-json"])
def test_anything_but_a_run_directory_is_refused_untouched(tmp_path, content):
    home = tmp_path / "home"
    home.mkdir()
    if content == "file":
        (home / "notes.txt").write_text("keep me")
    elif content == "dir":
        (home / "project").mkdir()
    else:
        (home / "run.json").write_text('{"name": "not a run"}')
    before = sorted(x.name for x in home.iterdir())
    with pytest.raises(RunDirError, match="non-empty directory that is not a skytrack run directory"):
        fresh_run_dir(home)
    assert sorted(x.name for x in home.iterdir()) == before and not (tmp_path / "home.1").exists()


def test_a_file_is_refused_as_a_run_directory(tmp_path):
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(RunDirError, match=f"^{f} exists and is not a directory$"):
        fresh_run_dir(f)
    assert f.read_text() == "x"


def test_cli_refuses_a_non_run_directory_as_out(tmp_path, capsys):
    home = tmp_path / "home"
    home.mkdir()
    (home / ".bashrc").write_text("keep me")
    assert main(["run", "demo", "--out", str(home), *QUICK]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"skytrack: --out {home}: {home} is a non-empty directory that is not a skytrack run")
    assert [x.name for x in home.iterdir()] == [".bashrc"] and not (tmp_path / "home.1").exists()


def test_reusing_out_starts_a_clean_run_and_keeps_the_earlier_one_aside(tmp_path, capsys):
    out = tmp_path / "demo"
    _old_run(out)
    assert len(load_search_sets(out)) == 1
    assert main(["run", "demo", "--out", str(out), *QUICK]) == 0
    assert f"skytrack: {out} held an earlier run: moved it to {tmp_path / 'demo.1'}\n" in capsys.readouterr().out
    assert load_search_sets(out) == [] and not (out / "plots" / "search.png").exists()
    assert load_run(out).run["world"] == "demo" and load_run(out).status == "completed"
    assert json.loads((tmp_path / "demo.1" / "run.json").read_text())["world"] == "search_decoys"
    assert len(load_search_sets(tmp_path / "demo.1")) == 1
    assert main(["run", "demo", "--out", str(out), *QUICK]) == 0  # `make demo` twice
    assert load_run(tmp_path / "demo.2").status == "completed" and load_run(out).status == "completed"


# -- failures before the loop ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("stage", ["write_geometry", "build_assembly"])
def test_a_crash_before_the_loop_ends_the_record_with_run_end(tmp_path, monkeypatch, capsys, stage):
    def boom(*args, **kwargs):
        raise OverflowError("cannot convert float infinity to integer")

    monkeypatch.setattr(engine, stage, boom)
    assert main(["run", "demo", "--out", str(tmp_path), *QUICK]) == 1
    rec = load_run(tmp_path)
    end = rec.events[-1]
    assert end["type"] == "run_end" and end["status"] == "error" and end["tick"] == 0
    assert end["error"] == "OverflowError: cannot convert float infinity to integer"
    assert rec.metrics["status"] == "error"
    assert [e["type"] for e in rec.events] == ["run_start", "exception", "run_end"]
    assert "skytrack: run failed: OverflowError: cannot convert float infinity to integer" in capsys.readouterr().err


# -- divergence ------------------------------------------------------------------------------------------------------
def test_a_blow_up_clamped_by_pybullet_stops_the_run_as_diverged(tmp_path, monkeypatch):
    built = {}
    real = engine.build_assembly

    def capture(*args, **kwargs):
        built["assembly"] = real(*args, **kwargs)
        return built["assembly"]

    def kick(tick):  # a solver gone wild: 500 m/s, which PyBullet shows as 100 m/s
        if tick == 60:
            q = built["assembly"].quads
            p.resetBaseVelocity(int(q.body_ids[1]), [500.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=q.client_id)

    monkeypatch.setattr(engine, "build_assembly", capture)
    outcome = run_world(load_world("demo"), RunOptions(duration_s=1.0, out_dir=tmp_path, on_tick=kick, plots=False))
    assert outcome.status == "diverged"
    assert outcome.error.startswith("uav2 diverged at tick 61: speed = 100 m/s (faster than the airframe can fly: "
                                    "above 70.")
    rec = load_run(tmp_path)
    end = rec.events[-1]
    assert end["type"] == "run_end" and end["status"] == "diverged" and end["tick"] == 61
    assert end["diverged"]["body"] == "uav2" and end["diverged"]["quantity"] == "speed"
    assert rec.metrics["status"] == "diverged" and rec.metrics["diverged"] == end["diverged"]
    assert rec.stream("uav_truth")["tick"].max() == 48  # every record tick (10 Hz) up to the blow-up is kept


def test_a_diverged_run_exits_3(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(engine, "world_watchdog",
                        lambda world: Watchdog([u.id for u in world.uavs], [], np.full(len(world.uavs), 1e3), 1e4))
    assert main(["run", "demo", "--out", str(tmp_path), *QUICK]) == EXIT_DIVERGED == 3
    err = capsys.readouterr().err
    assert "skytrack: run stopped: uav1 diverged at tick 1: z = " in err and "(under the ground: below" in err
    assert load_run(tmp_path).status == "diverged"


# -- interruption ----------------------------------------------------------------------------------------------------
def test_a_signal_inside_a_component_ends_the_run_between_ticks(tmp_path, sigint_raises):
    class Signalled:
        finished = []

        def step(self, t, detections):
            if t >= 0.25 and not self.finished:
                signal.raise_signal(signal.SIGINT)  # as if Ctrl-C came during a compiled solve
                self.finished.append(t)  # the component's step goes on to its end
            return None

    result = run("demo", duration=2.0, out_dir=tmp_path, estimator=Signalled)
    assert result.status == "interrupted" and Signalled.finished == [0.3]  # the agents' first step after 0.25 s
    end = result.record.events[-1]
    assert end["type"] == "run_end" and end["status"] == "interrupted" and end["tick"] == 72  # that tick's end
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_an_interrupt_that_surfaces_from_c_code_is_an_interruption_not_an_error(tmp_path):
    class CasadiLike:
        def step(self, t, detections):
            if t >= 0.25:
                try:
                    raise KeyboardInterrupt
                except KeyboardInterrupt as exc:
                    raise SystemError("<built-in function _function_buffer_eval> returned a result with an "
                                      "exception set") from exc
            return None

    result = run("demo", duration=2.0, out_dir=tmp_path, estimator=CasadiLike)
    assert result.status == "interrupted" and result.error is None
    assert not [e for e in result.record.events if e["type"] == "exception"]


# -- reading a record --------------------------------------------------------------------------------------------
def _record(tmp_path):
    rec = RunRecorder(tmp_path)
    rec.append_rows("uav_truth", {"tick": [1, 2], "t": [0.1, 0.2], "uav": [0, 0]})
    rec.close()
    return tmp_path / "timeseries" / "uav_truth" / "part-00000.npy"


def test_a_corrupt_chunk_is_named(tmp_path):
    part = _record(tmp_path)
    part.write_bytes(part.read_bytes()[:40])
    with pytest.raises(RecordError, match=f"^{part}: not a readable record chunk"):
        load_run(tmp_path)


def test_a_pickled_chunk_is_refused_unread_and_named(tmp_path):
    part = _record(tmp_path)
    np.save(part, np.array([{"x": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(RecordError, match=f"^{part}: not a readable record chunk .*when allow_pickle=False"):
        load_run(tmp_path)


def test_a_corrupt_json_file_is_named(tmp_path):
    _record(tmp_path)
    (tmp_path / "metrics.json").write_text('{"status": "compl')
    with pytest.raises(RecordError, match=f"^{tmp_path / 'metrics.json'}: not readable JSON"):
        load_run(tmp_path)


def test_render_of_a_corrupt_record_names_the_file(tmp_path, capsys):
    part = _record(tmp_path)
    (tmp_path / "run.json").write_text(json.dumps({"world": "demo", "seed": 1}))
    part.write_bytes(b"\x93NUMPY garbage")
    assert main(["render", str(tmp_path), "--renderer", "tiny", "--quiet"]) == 2
    assert f"skytrack render: {part}: not a readable record chunk" in capsys.readouterr().err


# -- video -----------------------------------------------------------------------------------------------------------
def test_an_interrupted_video_leaves_no_file_that_looks_complete(tmp_path):
    out = tmp_path / "video.mp4"
    frame = np.zeros((48, 64, 3), np.uint8)
    with pytest.raises(KeyboardInterrupt):
        with VideoEncoder(out, 64, 48, 10) as enc:
            for _ in range(3):
                enc.write(frame)
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []
    out.write_bytes(b"an earlier video")
    with pytest.raises(KeyboardInterrupt):
        with VideoEncoder(out, 64, 48, 10) as enc:
            enc.write(frame)
            raise KeyboardInterrupt
    assert out.read_bytes() == b"an earlier video" and list(tmp_path.iterdir()) == [out]
    with VideoEncoder(out, 64, 48, 10) as enc:
        enc.write(frame)
        assert out.read_bytes() == b"an earlier video"  # the new one is written beside it meanwhile
    assert list(tmp_path.iterdir()) == [out] and out.stat().st_size > 100


@pytest.mark.slow
@pytest.mark.parametrize("delay_s", [0.0, 0.35, 0.8])
def test_ctrl_c_during_the_nmpc_solves_is_an_interruption(tmp_path, delay_s):
    """A real SIGINT to a run whose UAVs solve a compiled NMPC at every agent step (most of its wall time): exit 130,
    status interrupted, whichever instant it lands (unguarded, some landed inside the solve and ended as errors)."""
    out = tmp_path / "nmpc"
    proc = subprocess.Popen([sys.executable, "-m", "simulator.cli", "run", "road_standoff", "--duration", "120",
                             "--out", str(out), "--quiet", "--no-plots", "--set", "sim.flush_every_s=0.5"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            preexec_fn=sigint_as_in_a_terminal)
    try:
        deadline = time.monotonic() + 300
        while not (out / "metrics.json").exists() and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        time.sleep(delay_s)
        proc.send_signal(signal.SIGINT)
        code = proc.wait(timeout=120)
    finally:
        proc.kill()
    stderr = proc.stderr.read()
    assert code == 130, stderr
    rec = load_run(out)
    assert rec.status == "interrupted" and rec.metrics["status"] == "interrupted"
    assert "SystemError" not in stderr and not [e for e in rec.events if e["type"] == "exception"]
