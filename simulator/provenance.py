"""Which code computed a result: fingerprints of the project's source.

A run records :func:`source_fingerprint` in its ``run.json`` (key ``code``), so results gathered over time — a campaign
resumed or extended after the code changed — say which versions of the source made them
(:func:`code_versions`). The reproductions' job stores key their results with a narrower fingerprint, the import
closure of one job module (:func:`simulator.reproduce.stored.code_fingerprint`); both hash files with
:func:`fingerprint`.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import json
from collections import Counter
from collections.abc import Iterable
from functools import lru_cache
from pathlib import Path

__all__ = ["ROOT", "PACKAGES", "LIBRARIES", "fingerprint", "source_fingerprint", "code_versions", "versions_text"]

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("autonomy", "interfaces", "simulator", "vehicles", "worlds")
"""The project's packages: what the source is."""
LIBRARIES = ("numpy", "scipy", "shapely", "casadi", "pybullet", "numba")
"""Libraries whose version enters every fingerprint (their numerics are part of the result)."""


def fingerprint(files: Iterable[Path], root: Path = ROOT) -> str:
    """SHA-256 (16 hex digits) of ``files`` (paths under ``root``, names and bytes), of every world file
    (``root/worlds/**/*.yaml``) and of the installed versions of :data:`LIBRARIES`."""
    h = hashlib.sha256()
    for p in sorted(set(files)):
        h.update(str(p.relative_to(root)).encode() + b"\0" + p.read_bytes() + b"\0")
    for p in sorted((root / "worlds").rglob("*.yaml")):
        h.update(str(p.relative_to(root)).encode() + b"\0" + p.read_bytes() + b"\0")
    for lib in LIBRARIES:
        try:
            h.update(f"{lib}={importlib.metadata.version(lib)}\0".encode())
        except importlib.metadata.PackageNotFoundError:
            h.update(f"{lib}=-\0".encode())
    return h.hexdigest()[:16]


@lru_cache(maxsize=1)
def source_fingerprint() -> str:
    """:func:`fingerprint` of every Python file of the project's packages: equal for two processes exactly when they
    run the same source (with the same world files and library versions). Computed once per process (≈ 20 ms)."""
    return fingerprint(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def code_versions(run_dirs: Iterable[Path]) -> Counter[str]:
    """How many of the runs in ``run_dirs`` each source version made: their ``run.json``'s ``code``; ``"unrecorded"``
    for runs made before runs recorded it (or whose ``run.json`` cannot be read: it is untrusted input)."""
    out: Counter[str] = Counter()
    for d in run_dirs:
        try:
            code = json.loads((Path(d) / "run.json").read_text(encoding="utf-8")).get("code")
        except (OSError, UnicodeDecodeError, ValueError, AttributeError):
            code = None
        out[code if isinstance(code, str) and code else "unrecorded"] += 1
    return out


def versions_text(counts: Counter[str], current: str | None = None) -> str:
    """One sentence on ``counts`` (:func:`code_versions`): all from ``current`` (default: this process's source), or
    how many runs each other version made."""
    current = current or source_fingerprint()
    total = sum(counts.values())
    if not total:
        return ""
    if counts.get(current, 0) == total:
        return f"all {total} physics runs by this source (code {current})"
    parts = [f"{counts[current]} by this source (code {current})"] if counts.get(current) else []
    parts += [f"{n} made before runs recorded their code" if k == "unrecorded" else f"{n} by code {k}"
              for k, n in counts.most_common() if k != current]
    return f"of {total} physics runs, " + ", ".join(parts)
