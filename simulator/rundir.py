"""Where a run writes: every run starts from a clean directory.

A run directory given again (``--out runs/demo`` twice) is not written over: the earlier run is moved aside to the
first free numbered sibling (``runs/demo`` -> ``runs/demo.1``, then ``runs/demo.2`` ...), whole, so no file of it
(``plots/search.png``, ``search_sets.jsonl.gz`` ...) can be mistaken for the new run's. Only a skytrack run directory
is ever moved; any other directory that is not empty (a home directory, a project) is refused, untouched.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

__all__ = ["RunDirError", "check_out_dir", "fresh_run_dir", "is_run_dir"]


class RunDirError(ValueError):
    """A run directory that cannot be used: not creatable, or a non-empty directory that is not a run's."""


def is_run_dir(path: Path) -> bool:
    """Whether ``path`` is a directory a skytrack run wrote: ``run.json`` naming a world and a seed, or an
    ``events.jsonl`` that is empty (a run killed as it began) or starts with a ``run_start`` event."""
    path = Path(path)
    if not path.is_dir():
        return False
    try:
        run = json.loads((path / "run.json").read_text(encoding="utf-8"))
        if isinstance(run, dict) and {"world", "seed"} <= run.keys():
            return True
    except (OSError, ValueError):
        pass
    try:
        with open(path / "events.jsonl", encoding="utf-8") as f:
            first = f.readline()
    except (OSError, ValueError):
        return False
    if not first.strip():
        return True
    try:
        return json.loads(first).get("type") == "run_start"
    except (ValueError, AttributeError):
        return False


def check_out_dir(path: Path) -> None:
    """Raise :class:`RunDirError` unless a run can write to ``path`` (nothing is created or moved): a missing
    directory under a writable one, an empty directory, or an earlier run's directory."""
    try:
        _check(Path(path))
    except OSError as exc:  # e.g. a directory that cannot be listed
        raise RunDirError(f"{path}: {exc.strerror or exc}") from None


def _check(path: Path) -> None:
    if path.exists() or path.is_symlink():
        if not path.is_dir():
            raise RunDirError(f"{path} exists and is not a directory")
        if not any(path.iterdir()):
            if not os.access(path, os.W_OK | os.X_OK):
                raise RunDirError(f"{path} is not writable")
            return
        if not is_run_dir(path):
            raise RunDirError(f"{path} is a non-empty directory that is not a skytrack run directory; refusing to "
                              "write into it or move it (give a new or empty directory)")
        if not os.access(path.absolute().parent, os.W_OK | os.X_OK):
            raise RunDirError(f"{path} holds an earlier run that cannot be moved aside: {path.absolute().parent} is "
                              "not writable")
        return
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise RunDirError(f"{path} cannot be created: {parent} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise RunDirError(f"{path} cannot be created: {parent} is not writable")


def _next_sibling(path: Path) -> Path:
    pattern = re.compile(re.escape(path.name) + r"\.(\d+)")
    taken = [int(m.group(1)) for p in path.parent.iterdir() if (m := pattern.fullmatch(p.name))]
    n = max(taken, default=0) + 1
    while (path.parent / f"{path.name}.{n}").exists():
        n += 1
    return path.parent / f"{path.name}.{n}"


def fresh_run_dir(path: Path) -> Path | None:
    """Make ``path`` an empty directory for a new run; returns where an earlier run there was moved (None if there
    was none).

    Raises
    ------
    RunDirError
        ``path`` cannot be used (see :func:`check_out_dir`), or making or moving it failed.
    """
    path = Path(path)
    check_out_dir(path)
    moved = None
    try:
        if path.is_dir() and any(path.iterdir()):
            moved = _next_sibling(path)
            os.rename(path, moved)
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RunDirError(f"{path}: {exc.strerror or exc}") from None
    return moved
