"""The on-disk cache of imported maps: hits, misses on changed inputs, damaged entries, an unwritable cache."""

from __future__ import annotations

import numpy as np
import pytest

from worlds import map_cache
from worlds.build import build_geometry
from worlds.loader import load_world


@pytest.fixture
def root(tmp_path, monkeypatch):
    monkeypatch.setenv("SKYTRACK_CACHE_DIR", str(tmp_path))
    return tmp_path


def _counting(value):
    calls = []

    def build():
        calls.append(1)
        return value

    return build, calls


def test_a_second_call_with_the_same_key_loads_the_entry(root):
    build, calls = _counting({"xy": np.arange(5.0)})
    first = map_cache.cached("t", [b"map bytes", "params"], build)
    again = map_cache.cached("t", [b"map bytes", "params"], build)
    assert len(calls) == 1
    np.testing.assert_array_equal(again["xy"], first["xy"])
    assert again is not first  # loaded from disk, not the object of the first call
    assert len(list((root / "maps").glob("t_*.npz"))) == 1


def test_another_key_or_kind_builds_anew(root):
    build, calls = _counting(1)
    map_cache.cached("t", [b"a"], build)
    map_cache.cached("t", [b"b"], build)
    map_cache.cached("u", [b"a"], build)
    assert len(calls) == 3


def test_a_damaged_entry_is_rebuilt_and_replaced(root):
    build, calls = _counting([1, 2, 3])
    map_cache.cached("t", [b"k"], build)
    (entry,) = (root / "maps").glob("t_*.npz")
    entry.write_bytes(b"not a pickle")
    assert map_cache.cached("t", [b"k"], build) == [1, 2, 3]
    assert map_cache.cached("t", [b"k"], build) == [1, 2, 3]
    assert len(calls) == 2  # rebuilt once, then read again


def test_an_unwritable_cache_still_returns_the_value(tmp_path, monkeypatch, caplog):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache directory would be")
    monkeypatch.setenv("SKYTRACK_CACHE_DIR", str(blocker))
    build, calls = _counting("v")
    assert map_cache.cached("t", [b"k"], build) == "v"
    assert map_cache.cached("t", [b"k"], build) == "v"
    assert len(calls) == 2


def test_a_failing_build_stores_nothing(root):
    def build():
        raise ValueError("bad map")

    with pytest.raises(ValueError, match="bad map"):
        map_cache.cached("t", [b"k"], build)
    assert not list(root.rglob("*.npz"))


def test_the_helsinki_world_loads_the_same_geometry_from_the_cache(root):
    loaded = load_world("helsinki_chase")
    fresh = build_geometry(loaded.world, loaded.path, np.random.default_rng(0))
    assert len(list((root / "maps").glob("osm_*.npz"))) == 1
    again = build_geometry(loaded.world, loaded.path, np.random.default_rng(0))
    assert list(again.network.roads) == list(fresh.network.roads)
    rid = next(iter(fresh.network.roads))
    np.testing.assert_array_equal(again.network.roads[rid].point(np.array([0.0, 5.0])),
                                  fresh.network.roads[rid].point(np.array([0.0, 5.0])))
    assert [b.top_z for b in again.buildings] == [b.top_z for b in fresh.buildings]
    np.testing.assert_array_equal(again.road_mesh.vertices, fresh.road_mesh.vertices)


def test_only_the_most_recently_used_entries_of_a_kind_are_kept(root, monkeypatch):
    import os

    monkeypatch.setattr(map_cache, "KEEP_PER_KIND", 3)
    for k in range(3):
        map_cache.cached("t", [f"k{k}"], lambda k=k: k)
    for f in (root / "maps").glob("t_*.npz"):  # all used long ago (coarse file-system clocks cannot order them)
        os.utime(f, (1.0, 1.0))
    assert map_cache.cached("t", ["k0"], lambda: -1) == 0  # a hit: k0 is the most recently used now
    map_cache.cached("t", ["k3"], lambda: 3)  # a fourth entry: one of the unused k1, k2 goes
    map_cache.cached("u", ["other kind"], lambda: 0)  # other kinds are counted apart
    assert len(list((root / "maps").glob("t_*.npz"))) == 3
    assert map_cache.cached("t", ["k0"], lambda: -1) == 0  # kept, not rebuilt
    assert map_cache.cached("t", ["k3"], lambda: -1) == 3
    assert len(list((root / "maps").glob("u_*.npz"))) == 1


