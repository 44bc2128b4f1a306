"""Redirection of file descriptor 1, where PyBullet's C code prints (EGL plugin banners, build time), so that the
``skytrack`` command's own output (e.g. ``bench --json``) stays clean."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator

__all__ = ["stdout_to_fd", "quiet_c_stdout"]


@contextlib.contextmanager
def stdout_to_fd(fd: int) -> Iterator[None]:
    """Send everything written to descriptor 1 (by Python and by C libraries) to descriptor ``fd`` meanwhile."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(fd, 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


@contextlib.contextmanager
def quiet_c_stdout() -> Iterator[None]:
    """Discard what is written to descriptor 1 meanwhile (use around chatty PyBullet calls only)."""
    try:
        sink = os.open(os.devnull, os.O_WRONLY)
    except OSError:  # pragma: no cover - no /dev/null: print as usual
        yield
        return
    try:
        with stdout_to_fd(sink):
            yield
    finally:
        os.close(sink)
