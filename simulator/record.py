"""Writing a run directory incrementally, so a run that raises, is interrupted or is killed still leaves a readable
record.

Layout of a run directory::

    world.yaml            the resolved world (after --set overrides), exactly as the run used it
    run.json              seed, world name and source, versions, start time, the source's fingerprint (``code``)
    events.jsonl          one JSON object per line: run_start, collisions, saturations, solver failures, ..., run_end
    metrics.json          rewritten atomically at every flush (partial) and at the end (final; "complete": true)
    timeseries/<stream>/part-NNNNN.npy
                          columnar chunks: one structured array per chunk (a field per column), each written
                          atomically (older records hold ``.npz`` chunks, one array per column; both load)
    plots/*.png           figures made at the end of the run

Streams are "long" tables: one row per entity per sample, with ``tick`` and ``t`` columns, e.g. ``uav_truth`` has
``tick, t, uav, x, y, z, qx, qy, qz, qw, vx, vy, vz``. :func:`simulator.runrecord.load_run` concatenates the chunks.
"""

from __future__ import annotations

import gzip
import json
import os
import time
from pathlib import Path
from collections.abc import Mapping
from typing import Any

import numpy as np

from simulator.streams import StreamSchema

__all__ = ["RunRecorder", "atomic_write_text", "json_default"]


def json_default(obj: Any) -> Any:
    """JSON encoder fallback for numpy scalars and arrays."""
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def atomic_write_text(path: Path, text: str, sync: bool = True) -> None:
    """Write ``text`` to ``path`` via a temporary file and rename, so readers never see half a file.

    ``sync``: force the text to the disk before the rename (``os.fsync``), so that even a crash of the machine leaves
    the old or the new file. Without it a killed process still leaves one of them whole (the written text is in the
    operating system's cache); only a crash of the machine itself can lose it.
    """
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
        if sync:
            f.flush()
            os.fsync(f.fileno())
    os.replace(tmp, path)


class _Stream:
    def __init__(self, folder: Path, schema: StreamSchema | None = None) -> None:
        self.folder = folder
        self.schema = schema
        self.columns: dict[str, list] = {}
        self.rows = 0
        self.parts = 0

    def extend(self, columns: dict[str, Any], n: int) -> None:
        """Append ``n`` rows given column-wise (each value a sequence of length ``n``)."""
        if self.columns and columns.keys() != self.columns.keys():
            differ = set(self.columns) ^ set(columns)
            raise KeyError(f"stream {self.folder.name}: columns differ from the first rows: {sorted(differ)}")
        if not self.columns:
            if self.schema is not None:
                self.schema.check(tuple(columns))
            self.columns = {k: [] for k in columns}
        for k, v in columns.items():
            self.columns[k].extend(v)
        self.rows += n

    def flush(self) -> None:
        """Write the buffered rows as the next chunk: one structured array, a field per column (one ``.npy`` header
        per chunk: a zip of one array per column cost ≈ 4× more to write and 8× more to read back)."""
        if self.rows == 0:
            return
        self.folder.mkdir(parents=True, exist_ok=True)
        arrays = {k: np.asarray(v) for k, v in self.columns.items()}
        chunk = np.empty(self.rows, dtype=[(k, a.dtype, a.shape[1:]) for k, a in arrays.items()])
        for k, a in arrays.items():
            chunk[k] = a
        final = self.folder / f"part-{self.parts:05d}.npy"
        tmp = self.folder / f".part-{self.parts:05d}.tmp.npy"
        with open(tmp, "wb") as f:
            np.save(f, chunk)
        os.replace(tmp, final)
        self.parts += 1
        self.columns = {k: [] for k in self.columns}
        self.rows = 0


