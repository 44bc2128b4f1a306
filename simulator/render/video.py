"""Replaying a recorded run directory as an MP4 video: ``render_run(run_dir, RenderConfig(...)) -> Path``.

The frames come from :func:`simulator.render.parallel.iter_frames` (one :class:`~simulator.render.replay.Replayer`
in this process, or one per worker process) and go to the encoder in order.
"""

from __future__ import annotations

from pathlib import Path

from tqdm import tqdm

from simulator.render.config import RenderConfig
from simulator.render.encode import VideoEncoder
from simulator.render.parallel import iter_frames
from simulator.stdio import quiet_c_stdout

__all__ = ["render_run"]


def render_run(run_dir: Path, config: RenderConfig) -> Path:
    """Render the run directory ``run_dir`` to an MP4 video as ``config`` says; returns the video's path.

    Raises
    ------
    FileNotFoundError
        No run directory at ``run_dir``.
    ValueError
        The record has no ``uav_truth`` samples, or ``config.uav`` is not one of its UAVs.
    """
    run_dir = Path(run_dir)
    out = Path(config.out) if config.out is not None else run_dir / "video.mp4"
    with quiet_c_stdout():  # the EGL plugin prints GL banners on descriptor 1 while it renders and closes
        n, frames = iter_frames(run_dir, config)
        try:
            with VideoEncoder(out, config.width, config.height, config.fps, config.crf, config.preset) as enc:
                for rgb in tqdm(frames, total=n, unit="frame", desc=f"render {out.name}", disable=not config.progress):
                    enc.write(rgb)
        finally:
            frames.close()  # closes the PyBullet clients inside the quiet block
    return out
