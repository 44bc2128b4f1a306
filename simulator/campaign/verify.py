"""Checking a campaign's stored runs before a resume trusts them.

A journaled run is not run again, so its run directory must still be what the run left: a truncated ``metrics.json``,
a damaged record chunk or a deleted directory would otherwise stay in the campaign for good. When the campaign
process journals a run it records the size and SHA-256 of every file in the run directory (:func:`manifest`, the
``files`` of the journal line); on resume :func:`damage` compares the directory against it. Journal lines written
before ``files`` existed are checked by loading instead: ``metrics.json`` must be a JSON object and every record
chunk must load with ``numpy.load(allow_pickle=False)``.
"""

from __future__ import annotations

import hashlib
import os
import json
import zipfile
from pathlib import Path

import numpy as np

from simulator.campaign.config import RunReport

__all__ = ["damage", "manifest"]


def _digest(path: Path) -> tuple[int, str]:
    with path.open("rb") as f:
        return os.fstat(f.fileno()).st_size, hashlib.file_digest(f, "sha256").hexdigest()


def manifest(run_dir: Path) -> dict[str, list]:
    """``{relative path: [size in bytes, SHA-256 hex]}`` of every file under ``run_dir`` (empty when it does not
    exist: a worker that died before writing anything)."""
    if not run_dir.is_dir():
        return {}
    out: dict[str, list] = {}
    for f in sorted(run_dir.rglob("*")):
        if f.is_file() and not f.is_symlink():
            size, sha = _digest(f)
            out[f.relative_to(run_dir).as_posix()] = [size, sha]
    return out


def damage(run_dir: Path, report: RunReport) -> str | None:
    """What is wrong with the stored run ``report`` in ``run_dir``, or None when it is intact."""
    if report.files is None:
        return _load_check(run_dir, report)
    if report.files and not run_dir.is_dir():
        return f"its run directory {run_dir.name} is missing"
    for rel, (size, sha) in sorted(report.files.items()):
        path = run_dir / rel
        try:
            have = _digest(path)
        except FileNotFoundError:
            return f"{rel} is missing"
        except OSError as exc:
            return f"{rel} cannot be read ({exc})"
        if have[0] != size:
            return f"{rel} has {have[0]} bytes, {size} when the run finished"
        if have[1] != sha:
            return f"{rel} differs from the file the run wrote (SHA-256 {have[1][:12]}…, was {sha[:12]}…)"
    return None


def _load_check(run_dir: Path, report: RunReport) -> str | None:
    """Checks for runs journaled without ``files``: the directory exists and, for completed runs, the metrics and
    every record chunk load."""
    if not run_dir.is_dir():
        return f"its run directory {run_dir.name} is missing"
    if report.status != "completed":
        return None
    try:
        metrics = json.loads((run_dir / "metrics.json").read_text(encoding="utf-8"))
        if not isinstance(metrics, dict):
            raise ValueError("not a JSON object")
    except (OSError, ValueError) as exc:
        return f"metrics.json does not load ({type(exc).__name__}: {exc})"
    for chunk in sorted((run_dir / "timeseries").glob("*/part-*.np[yz]")):
        try:
            with open(chunk, "rb") as f:
                loaded = np.load(f, allow_pickle=False)
                if isinstance(loaded, np.lib.npyio.NpzFile):
                    for name in loaded.files:
                        loaded[name]
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            return f"{chunk.relative_to(run_dir).as_posix()} does not load ({type(exc).__name__}: {exc})"
    return None
