"""Clock, seeds and the run record, without physics."""

import json
import os

import numpy as np
import pytest

from simulator.clock import Clock
from simulator.record import RunRecorder
from simulator.runrecord import load_run
from simulator.seeding import RunSeeds


def test_clock_divisors_and_time_without_accumulation():
    clock = Clock(physics_hz=240)
    assert clock.divisor(48) == 5 and clock.divisor(2) == 120 and clock.divisor(0.5) == 480
    with pytest.raises(ValueError, match="7 Hz does not divide physics_hz = 240"):
        clock.divisor(7, "rate_hz")
    # 1e6 ticks: time is exact, not a sum of floats
    assert clock.time(240 * 100_000) == 100_000.0
    with pytest.raises(ValueError):
        Clock(physics_hz=0)


def test_named_streams_are_reproducible_and_independent():
    a = RunSeeds(7)
    x = a.generator("sensor/u1/0").standard_normal(5)
    y = a.generator("sensor/u2/0").standard_normal(5)
    b = RunSeeds(7)
    b.generator("something/else")  # an extra component does not shift the others
    assert np.array_equal(b.generator("sensor/u1/0").standard_normal(5), x)
    assert not np.array_equal(x, y)
    assert not np.array_equal(RunSeeds(8).generator("sensor/u1/0").standard_normal(5), x)
    with pytest.raises(ValueError, match="twice"):
        a.generator("sensor/u1/0")


def test_record_roundtrip_partial_and_truncated(tmp_path):
    rec = RunRecorder(tmp_path)
    rec.append_rows("truth", {"tick": [1, 2], "t": [0.1, 0.2], "x": np.array([1.0, 2.0])})
    rec.flush({"sim_time_s": 0.2})
    rec.append("truth", tick=3, t=0.3, x=3.0)  # buffered, never flushed: lost, as a killed process would lose it
    rec.event("collision", 3, 0.3, uav=0)
    # simulate a process killed mid-write: a torn last line in events.jsonl and a stray temporary chunk
    with open(tmp_path / "events.jsonl", "a") as f:
        f.write('{"type": "torn')
    (tmp_path / "timeseries" / "truth" / ".part-00001.tmp.npy").write_bytes(b"garbage")
    loaded = load_run(tmp_path)
    assert loaded.status == "unknown"
    assert [e["type"] for e in loaded.events] == ["collision"]
    assert loaded.stream("truth")["tick"].tolist() == [1, 2]
    assert loaded.metrics == {"sim_time_s": 0.2}
    with pytest.raises(KeyError, match="no stream"):
        loaded.stream("nope")


def test_record_chunks_keep_dtypes_shapes_and_order(tmp_path):
    rec = RunRecorder(tmp_path)
    for k in range(12):  # more than one chunk, road names of growing width, a (2, 2) column
        rec.append_rows("s", {"tick": [k], "road": ["r" * (k + 1)], "P": np.full((1, 2, 2), float(k))})
        rec.flush()
    s = load_run(tmp_path).stream("s")
    assert s["tick"].tolist() == list(range(12)) and s["tick"].dtype.kind == "i"
    assert s["road"].tolist() == ["r" * (k + 1) for k in range(12)]
    assert s["P"].shape == (12, 2, 2) and s["P"][11].tolist() == [[11.0, 11.0], [11.0, 11.0]]


def test_record_of_the_older_npz_layout_loads(tmp_path):
    # records written before the chunks became one structured array: one .npz member per column
    folder = tmp_path / "timeseries" / "truth"
    folder.mkdir(parents=True)
    np.savez(folder / "part-00000.npz", tick=np.array([1, 2]), x=np.array([1.0, 2.0]))
    np.savez(folder / "part-00001.npz", tick=np.array([3]), x=np.array([3.0]))
    s = load_run(tmp_path).stream("truth")
    assert s["tick"].tolist() == [1, 2, 3] and s["x"].tolist() == [1.0, 2.0, 3.0]


def test_record_rejects_inconsistent_columns(tmp_path):
    rec = RunRecorder(tmp_path)
    rec.append("s", a=1, b=2)
    with pytest.raises(KeyError):
        rec.append("s", a=1)
    with pytest.raises(ValueError):
        rec.append_rows("s", {"a": [1, 2], "b": [1]})


def test_metrics_file_is_always_complete_json(tmp_path):
    rec = RunRecorder(tmp_path)
    for k in range(5):
        rec.flush({"k": k})
        assert json.loads((tmp_path / "metrics.json").read_text()) == {"k": k}
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".tmp")]


def test_partial_metrics_are_written_whole_without_a_sync_and_final_ones_synced(tmp_path, monkeypatch):
    import simulator.record as record

    synced = []
    monkeypatch.setattr(record.os, "fsync", lambda fd: synced.append(fd))
    rec = RunRecorder(tmp_path)
    rec.flush({"k": 0}, sync=False)
    assert json.loads((tmp_path / "metrics.json").read_text()) == {"k": 0} and synced == []
    rec.flush({"k": 1})
    assert json.loads((tmp_path / "metrics.json").read_text()) == {"k": 1} and len(synced) == 1
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".tmp")]
