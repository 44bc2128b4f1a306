"""Finished jobs of a reproduction's in-process experiments, kept on disk so an interrupted reproduction resumes.

The physics experiments are campaigns with journals of their own (:mod:`simulator.campaign.journal`); the kinematic
loops run through :meth:`simulator.reproduce.report.ReproContext.map`, and with a :class:`JobStore` each finished job's
result is appended to ``<store>/results.jsonl`` as it comes back (one flushed line per job), so a reproduction killed
at any moment keeps every finished job, and a later one with more runs only runs the new jobs.

A stored result is reused only when it was computed by the same code: each line carries :func:`code_fingerprint` of the
job function's module, a hash of its source and of every project module it imports (transitively, function-level
imports included), of the world files and of the numerical libraries' versions. Any change there, however small, means
every stored result runs again (a report is never a mix of two versions of the computing code); a change to how the
report judges or prints the results (rules, tables, findings) keeps them.

The file is untrusted input: results are plain JSON, decoded only into the dataclasses the caller names (never
pickle), and a line that cannot be read or decoded — a torn last line, garbage, a field that does not match its
class — is dropped with a warning into ``results.rejected.jsonl`` and its job runs again. One process at a time
(``store.lock``, as a campaign's).
"""

from __future__ import annotations

import ast
import dataclasses
import json
import logging
import math
from collections.abc import Iterable
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from simulator.campaign.journal import QuietDrop, exclusive_lock, read_jsonl
from simulator.provenance import PACKAGES, ROOT, fingerprint

__all__ = ["JobStore", "StoreError", "code_fingerprint", "decode", "encode"]

_LOG = logging.getLogger(__name__)
RESULTS_FILE = "results.jsonl"
REJECTED_FILE = "results.rejected.jsonl"
LOCK_FILE = "store.lock"
_KINDS = "fiub"  # ndarray dtypes a result may hold: float, int, unsigned, bool
_TAGS = {frozenset(k) for k in (("__float__",), ("__tuple__",), ("__dict__",), ("__ndarray__", "shape", "data"),
                                ("__dataclass__", "fields"))}


class StoreError(RuntimeError):
    """A job store that cannot be used (held by another process)."""


@lru_cache(maxsize=None)
def code_fingerprint(module: str) -> str:
    """SHA-256 (16 hex digits) of the source of ``module`` and of every project module it imports, directly or not
    (anywhere in a file, function-level imports included, with the packages' ``__init__`` files), of every world
    file, and of the installed versions of the numerical libraries: whatever a job of ``module`` can compute with
    (:func:`simulator.provenance.fingerprint` of the closure)."""
    return fingerprint(_closure(module))


def _source(name: str) -> Path | None:
    """The file of project module (or package) ``name``, or None when it is not one of the project's."""
    if name.split(".")[0] not in PACKAGES:
        return None
    base = ROOT.joinpath(*name.split("."))
    for p in (base.with_suffix(".py"), base / "__init__.py"):
        if p.is_file():
            return p
    return None


