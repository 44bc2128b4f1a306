"""Video rendering benchmark: frames per wall-clock second of a 1280x720 replay, overlays and H.264 encoding included.

A 6-second demo run is recorded once; then 2 s of it (60 frames at 30 fps) are rendered to MP4 three times with the
default :class:`RenderConfig` (split chase + top-down, renderer chosen by speed, 3D drawn at half size and scaled up)
and once with the 3D drawn at full size. Scene build and renderer choice are outside the timed part: only the frame
loop (pose, render, overlays, encode) is timed, as for a long video.
"""

from __future__ import annotations

import tempfile
import time
import warnings
from pathlib import Path

from simulator.bench.registry import BenchRecord, benchmark, median_of

__all__: list[str] = []

_FRAMES_S = 2.0


def _fps(run_dir: Path, out: Path, scale: float) -> float:
    from simulator.render.config import RenderConfig
    from simulator.render.encode import VideoEncoder
    from simulator.render.replay import Replayer

    cfg = RenderConfig(out=out, t_start=2.0, t_end=2.0 + _FRAMES_S, render_scale=scale, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = Replayer(run_dir, cfg)
    try:
        t0 = time.perf_counter()
        n = 0
        with VideoEncoder(out, cfg.width, cfg.height, cfg.fps, cfg.crf, cfg.preset) as enc:
            for frame in rep.render_frames():
                enc.write(frame.rgb)
                n += 1
        return n / (time.perf_counter() - t0)
    finally:
        rep.close()


@benchmark("render", produces=("render_fps_1280x720", "render_fps_1280x720_full_scale"))
def bench_render() -> list[BenchRecord]:
    """Replay video frames per second at 1280x720 (split view, overlays, H.264), CPU only."""
    from simulator.api import run

    with tempfile.TemporaryDirectory(prefix="skytrack-bench-render-") as tmp:
        run_dir = Path(tmp) / "run"
        run("demo", duration=_FRAMES_S + 4.0, seed=1, out_dir=run_dir)
        video = Path(tmp) / "bench.mp4"
        half = median_of(lambda: _fps(run_dir, video, 0.5), repeats=3)
        full = _fps(run_dir, video, 1.0)
    return [BenchRecord(name="render_fps_1280x720", value=half, unit="fps", target=15.0, better="higher"),
            BenchRecord(name="render_fps_1280x720_full_scale", value=full, unit="fps", target=15.0, better="higher")]
