"""Recorded numbers that hold bit for bit on the machine that recorded them and to a tolerance on any other.

A digest of the bytes of a computation holds only where the floating-point arithmetic is the same: another CPU makes
numpy's OpenBLAS pick another kernel (sums in another order) and numba's LLVM emit other instructions, and the last
bits change — 1e-13 to 1e-11 relative after a 3 s closed-loop run here, when OpenBLAS was made to take another
kernel, with every discrete outcome (detections, track ids, events) the same. So a record keeps both: digests, which
the machine that wrote them (:func:`machine_key`) checks bit for bit, and a short summary of every column
(:func:`summarise`), which any other machine checks to a relative tolerance far above rounding and far below what a
change of wiring or arithmetic moves.
"""

from __future__ import annotations

import hashlib
import json
import math
import platform
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["RTOL", "close", "column_digest", "differences", "flatten", "machine_key", "summarise"]

RTOL = 1e-6
"""Relative tolerance of a summary on another machine: ``|a − b| <= RTOL · (1 + |a|)`` per entry."""

SAMPLES = 6
"""Values of a column kept besides its sums and extremes, at evenly spaced indices."""


def _cpu() -> str:
    """Vendor, family, model and flags of the first processor (Linux), else the platform's processor string."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            text = f.read().split("\n\n", 1)[0]
    except OSError:
        return platform.processor()
    keep = ("vendor_id", "cpu family", "model", "flags")
    fields = dict(line.split(":", 1) for line in text.splitlines() if ":" in line)
    return "|".join(fields.get(k, "").strip() if k != "flags" else " ".join(sorted(fields.get(k, "").split()))
                    for k in keep)


def machine_key() -> str:
    """Short hash of what sets the bits of a computation here: the architecture, the processor (vendor, family,
    model, flags) and the versions of the numerical packages."""
    from importlib.metadata import PackageNotFoundError, version

    parts = [platform.machine(), platform.python_version(), _cpu()]
    for pkg in ("numpy", "scipy", "numba", "llvmlite", "pybullet", "casadi"):
        try:
            parts.append(f"{pkg}={version(pkg)}")
        except PackageNotFoundError:
            parts.append(f"{pkg}=none")
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]


def column_digest(values: Any) -> str:
    """SHA-256 (20 hex digits) of an array's dtype, shape and bytes."""
    a = np.ascontiguousarray(values)
    return hashlib.sha256(str(a.dtype).encode() + str(a.shape).encode() + a.tobytes()).hexdigest()[:20]


def summarise(values: Any) -> list:
    """A column's summary: for numbers ``[size, nan count, Σx, Σ|x|, min, max, x at SAMPLES evenly spaced
    indices]`` (NaNs left out of the sums and extremes); for anything else ``["digest", sha256 of its bytes]``."""
    a = np.ascontiguousarray(values)
    if a.dtype.kind not in "biuf":
        return ["digest", column_digest(a)]
    x = a.astype(float).ravel()
    finite = x[~np.isnan(x)]
    head = [float(x.size), float(x.size - finite.size)]
    if not finite.size:
        return head
    idx = np.unique(np.linspace(0, x.size - 1, SAMPLES).round().astype(int))
    return head + [float(finite.sum()), float(np.abs(finite).sum()), float(finite.min()), float(finite.max()),
                   *(float(v) for v in x[idx])]


def flatten(obj: Any, prefix: str = "") -> dict[str, Any]:
    """A JSON-like object as ``{path: leaf}`` (numbers as floats, other leaves as they are)."""
    out: dict[str, Any] = {}
    if isinstance(obj, Mapping):
        for k, v in sorted(obj.items()):
            out.update(flatten(v, f"{prefix}.{k}" if prefix else str(k)))
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            out.update(flatten(v, f"{prefix}[{i}]"))
    elif isinstance(obj, bool) or obj is None or isinstance(obj, str):
        out[prefix] = obj
    elif isinstance(obj, (int, float)):
        out[prefix] = float(obj)
    else:
        out[prefix] = json.dumps(obj, sort_keys=True, default=str)
    return out


def close(want: Any, got: Any, rtol: float = RTOL) -> bool:
    """Whether two summaries (or two leaves) agree: the same strings and shapes, numbers within ``rtol`` relative
    (NaN only against NaN)."""
    if isinstance(want, list) and isinstance(got, list):
        return len(want) == len(got) and all(close(a, b, rtol) for a, b in zip(want, got, strict=True))
    if isinstance(want, float) and isinstance(got, float):
        if math.isnan(want) or math.isnan(got):
            return math.isnan(want) and math.isnan(got)
        if math.isinf(want) or math.isinf(got):
            return want == got
        return abs(want - got) <= rtol * (1.0 + abs(want))
    return want == got


def differences(want: Mapping[str, Any], got: Mapping[str, Any], rtol: float = RTOL) -> list[str]:
    """Keys of two ``{name: summary}`` mappings whose summaries do not agree (:func:`close`), or that only one has."""
    return sorted(k for k in set(want) | set(got) if k not in want or k not in got or not close(want[k], got[k], rtol))