class _MakesMarker:
    """A pickle whose loading creates a file: what a crafted cache entry could do instead."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


@pytest.mark.parametrize("where", ["entry", "legacy-pkl"])
def test_a_crafted_pickle_in_the_cache_is_never_executed(root, caplog, where):
    import pickle

    build, calls = _counting({"xy": np.arange(3.0)})
    map_cache.cached("t", [b"k"], build)
    (entry,) = (root / "maps").glob("t_*.npz")
    marker = root / "pwned"
    crafted = pickle.dumps(_MakesMarker(marker))
    if where == "entry":  # written in the entry's place
        entry.write_bytes(crafted)
    else:  # an entry of the earlier pickled format with the same stem
        entry.unlink()
        entry.with_suffix(".pkl").write_bytes(crafted)
    with caplog.at_level("WARNING", logger="worlds.map_cache"):
        value = map_cache.cached("t", [b"k"], build)
    np.testing.assert_array_equal(value["xy"], np.arange(3.0))
    assert not marker.exists()
    assert len(calls) == 2  # rebuilt
    assert not list((root / "maps").glob("*.pkl"))  # the legacy file is deleted, unread
    if where == "entry":
        says = f"map cache entry {entry} unusable (EntryError: not an .npz archive (it starts with b'\\x80\\x04"
        assert says in caplog.text


def test_an_entry_holding_another_keys_value_is_rebuilt(root, caplog):
    map_cache.cached("t", [b"a"], lambda: "value of a")
    (entry_a,) = (root / "maps").glob("t_*.npz")
    map_cache.cached("t", [b"b"], lambda: "value of b")
    (entry_b,) = set((root / "maps").glob("t_*.npz")) - {entry_a}  # the file b's call added (names are digests)
    by_value = {map_cache.cached("t", [k], lambda: None): k for k in (b"a", b"b")}
    assert set(by_value) == {"value of a", "value of b"}
    entry_b.write_bytes(entry_a.read_bytes())  # b's file now holds a's entry (a copy gone wrong)
    build, calls = _counting("value of b")
    with caplog.at_level("WARNING", logger="worlds.map_cache"):
        assert map_cache.cached("t", [b"b"], build) == "value of b"
    assert calls == [1]
    assert f"map cache entry {entry_b} unusable (EntryError: its key is" in caplog.text
    assert map_cache.cached("t", [b"b"], build) == "value of b" and calls == [1]  # replaced by the right entry


def test_a_truncated_entry_is_rebuilt(root, caplog):
    build, calls = _counting({"xy": np.arange(1000.0), "name": "n"})
    map_cache.cached("t", [b"k"], build)
    (entry,) = (root / "maps").glob("t_*.npz")
    with entry.open("r+b") as f:
        f.truncate(entry.stat().st_size // 2)
    with caplog.at_level("WARNING", logger="worlds.map_cache"):
        value = map_cache.cached("t", [b"k"], build)
    np.testing.assert_array_equal(value["xy"], np.arange(1000.0))
    assert len(calls) == 2
    assert f"map cache entry {entry} unusable (" in caplog.text and "rebuilding it" in caplog.text
    assert map_cache.cached("t", [b"k"], build)["name"] == "n" and len(calls) == 2


def test_an_entry_of_another_format_or_naming_a_foreign_class_is_rebuilt(root, caplog):
    import json

    build, calls = _counting(("a", 1.5))
    assert map_cache.cached("t", [b"k"], build) == ("a", 1.5)
    (entry,) = (root / "maps").glob("t_*.npz")
    with np.load(entry, allow_pickle=False) as npz:
        members = {k: npz[k] for k in npz.files}
    header = json.loads(members["__header__"].tobytes())
    for change, says in ((dict(header, format="skytrack-map-1"), "EntryError: its format is 'skytrack-map-1'"),
                         (dict(header, tree={"t": "obj", "cls": "Popen", "v": {}}),
                          "EntryError: class 'Popen' is not allowed")):
        members["__header__"] = np.frombuffer(json.dumps(change).encode(), dtype=np.uint8)
        with entry.open("wb") as f:
            np.savez(f, **members)
        caplog.clear()
        with caplog.at_level("WARNING", logger="worlds.map_cache"):
            assert map_cache.cached("t", [b"k"], build) == ("a", 1.5)
        assert says in caplog.text
    assert len(calls) == 3


def test_a_value_the_cache_cannot_store_is_returned_uncached(root, caplog):
    build, calls = _counting({"f": object()})
    with caplog.at_level("WARNING", logger="worlds.map_cache"):
        map_cache.cached("t", [b"k"], build)
        map_cache.cached("t", [b"k"], build)
    assert len(calls) == 2 and not list((root / "maps").glob("*.npz"))
    assert "values of type builtins.object cannot be stored" in caplog.text