class RunRecorder:
    """Writes one run directory.

    Parameters
    ----------
    out_dir : Path
        The run directory; created if missing. Existing record files in it are replaced.
    schemas : mapping of str to StreamSchema, optional
        Declared streams (:data:`simulator.streams.STREAMS`): the first row of each is checked against its schema.
    """

    def __init__(self, out_dir: Path, schemas: Mapping[str, StreamSchema] | None = None) -> None:
        self.out_dir = Path(out_dir)
        self.schemas = dict(schemas or {})
        self.out_dir.mkdir(parents=True, exist_ok=True)
        for old in ("events.jsonl", "metrics.json"):
            (self.out_dir / old).unlink(missing_ok=True)
        ts = self.out_dir / "timeseries"
        if ts.exists():
            for part in (*ts.glob("*/*.npy"), *ts.glob("*/*.npz")):
                part.unlink()
        self._events = open(self.out_dir / "events.jsonl", "a", encoding="utf-8", buffering=1)
        self._streams: dict[str, _Stream] = {}
        self._lines: set[str] = set()  # files of append_line this record has started
        self.event_counts: dict[str, int] = {}
        self.closed = False

    # -- static files ----------------------------------------------------------------------------------------------
    def write_text(self, name: str, text: str, sync: bool = True) -> Path:
        path = self.out_dir / name
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(path, text, sync)
        return path

    def write_json(self, name: str, data: Any, sync: bool = True) -> Path:
        return self.write_text(name, json.dumps(data, indent=2, default=json_default) + "\n", sync)

    def append_line(self, name: str, data: Any) -> None:
        """Append ``data`` as one JSON line to the file ``name`` (written at once; replaced with a new record). A name
        ending in ``.gz`` gets each line as a gzip member of its own (``gzip.open`` reads them as one text; a run killed
        mid-write loses its last line only)."""
        path = self.out_dir / name
        mode = "ab" if name in self._lines else "wb"
        self._lines.add(name)
        line = (json.dumps(data, default=json_default) + "\n").encode("utf-8")
        if name.endswith(".gz"):
            line = gzip.compress(line, compresslevel=6, mtime=0)
        with open(path, mode) as f:
            f.write(line)

    # -- events ----------------------------------------------------------------------------------------------------
    def event(self, type: str, tick: int | None = None, t: float | None = None, /, **fields: Any) -> None:
        """Append one event line (flushed at once); ``fields`` may not redefine ``type``, ``tick`` or ``t``."""
        fields = {k: v for k, v in fields.items() if k not in ("type", "tick", "t")}
        rec = {"type": type, "tick": tick, "t": t, **fields, "wall": round(time.time(), 3)}
        self._events.write(json.dumps(rec, default=json_default) + "\n")
        self.event_counts[type] = self.event_counts.get(type, 0) + 1

    # -- time series -----------------------------------------------------------------------------------------------
    def append(self, stream: str, **row: Any) -> None:
        """Append one row to ``stream`` (buffered until :meth:`flush`)."""
        self._stream(stream).extend({k: (v,) for k, v in row.items()}, 1)

    def append_rows(self, stream: str, columns: dict[str, Any]) -> None:
        """Append several rows given column-wise (all columns of equal length; scalars are broadcast)."""
        arrays = {k: np.asarray(v) for k, v in columns.items()}  # each column made an array once (np.ndim would too)
        lengths = {len(a) for a in arrays.values() if a.ndim > 0}
        if len(lengths) != 1:
            raise ValueError(f"stream {stream}: columns of unequal or no length {lengths}")
        (n,) = lengths
        cols = {k: (a.tolist() if a.ndim > 0 else [columns[k]] * n) for k, a in arrays.items()}
        self._stream(stream).extend(cols, n)

    def _stream(self, name: str) -> _Stream:
        if name not in self._streams:
            self._streams[name] = _Stream(self.out_dir / "timeseries" / name, self.schemas.get(name))
        return self._streams[name]

    def flush(self, metrics: dict[str, Any] | None = None, sync: bool = True) -> None:
        """Write buffered rows as new chunks; rewrite ``metrics.json`` when given (``sync``: see
        :func:`atomic_write_text`; the chunks are never synced)."""
        for s in self._streams.values():
            s.flush()
        if metrics is not None:
            self.write_json("metrics.json", metrics, sync)
        self._events.flush()

    def close(self) -> None:
        if not self.closed:
            self.flush()
            self._events.close()
            self.closed = True
