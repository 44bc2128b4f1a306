"""The video flags of ``skytrack run``, the ``skytrack render`` subcommand, and a clean ``bench --json`` stdout."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import cv2
import pytest

from simulator.cli import main

TINY = ["--width", "160", "--height", "96", "--fps", "10", "--renderer", "tiny", "--quiet"]


def _frames(path: Path) -> tuple[int, tuple[int, int], float]:
    cap = cv2.VideoCapture(str(path))
    assert cap.isOpened(), path
    n, shape = 0, None
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        n, shape = n + 1, frame.shape[:2]
    fps = cap.get(cv2.CAP_PROP_FPS)
    cap.release()
    return n, shape, fps


@pytest.fixture(scope="module")
def video_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("video_run")
    code = main(["run", "demo", "--duration", "2", "--seed", "4", "--out", str(out), "--no-plots", "--video", *TINY])
    return code, out


def test_run_with_video_writes_an_mp4_of_the_whole_run(video_run):
    code, out = video_run
    assert code == 0
    n, shape, fps = _frames(out / "video.mp4")
    assert shape == (96, 160)
    assert fps == pytest.approx(10.0)
    assert abs(n - 2 * 10) <= 1  # fps x duration frames


def test_render_subcommand_replays_a_recorded_run(video_run, tmp_path):
    _, out = video_run
    clip = tmp_path / "top.mp4"
    code = main(["render", str(out), "--camera", "topdown", "--out", str(clip), "--start", "0.5", "--end", "1.5",
                 *TINY])
    assert code == 0
    n, shape, _ = _frames(clip)
    assert shape == (96, 160) and abs(n - 10) <= 1


def test_render_enabled_in_the_world_file_makes_a_video(tmp_path):
    code = main(["run", "demo", "--duration", "1", "--out", str(tmp_path), "--no-plots", "--quiet",
                 "--set", "render.enabled=true", "--set", "render.width=96", "--set", "render.height=64",
                 "--set", "render.fps=8", "--renderer", "tiny"])
    assert code == 0
    n, shape, fps = _frames(tmp_path / "video.mp4")
    assert shape == (64, 96) and fps == pytest.approx(8.0) and abs(n - 8) <= 1


@pytest.mark.parametrize("flags,message", [
    (["--width", "33"], "RenderConfig.width must be an even integer"),
    (["--uav", "7"], "--uav 7: the world has 2 UAV(s)"),
])
def test_bad_video_flags_fail_before_the_run(tmp_path, capsys, flags, message):
    out = tmp_path / "never"
    code = main(["run", "demo", "--duration", "1", "--out", str(out), "--quiet", "--video", *flags])
    assert code == 2
    assert message in capsys.readouterr().err
    assert not out.exists()  # nothing ran


def test_render_of_something_that_is_not_a_run_directory(tmp_path, capsys):
    assert main(["render", str(tmp_path)]) == 2
    assert "is not a run directory" in capsys.readouterr().err


def test_world_render_section_is_validated(tmp_path, capsys):
    assert main(["run", "demo", "--out", str(tmp_path / "x"), "--set", "render.camera=fisheye"]) == 2
    assert "render.camera" in capsys.readouterr().err


def test_bench_json_stdout_is_only_json_even_when_c_code_prints(tmp_path):
    # a benchmark that writes to file descriptor 1 behind Python's back, as PyBullet's EGL plugin does
    script = textwrap.dedent("""
        import os, sys
        from simulator.bench import registry, runner
        from simulator.bench.registry import BenchRecord, benchmark
        from simulator.cli import main

        @benchmark("noisy_probe", produces=("noisy_probe_value",))
        def noisy():
            os.write(1, b"GL_VENDOR=banner printed by C code\\n")
            print("and a Python print")
            return [BenchRecord(name="noisy_probe_value", value=1.5, unit="x", better="higher")]

        runner.discover = lambda: registry.registered()
        sys.exit(main(["bench", "--only", "noisy_probe", "--json"]))
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    records = json.loads(proc.stdout)
    assert records == [{"name": "noisy_probe_value", "value": 1.5, "unit": "x", "target": None, "better": "higher"}]
    assert "GL_VENDOR" in proc.stderr
