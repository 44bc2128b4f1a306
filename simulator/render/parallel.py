"""The frames of a replay video, rendered in this process or in a pool of worker processes.

Each worker holds its own :class:`~simulator.render.replay.Replayer` (its own PyBullet client) and renders contiguous
chunks of frames; cameras are advanced from the first frame in every chunk (cheap: no rendering), so the frames are
identical to a single-process pass. Chunks come back in order and are handed to the encoder one frame at a time. The
renderer is chosen once, in this process, and passed to the workers.
"""

from __future__ import annotations

import dataclasses
import multiprocessing as mp
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from simulator.render.config import RenderConfig
from simulator.render.replay import Replayer

__all__ = ["iter_frames"]

_CHUNK_FRAMES = 15  # frames per task handed to a worker
_worker: Replayer | None = None


def _init_worker(run_dir: Path, config: RenderConfig) -> None:
    global _worker
    warnings.simplefilter("ignore")  # the parent has already shown any warning about this run
    _worker = Replayer(run_dir, config)


def _render_chunk(bounds: tuple[int, int]) -> list[np.ndarray]:
    assert _worker is not None
    return [f.rgb for f in _worker.render_frames(start=bounds[0], stop=bounds[1])]


def _serial(replayer: Replayer) -> Iterator[np.ndarray]:
    try:
        for frame in replayer.render_frames():
            yield frame.rgb
    finally:
        replayer.close()


def _pooled(run_dir: Path, config: RenderConfig, n: int) -> Iterator[np.ndarray]:
    chunks = [(k, min(k + _CHUNK_FRAMES, n)) for k in range(0, n, _CHUNK_FRAMES)]
    ctx = mp.get_context("spawn")  # a fresh interpreter per worker: no PyBullet client copied by fork
    with ctx.Pool(config.workers, initializer=_init_worker, initargs=(run_dir, config)) as pool:
        for frames in pool.imap(_render_chunk, chunks):
            yield from frames


def iter_frames(run_dir: Path, config: RenderConfig) -> tuple[int, Iterator[np.ndarray]]:
    """The number of frames of the video and an iterator over them, (H, W, 3) RGB uint8, in order."""
    replayer = Replayer(run_dir, config)
    n = len(replayer.frame_times())
    if config.workers == 1 or n <= _CHUNK_FRAMES:
        return n, _serial(replayer)
    chosen = replayer.stage.renderer_name
    replayer.close()
    return n, _pooled(Path(run_dir), dataclasses.replace(config, renderer=chosen, progress=False), n)
