"""On-disk cache of imported maps.

Importing an OpenStreetMap extract — parsing, fitting the road splines, clearing roads of buildings, keeping the
largest connected component — and meshing its road surface take seconds (Helsinki: ≈ 2.4 s and 0.5 s) and are
the same for every run of a world; loading the stored result takes ≈ 0.1 s. Entries live under
``cache_root() / "maps"``; an entry's key covers the map file's bytes, the import parameters, the source of the
``worlds`` package (any change to the import code makes new entries) and the numpy version. An entry is written to a
temporary file and published by atomic rename, so parallel campaign workers never read half an entry; a cache that
cannot be written is skipped with one warning: the cache only ever saves time.

Entries are untrusted input. They are ``.npz`` files of plain data (:mod:`worlds.cache_codec`), read with
``allow_pickle=False``: an entry cannot run code, whatever was written in its place. Each entry's header names its
format, kind and full key digest, checked on load; an entry that cannot be read (truncated, damaged: the zip's CRCs),
of another format, or holding another key's value is rebuilt with a warning naming it. Entries of the earlier pickle
format (``*.pkl``) are never read, only deleted. The ``KEEP_PER_KIND`` most recently used entries of each kind are
kept.
"""

from __future__ import annotations

import hashlib
import logging
import os
import tempfile
from collections.abc import Callable, Sequence
from functools import lru_cache
from pathlib import Path
from typing import TypeVar

import numpy as np

from worlds.cache_codec import decode, encode

__all__ = ["KEEP_PER_KIND", "cache_root", "cached"]

_LOG = logging.getLogger(__name__)
_FORMAT = "skytrack-map-2"  # bump when the meaning of an entry changes
KEEP_PER_KIND = 16  # entries kept per kind, most recently used first
_T = TypeVar("_T")
_warned: set[str] = set()


def cache_root() -> Path:
    """Root of skytrack's caches: ``$SKYTRACK_CACHE_DIR``, else ``$XDG_CACHE_HOME/skytrack``, else
    ``~/.cache/skytrack``."""
    env = os.environ.get("SKYTRACK_CACHE_DIR")
    if env:
        return Path(env).expanduser()
    return Path(os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")) / "skytrack"


@lru_cache(maxsize=1)
def _source_digest() -> bytes:
    """Digest of the ``worlds`` package's Python source (read once per process)."""
    root = Path(__file__).resolve().parent
    h = hashlib.sha256()
    for f in sorted(root.rglob("*.py")):
        h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
    return h.digest()


def _warn_once(msg: str) -> None:
    if msg not in _warned:
        _warned.add(msg)
        _LOG.warning(msg)


def cached(kind: str, key: Sequence[bytes | str], build: Callable[[], _T]) -> _T:
    """``build()``, or its result stored by an earlier call with the same ``kind`` and ``key``.

    Parameters
    ----------
    kind : str
        Entry family, part of the file name (e.g. ``"osm"``).
    key : sequence of bytes or str
        Everything the result depends on besides the ``worlds`` source and numpy (e.g. the map file's bytes and the
        import parameters).
    build : callable
        Computes the result; its exceptions propagate and nothing is stored. The result must be data
        :mod:`worlds.cache_codec` can store (else it is returned uncached, with a warning).
    """
    h = hashlib.sha256(_FORMAT.encode() + b"\0" + kind.encode() + b"\0" + _source_digest()
                       + np.__version__.encode())
    for part in key:
        h.update(b"\0" + (part if isinstance(part, bytes) else part.encode()))
    digest = h.hexdigest()
    entry = cache_root() / "maps" / f"{kind}_{digest[:24]}.npz"
    header = {"format": _FORMAT, "kind": kind, "key": digest}
    if entry.is_file():
        try:
            with entry.open("rb") as f:
                value = decode(f, header)
            _touch(entry)
            return value
        except Exception as exc:  # noqa: BLE001 - a damaged entry of any kind is rebuilt
            _LOG.warning("map cache entry %s unusable (%s: %s): rebuilding it", entry, type(exc).__name__, exc)
    value = build()
    try:
        entry.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=entry.parent, prefix=".tmp-", suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as f:
                encode(value, header, f)
            os.replace(tmp, entry)  # atomic: readers see no entry or a whole one
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        _prune(entry.parent, kind)
    except OSError as exc:
        _warn_once(f"map cache {entry.parent} not writable ({exc}): maps are imported on every run")
    except TypeError as exc:
        _warn_once(f"map cache: a {kind!r} value cannot be stored ({exc}): it is built on every run")
    return value


def _touch(entry: Path) -> None:
    """Mark an entry as used now (pruning keeps the most recently used)."""
    try:
        os.utime(entry)
    except OSError:
        pass  # a read-only cache still serves its entries


def _prune(directory: Path, kind: str) -> None:
    """Keep the ``KEEP_PER_KIND`` most recently used entries of ``kind``: every change to the import code or the
    parameters makes a new entry (several MB for a city), and old ones would otherwise pile up."""
    for legacy in directory.glob(f"{kind}_*.pkl"):  # the earlier, pickled format: never read again
        legacy.unlink(missing_ok=True)
    entries = sorted(directory.glob(f"{kind}_*.npz"), key=lambda f: f.stat().st_mtime, reverse=True)
    for old in entries[KEEP_PER_KIND:]:
        old.unlink(missing_ok=True)
