"""Reading a run directory back (complete or partial): time series as numpy arrays (or pandas frames), events,
metrics, and the set-membership search's set snapshots."""

from __future__ import annotations

import gzip
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["RecordError", "RunRecord", "SetSnapshot", "load_run", "load_search_sets", "load_stream"]


class RecordError(ValueError):
    """A file of a run directory that cannot be read (corrupt, truncated, not what its name says); the message
    names the file."""


def _chunk(p: Path) -> dict[str, np.ndarray]:
    """One chunk's columns; never unpickles (``allow_pickle=False``: a record holds plain arrays only)."""
    try:
        if p.suffix == ".npy":
            a = np.load(p, allow_pickle=False)
            if a.dtype.names is None:
                raise ValueError(f"an array of {a.dtype} without named columns")
            return {k: a[k] for k in a.dtype.names}
        with np.load(p, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError, KeyError) as exc:  # zipfile.BadZipFile is an OSError
        raise RecordError(f"{p}: not a readable record chunk ({type(exc).__name__}: {exc})") from exc


def _json_file(p: Path) -> dict[str, Any]:
    if not p.exists():
        return {}
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        raise RecordError(f"{p}: not readable JSON ({type(exc).__name__}: {exc})") from exc
    if not isinstance(data, dict):
        raise RecordError(f"{p}: a JSON {type(data).__name__}, expected an object")
    return data


def load_stream(folder: Path) -> dict[str, np.ndarray]:
    """Concatenate the chunks of one stream folder into one array per column (empty dict if none): ``part-*.npy``
    (a structured array each) and the ``part-*.npz`` of older records (an array per column)."""
    parts = sorted((*Path(folder).glob("part-*.npy"), *Path(folder).glob("part-*.npz")), key=lambda p: p.stem)
    if not parts:
        return {}
    chunks = [_chunk(p) for p in parts]
    for p, c in zip(parts[1:], chunks[1:], strict=True):
        if c.keys() != chunks[0].keys():
            raise RecordError(f"{p}: columns {sorted(c)} differ from those of {parts[0].name} {sorted(chunks[0])}")
    return {k: np.concatenate([c[k] for c in chunks]) for k in chunks[0]}


@dataclass
class RunRecord:
    """A run directory, loaded.

    Attributes
    ----------
    path : Path
    run : dict
        Contents of ``run.json`` (seed, world, versions).
    metrics : dict
        Contents of ``metrics.json`` (``{}`` if the run died before the first flush).
    events : list[dict]
        Every event, in order. A truncated last line (a killed process) is skipped.
    streams : dict[str, dict[str, np.ndarray]]
        Time series by stream name, column name.
    """

    path: Path
    run: dict[str, Any]
    metrics: dict[str, Any]
    events: list[dict[str, Any]]
    streams: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)

    @property
    def status(self) -> str:
        """How the run ended: ``completed``, ``interrupted``, ``diverged``, ``error`` or ``unknown`` (killed: no run_end
        event)."""
        for ev in reversed(self.events):
            if ev.get("type") == "run_end":
                return str(ev.get("status", "unknown"))
        return "unknown"

    def stream(self, name: str) -> dict[str, np.ndarray]:
        if name not in self.streams:
            raise KeyError(f"no stream {name!r} in {self.path} (have: {sorted(self.streams)})")
        return self.streams[name]

    def to_pandas(self, name: str):  # pragma: no cover - optional dependency
        """The stream as a ``pandas.DataFrame`` (pandas is not a dependency of skytrack; install it to use this)."""
        import pandas as pd

        return pd.DataFrame(self.stream(name))


def load_run(path: str | Path) -> RunRecord:
    """Load a (possibly partial) run directory.

    Raises
    ------
    FileNotFoundError
        No directory at ``path``.
    RecordError
        A file of it cannot be read (the message names the file).
    """
    path = Path(path)
    if not path.is_dir():
        raise FileNotFoundError(f"no run directory at {path}")
    run, metrics = _json_file(path / "run.json"), _json_file(path / "metrics.json")
    events: list[dict[str, Any]] = []
    ev_path = path / "events.jsonl"
    if ev_path.exists():
        for line in ev_path.read_text(encoding="utf-8").splitlines():
            try:
                events.append(json.loads(line))
            except json.JSONDecodeError:
                continue
    streams = {}
    ts = path / "timeseries"
    if ts.is_dir():
        for folder in sorted(p for p in ts.iterdir() if p.is_dir()):
            data = load_stream(folder)
            if data:
                streams[folder.name] = data
    return RunRecord(path=path, run=run, metrics=metrics, events=events, streams=streams)


@dataclass(frozen=True)
class SetSnapshot:
    """The search team's sets at one step (a line of ``search_sets.jsonl.gz``): ``sets[uav] = (X, X̄)`` as WKT."""

    tick: int
    t: float
    sets: dict[int, tuple[str, str]]


def load_search_sets(path: str | Path) -> list[SetSnapshot]:
    """The set snapshots of the run directory ``path`` in time order (``[]`` when it has none):
    ``search_sets.jsonl.gz``, or the plain ``search_sets.jsonl`` of older runs.

    A UAV written ``same_as`` another gets that UAV's sets; a truncated last line (a killed run) ends the list.
    """
    path = Path(path)
    gz, plain = path / "search_sets.jsonl.gz", path / "search_sets.jsonl"
    if not (gz.exists() or plain.exists()):
        return []
    out = []
    with (gzip.open(gz, "rt", encoding="utf-8") if gz.exists() else open(plain, encoding="utf-8")) as f:
        try:
            for line in f:
                if line.strip():
                    out.append(_snapshot(json.loads(line)))
        except (EOFError, gzip.BadGzipFile, json.JSONDecodeError, KeyError):  # a run killed while writing a line
            pass
    return out


def _snapshot(rec: dict[str, Any]) -> SetSnapshot:
    sets: dict[int, tuple[str, str]] = {}
    for u in rec["uavs"]:
        sets[int(u["uav"])] = sets[int(u["same_as"])] if "same_as" in u else (u["X"], u["Xbar"])
    return SetSnapshot(tick=int(rec["tick"]), t=float(rec["t"]), sets=sets)