def _closure(module: str) -> set[Path]:
    """Source files of ``module`` and of the project modules it imports, transitively."""
    seen: set[str] = set()
    files: set[Path] = set()
    todo = [module]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        path = _source(name)
        if path is None:
            continue
        files.add(path)
        parts = name.split(".")
        todo += [".".join(parts[:i]) for i in range(1, len(parts))]  # importing a.b.c runs a and a.b
        package = name if path.name == "__init__.py" else ".".join(parts[:-1])
        for node in ast.walk(ast.parse(path.read_bytes(), filename=str(path))):
            if isinstance(node, ast.Import):
                todo += [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                    base = ".".join([*up, base] if base else up)
                todo.append(base)
                todo += [f"{base}.{a.name}" for a in node.names]  # ``from pkg import module``
    return files


def _type_name(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def encode(x: Any) -> Any:
    """``x`` as JSON-ready data: scalars, strings, lists, tuples, dicts, numeric ndarrays and dataclasses (tagged so
    :func:`decode` restores each type). Raises ``TypeError`` on anything else."""
    if x is None or isinstance(x, (bool, str)):
        return x
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return _float(float(x))
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, np.ndarray):
        if x.dtype.kind not in _KINDS:
            raise TypeError(f"cannot store an ndarray of dtype {x.dtype}")
        flat = [_float(v) if x.dtype.kind == "f" else v for v in x.ravel().tolist()]
        return {"__ndarray__": x.dtype.str, "shape": list(x.shape), "data": flat}
    if isinstance(x, list):
        return [encode(v) for v in x]
    if isinstance(x, tuple):
        return {"__tuple__": [encode(v) for v in x]}
    if isinstance(x, dict):
        return {"__dict__": [[encode(k), encode(v)] for k, v in x.items()]}
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return {"__dataclass__": _type_name(type(x)),
                "fields": {f.name: encode(getattr(x, f.name)) for f in dataclasses.fields(x)}}
    raise TypeError(f"cannot store a {type(x).__name__}")


def _float(v: float) -> Any:
    return v if math.isfinite(v) else {"__float__": repr(v)}  # strict JSON: no NaN/Infinity literals


def decode(data: Any, types: Iterable[type] = ()) -> Any:
    """The value :func:`encode` stored; dataclasses only of ``types`` (anything else, or a field that does not match,
    raises ``ValueError``)."""
    allowed = {_type_name(t): t for t in types}
    return _decode(data, allowed)


def _decode(d: Any, allowed: dict[str, type]) -> Any:
    if d is None or isinstance(d, (bool, int, float, str)):
        return d
    if isinstance(d, list):
        return [_decode(v, allowed) for v in d]
    if not isinstance(d, dict) or frozenset(d) not in _TAGS:
        raise ValueError(f"unexpected stored value {str(d)[:80]!r}")
    if "__float__" in d:
        if d["__float__"] not in ("nan", "inf", "-inf"):
            raise ValueError(f"bad non-finite float {d['__float__']!r}")
        return float(d["__float__"])
    if "__tuple__" in d:
        return tuple(_decode(v, allowed) for v in _list(d["__tuple__"]))
    if "__dict__" in d:
        pairs = (_pair(p) for p in _list(d["__dict__"]))
        return {_hashable(_decode(k, allowed)): _decode(v, allowed) for k, v in pairs}
    if "__ndarray__" in d:
        dtype = np.dtype(str(d["__ndarray__"]))
        if dtype.kind not in _KINDS:
            raise ValueError(f"stored ndarray of dtype {dtype} not allowed")
        shape = tuple(int(n) for n in _list(d["shape"]))
        data = [_decode(v, allowed) for v in _list(d["data"])]
        if math.prod(shape) != len(data):
            raise ValueError(f"stored ndarray of shape {shape} has {len(data)} values")
        return np.array(data, dtype=dtype).reshape(shape)
    if "__dataclass__" in d:
        cls = allowed.get(str(d["__dataclass__"]))
        if cls is None:
            raise ValueError(f"stored type {d['__dataclass__']!r} is not one this reproduction reads")
        fields = d["fields"]
        if not isinstance(fields, dict):
            raise ValueError(f"stored {cls.__name__} has no field mapping")
        names = {f.name for f in dataclasses.fields(cls) if f.init}
        if set(fields) != names:
            raise ValueError(f"stored {cls.__name__} has fields {sorted(fields)}, expected {sorted(names)}")
        return cls(**{k: _decode(v, allowed) for k, v in fields.items()})
    raise ValueError(f"unexpected stored mapping with keys {sorted(d)}")


def _list(v: Any) -> list:
    if not isinstance(v, list):
        raise ValueError(f"expected a list, got {type(v).__name__}")
    return v


def _pair(v: Any) -> tuple[Any, Any]:
    if not isinstance(v, list) or len(v) != 2:
        raise ValueError("expected a [key, value] pair")
    return v[0], v[1]


def _hashable(k: Any) -> Any:
    hash(k)  # TypeError on a list key: caught by the reader as a bad line
    return k


class JobStore:
    """The stored results of one experiment's jobs (module docstring).

    Parameters
    ----------
    directory : Path
        The store's folder (created).
    types : Iterable[type]
        The dataclasses a stored result may contain.
    code : str
        The fingerprint of the code computing the results (:func:`code_fingerprint` of the job function's module):
        stored results of another fingerprint are not used.

    Use as a context manager (the lock is held while open); :meth:`get` a finished job's result, :meth:`put` a new
    one. A job's key is its :func:`encode`-d JSON text, so jobs must be made of the values :func:`encode` takes.
    """

    def __init__(self, directory: Path, types: Iterable[type] = (), code: str = "") -> None:
        self.dir = Path(directory)
        self.types = tuple(types)
        self.dir.mkdir(parents=True, exist_ok=True)
        self._lock = exclusive_lock(self.dir / LOCK_FILE, StoreError, f"{self.dir} is in use by another reproduction")
        self.path = self.dir / RESULTS_FILE
        self.code = code
        self.stale = 0
        self._results = self._read()
        self._file = open(self.path, "a", encoding="utf-8")

    @staticmethod
    def key(job: Any) -> str:
        return json.dumps(encode(job), sort_keys=True, allow_nan=False)

    def __contains__(self, job: Any) -> bool:
        return self.key(job) in self._results

    def __len__(self) -> int:
        return len(self._results)

    def get(self, job: Any) -> Any:
        return self._results[self.key(job)]

    def put(self, job: Any, result: Any) -> None:
        """Store ``result`` of ``job`` (flushed at once)."""
        k = self.key(job)
        line = json.dumps({"code": self.code, "job": json.loads(k), "result": encode(result)}, allow_nan=False)
        self._file.write(line + "\n")
        self._file.flush()
        self._results[k] = result

    def _read(self) -> dict[str, Any]:
        def parse(rec: Any) -> tuple[str, Any]:
            if not isinstance(rec, dict) or set(rec) != {"code", "job", "result"}:
                raise ValueError("not a {code, job, result} record")
            if rec["code"] != self.code:
                self.stale += 1
                raise QuietDrop
            return json.dumps(rec["job"], sort_keys=True, allow_nan=False), decode(rec["result"], self.types)

        out = dict(read_jsonl(self.path, parse, self.dir / REJECTED_FILE, "result", "job"))
        if self.stale:
            _LOG.warning("%s: %d stored results were computed by other code: their jobs run again", self.path,
                         self.stale)
        return out

    def close(self) -> None:
        self._file.close()
        if self._lock is not None:
            self._lock.close()
            self._lock = None

    def __enter__(self) -> JobStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
