"""Map-cache entries as data that cannot run code: a JSON tree plus numpy arrays, in one ``.npz`` file.

The map cache (:mod:`worlds.map_cache`) used to pickle its values; unpickling runs whatever the file says, so a cache
entry written by anyone else (a shared or copied cache directory) could run code in every later run. This codec
writes a value as

* ``__header__``: UTF-8 JSON (stored as a ``uint8`` array) with the entry's format, kind and key digest and the value's
  tree: JSON scalars as themselves, everything else as a tagged object (``{"t": "tuple", ...}``);
* one flat array per dtype (``f8``, ``i8``, ...) that every numpy array of the value is a slice of (a city's 1400
  roads have ≈ 8000 arrays; packed, loading takes milliseconds instead of reading 8000 zip members).

and reads it with ``numpy.load(..., allow_pickle=False)``: object arrays and pickles are refused. Objects are rebuilt
only for the classes in :data:`_CLASSES`, by setting their stored attributes without calling their constructors
(a Road's constructor recomputes its arc-length table, which is what the cache saves; ≈ 0.8 s for Helsinki).
A tree naming any other class, or an allowed class with other attributes than the running code's (a stale layout),
raises :class:`EntryError`. Shared references are not preserved (the cached values are immutable trees).
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import math
from typing import IO, Any

import numpy as np

__all__ = ["EntryError", "decode", "encode"]

HEADER = "__header__"
_ZIP_MAGIC = b"PK\x03\x04"
_CLASSES = {  # tag -> (module, class name): the only classes an entry may hold besides kd-trees and meshes
    "Town": ("worlds.town", "Town"),
    "RoadNetwork": ("worlds.roads.network", "RoadNetwork"),
    "Road": ("worlds.roads.road", "Road"),
    "Building": ("worlds.geometry", "Building"),
}
_FLOAT_LIST_MIN = 8  # lists of at least this many floats go to the f8 array (a Road's plain-float tables)


class EntryError(ValueError):
    """An entry that is not a valid map-cache entry (damaged, another format, or a class not allowed)."""


def _allowed(tag: str) -> type:
    try:
        module, name = _CLASSES[tag]
    except (KeyError, TypeError):
        raise EntryError(f"class {tag!r} is not allowed in a map-cache entry") from None
    return getattr(importlib.import_module(module), name)


class _Packer:
    """Collects arrays into one flat buffer per dtype while the tree is encoded."""

    def __init__(self) -> None:
        self.parts: dict[str, list[np.ndarray]] = {}
        self.sizes: dict[str, int] = {}

    def add(self, a: np.ndarray) -> dict:
        if a.dtype.hasobject or a.dtype.fields is not None or a.dtype.kind not in "biufc":
            raise TypeError(f"map cache: arrays of dtype {a.dtype} cannot be stored")
        dt = a.dtype.str
        off = self.sizes.get(dt, 0)
        self.parts.setdefault(dt, []).append(np.ascontiguousarray(a).reshape(-1))
        self.sizes[dt] = off + a.size
        return {"t": "nd", "dtype": dt, "off": off, "shape": list(a.shape), "ro": not a.flags.writeable}

    def arrays(self) -> dict[str, np.ndarray]:
        names = {dt: f"a{k}" for k, dt in enumerate(sorted(self.parts))}
        return {names[dt]: np.concatenate(p) for dt, p in self.parts.items()} | {
            "__dtypes__": np.frombuffer(json.dumps(names).encode(), dtype=np.uint8)}


def _enc(v: Any, pk: _Packer) -> Any:
    if v is None or isinstance(v, (bool, str, int)) and not isinstance(v, np.generic):
        return v
    if isinstance(v, float) and not isinstance(v, np.generic):
        return v if math.isfinite(v) else {"t": "float", "v": repr(v)}
    if isinstance(v, np.ndarray):
        return pk.add(v)
    if isinstance(v, np.generic):
        return {"t": "scalar", "v": pk.add(np.asarray(v))}
    if isinstance(v, (list, tuple)):
        if len(v) >= _FLOAT_LIST_MIN and all(type(x) is float for x in v):
            return {"t": "floats", "tuple": isinstance(v, tuple), "v": pk.add(np.array(v, dtype=np.float64))}
        return {"t": "tuple" if isinstance(v, tuple) else "list", "v": [_enc(x, pk) for x in v]}
    if isinstance(v, dict):
        if not all(isinstance(k, str) for k in v):
            raise TypeError("map cache: dict keys must be strings")
        return {"t": "dict", "v": {k: _enc(x, pk) for k, x in v.items()}}
    name = type(v).__name__
    if name == "cKDTree" and type(v).__module__.startswith("scipy.spatial"):
        return {"t": "kdtree", "data": pk.add(np.asarray(v.data)), "leafsize": int(v.leafsize)}
    if name == "Trimesh" and type(v).__module__.startswith("trimesh"):
        return {"t": "trimesh", "vertices": pk.add(np.asarray(v.vertices)), "faces": pk.add(np.asarray(v.faces))}
    if name in _CLASSES and type(v) is _allowed(name):
        return {"t": "obj", "cls": name, "v": {k: _enc(x, pk) for k, x in vars(v).items()}}
    raise TypeError(f"map cache: values of type {type(v).__module__}.{type(v).__qualname__} cannot be stored")


def encode(value: Any, header: dict[str, Any], f: IO[bytes]) -> None:
    """Write ``value`` with ``header`` (JSON data: format, kind, key) to the binary file ``f`` as an ``.npz``.

    Raises ``TypeError`` for a value holding anything but JSON scalars, lists, tuples, str-keyed dicts, numeric numpy
    arrays and scalars, kd-trees, trimesh meshes and the classes of :data:`_CLASSES`."""
    pk = _Packer()
    tree = _enc(value, pk)
    text = json.dumps(dict(header, tree=tree), separators=(",", ":"))
    np.savez(f, **{HEADER: np.frombuffer(text.encode(), dtype=np.uint8)}, **pk.arrays())


def decode(f: IO[bytes], expect: dict[str, Any]) -> Any:
    """The value stored in the ``.npz`` binary file ``f``, after checking that its header has every item of ``expect``.

    Raises :class:`EntryError` (or the ``OSError`` / ``ValueError`` of a damaged zip) instead of returning a value
    that is not the one asked for. Anything but a zip archive (a pickle, a bare ``.npy``) is refused before a loader
    sees it."""
    magic = f.read(len(_ZIP_MAGIC))
    if magic != _ZIP_MAGIC:
        raise EntryError(f"not an .npz archive (it starts with {magic!r})")
    f.seek(0)
    with np.load(f, allow_pickle=False) as npz:
        if not isinstance(npz, np.lib.npyio.NpzFile) or HEADER not in npz.files:
            raise EntryError("not a map-cache entry (no header)")
        header = json.loads(npz[HEADER].tobytes().decode())
        for k, want in expect.items():
            if header.get(k) != want:
                raise EntryError(f"its {k} is {str(header.get(k))[:40]!r}, expected {str(want)[:40]!r}")
        names = json.loads(npz["__dtypes__"].tobytes().decode())
        flat = {dt: npz[name] for dt, name in names.items()}
    return _Decoder(flat).dec(header["tree"])


class _Decoder:
    def __init__(self, flat: dict[str, np.ndarray]) -> None:
        self.flat = flat

    def nd(self, d: dict) -> np.ndarray:
        buf = self.flat.get(d["dtype"])
        shape = tuple(int(n) for n in d["shape"])
        off, size = int(d["off"]), math.prod(shape)
        if buf is None or buf.dtype.str != d["dtype"] or off < 0 or off + size > buf.size:
            raise EntryError(f"array reference {d['dtype']}[{off}:{off + size}] outside the stored arrays")
        a = buf[off:off + size].reshape(shape)
        if d.get("ro"):
            a.setflags(write=False)
        return a

    def dec(self, v: Any) -> Any:
        if not isinstance(v, dict):
            if isinstance(v, list):
                raise EntryError("untagged list in an entry")
            return v
        t = v.get("t")
        if t == "nd":
            return self.nd(v)
        if t == "float":
            return float(v["v"])
        if t == "scalar":
            return self.nd(v["v"])[()]
        if t == "floats":
            out = self.nd(v["v"]).tolist()
            return tuple(out) if v["tuple"] else out
        if t in ("list", "tuple"):
            items = [self.dec(x) for x in v["v"]]
            return tuple(items) if t == "tuple" else items
        if t == "dict":
            return {str(k): self.dec(x) for k, x in v["v"].items()}
        if t == "kdtree":
            from scipy.spatial import cKDTree

            return cKDTree(self.nd(v["data"]), leafsize=int(v["leafsize"]))
        if t == "trimesh":
            import trimesh

            return trimesh.Trimesh(vertices=self.nd(v["vertices"]), faces=self.nd(v["faces"]), process=False)
        if t == "obj":
            return self.obj(v)
        raise EntryError(f"unknown tag {str(t)[:40]!r} in an entry")

    def obj(self, v: dict) -> Any:
        cls = _allowed(v.get("cls"))
        state = v["v"]
        if dataclasses.is_dataclass(cls):
            want = {f.name for f in dataclasses.fields(cls)}
            if set(state) != want:
                raise EntryError(f"a {cls.__name__} with attributes {sorted(set(state) ^ want)} that differ from "
                                 "the running code's")
        obj = object.__new__(cls)
        for k, x in state.items():
            object.__setattr__(obj, str(k), self.dec(x))
        return obj
