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
    assert len(list((root / "maps").glob("t_*.pkl"))) == 1


def test_another_key_or_kind_builds_anew(root):
    build, calls = _counting(1)
    map_cache.cached("t", [b"a"], build)
    map_cache.cached("t", [b"b"], build)
    map_cache.cached("u", [b"a"], build)
    assert len(calls) == 3


def test_a_damaged_entry_is_rebuilt_and_replaced(root):
    build, calls = _counting([1, 2, 3])
    map_cache.cached("t", [b"k"], build)
    (entry,) = (root / "maps").glob("t_*.pkl")
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
    assert not list(root.rglob("*.pkl"))


def test_the_helsinki_world_loads_the_same_geometry_from_the_cache(root):
    loaded = load_world("helsinki_chase")
    fresh = build_geometry(loaded.world, loaded.path, np.random.default_rng(0))
    assert len(list((root / "maps").glob("osm_*.pkl"))) == 1
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
    for f in (root / "maps").glob("t_*.pkl"):  # all used long ago (coarse file-system clocks cannot order them)
        os.utime(f, (1.0, 1.0))
    assert map_cache.cached("t", ["k0"], lambda: -1) == 0  # a hit: k0 is the most recently used now
    map_cache.cached("t", ["k3"], lambda: 3)  # a fourth entry: one of the unused k1, k2 goes
    map_cache.cached("u", ["other kind"], lambda: 0)  # other kinds are counted apart
    assert len(list((root / "maps").glob("t_*.pkl"))) == 3
    assert map_cache.cached("t", ["k0"], lambda: -1) == 0  # kept, not rebuilt
    assert map_cache.cached("t", ["k3"], lambda: -1) == 3
    assert len(list((root / "maps").glob("u_*.pkl"))) == 1
