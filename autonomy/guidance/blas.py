"""Limit the threads of the loaded OpenBLAS libraries while solving many tiny dense problems.

The fast-MPC interior point factorises matrices of a few dozen rows hundreds of times per second; multi-threaded
OpenBLAS on such sizes only adds synchronisation, and on a loaded machine its spinning threads slow each call by an
order of magnitude. :func:`blas_threads` sets the thread count of every OpenBLAS copy in the process (numpy's and
scipy's wheels each bundle one) for the duration of a ``with`` block and restores it afterwards. It is a process-wide
setting: runs that host many agents may rather export ``OPENBLAS_NUM_THREADS=1`` once.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["blas_threads"]

_SETTERS = ("scipy_openblas_set_num_threads64_", "scipy_openblas_set_num_threads", "openblas_set_num_threads64_",
            "openblas_set_num_threads")
_GETTERS = ("scipy_openblas_get_num_threads64_", "scipy_openblas_get_num_threads", "openblas_get_num_threads64_",
            "openblas_get_num_threads")


@functools.lru_cache(maxsize=1)
def _libraries() -> tuple[tuple[object, object], ...]:
    """(setter, getter) pairs of the OpenBLAS libraries mapped into this process (Linux ``/proc/self/maps``)."""
    try:
        with open("/proc/self/maps") as fh:
            paths = sorted({line.split()[-1] for line in fh if "openblas" in line.lower() and "/" in line})
    except OSError:
        return ()
    out = []
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        setter = next((getattr(lib, n) for n in _SETTERS if hasattr(lib, n)), None)
        getter = next((getattr(lib, n) for n in _GETTERS if hasattr(lib, n)), None)
        if setter is not None and getter is not None:
            out.append((setter, getter))
    return tuple(out)


@contextmanager
def blas_threads(n: int = 1) -> Iterator[None]:
    """Run the ``with`` block with ``n`` OpenBLAS threads (no-op where no OpenBLAS is found)."""
    libs = _libraries()
    before = [int(get()) for _, get in libs]
    for setter, _ in libs:
        setter(int(n))
    try:
        yield
    finally:
        for (setter, _), k in zip(libs, before, strict=True):
            setter(k)
