"""MP4 encoding of RGB frames: H.264 / yuv420p through the ffmpeg binary of ``imageio-ffmpeg`` (plays in browsers),
else OpenCV's ``mp4v`` writer with a warning (plays in most desktop players, not in browsers).

The frames go to a temporary file beside the video, renamed to the video's name only when the encoder is closed
after the last frame: an interrupted or failed render leaves no short video that looks complete (and keeps a video
that was there before it).
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from types import TracebackType

import cv2
import numpy as np

__all__ = ["VideoEncoder"]


class VideoEncoder:
    """Writes frames (H, W, 3) RGB uint8 to an MP4 file; use as a context manager.

    Parameters
    ----------
    path : Path
        Output file.
    width, height : int
        Frame size, pixels (even).
    fps : int
        Frame rate, Hz.
    crf : int
        x264 constant rate factor.
    preset : str
        x264 speed preset.
    backend : {"auto", "ffmpeg", "opencv"}
        ``auto`` uses ffmpeg when ``imageio_ffmpeg`` imports, else OpenCV.

    Notes
    -----
    :meth:`close` (or leaving the ``with`` block normally) finishes the video at ``path``; :meth:`abort` (or leaving
    the block by an exception, Ctrl-C included) removes the partial file instead.
    """

    def __init__(self, path: Path, width: int, height: int, fps: int, crf: int = 23, preset: str = "veryfast",
                 backend: str = "auto") -> None:
        self.path = Path(path)
        self.partial = self.path.with_name(f".{self.path.stem}.partial-{os.getpid()}{self.path.suffix}")
        """The file being written until :meth:`close` renames it to :attr:`path`."""
        self.size = (int(width), int(height))
        self.frames = 0
        self._gen = None
        self._cv = None
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if backend in ("auto", "ffmpeg"):
            try:
                import imageio_ffmpeg

                self._gen = imageio_ffmpeg.write_frames(
                    str(self.partial), self.size, pix_fmt_in="rgb24", pix_fmt_out="yuv420p", fps=fps, codec="libx264",
                    quality=None, macro_block_size=2,
                    output_params=["-crf", str(int(crf)), "-preset", preset, "-movflags", "+faststart"])
                self._gen.send(None)
                self.backend = "ffmpeg"
            except ImportError:
                if backend == "ffmpeg":
                    raise
                warnings.warn("imageio-ffmpeg is not installed: writing MPEG-4 Part 2 (mp4v) with OpenCV, which "
                              "browsers do not play; `pip install imageio-ffmpeg` for H.264", stacklevel=2)
        if self._gen is None:
            self._cv = cv2.VideoWriter(str(self.partial), cv2.VideoWriter_fourcc(*"mp4v"), float(fps), self.size)
            if not self._cv.isOpened():
                raise RuntimeError(f"OpenCV could not open a video writer for {self.path}")
            self.backend = "opencv"

    def write(self, rgb: np.ndarray) -> None:
        """Append one frame (H, W, 3) RGB uint8."""
        if rgb.shape != (self.size[1], self.size[0], 3) or rgb.dtype != np.uint8:
            raise ValueError(f"frame must be ({self.size[1]}, {self.size[0]}, 3) uint8, got {rgb.shape} {rgb.dtype}")
        if self._gen is not None:
            self._gen.send(np.ascontiguousarray(rgb))
        else:
            self._cv.write(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
        self.frames += 1

    def _finish_writer(self) -> None:
        if self._gen is not None:
            gen, self._gen = self._gen, None
            gen.close()
        if self._cv is not None:
            cv, self._cv = self._cv, None
            cv.release()

    def close(self) -> None:
        """Finish the file (flushes the encoder) and give it its name."""
        if self._gen is None and self._cv is None:
            return
        try:
            self._finish_writer()
        except BaseException:
            self.partial.unlink(missing_ok=True)
            raise
        os.replace(self.partial, self.path)

    def abort(self) -> None:
        """Stop writing and remove the partial file (the video at :attr:`path`, if any, is left as it was)."""
        try:
            self._finish_writer()
        finally:
            self.partial.unlink(missing_ok=True)

    def __enter__(self) -> VideoEncoder:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()
