"""``skytrack export``: a short demo run written for Rerun and for Foxglove (MCAP), read back with each format's own
reader and checked against the run's record (entity paths / channels, schemas, row and message counts, times)."""

from __future__ import annotations

import json
from collections import Counter

import numpy as np
import pytest

from simulator.api import run
from simulator.cli import main
from simulator.export.scene import covariance_ellipse

rerun_chunk = pytest.importorskip("rerun.chunk")
mcap_reader = pytest.importorskip("mcap.reader")


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory):
    """Two seconds of the demo world (tracks, detections, fused estimates) under a Rayleigh radio (links)."""
    return run("demo", duration=2.0, seed=5, overrides=["comms.model=rayleigh"],
               out_dir=tmp_path_factory.mktemp("export_run"))


def _per(stream: dict[str, np.ndarray], key: str) -> dict[int, int]:
    return {int(k): int(n) for k, n in zip(*np.unique(stream[key], return_counts=True), strict=True)}


def _expected(rec) -> dict[str, int]:
    """Rows per temporal entity path, from the run's own record."""
    uav_ids = {0: "uav1", 1: "uav2"}
    car_ids = {0: "car1", 1: "van1", 2: "car2", 3: "car3"}
    s = rec.streams
    out = {f"/world/uavs/{uav_ids[u]}": n for u, n in _per(s["uav_truth"], "uav").items()}
    out.update({f"/world/vehicles/{car_ids[v]}": n for v, n in _per(s["vehicle_truth"], "vehicle").items()})
    det = s["detections"]
    for sensor in np.unique(det["sensor"]):
        out[f"/world/detections/{sensor}"] = np.unique(det["t_meas"][det["sensor"] == sensor]).size
    tr = s["tracks"]
    for u in np.unique(tr["uav"]):
        out[f"/world/tracks/{uav_ids[int(u)]}"] = np.unique(tr["tick"][tr["uav"] == u]).size
    for layer in ("estimates", "fused_estimates"):
        out.update({f"/world/{layer}/{uav_ids[u]}": n for u, n in _per(s[layer], "uav").items()})
    out["/world/links"] = _per(s["uav_truth"], "uav")[0]
    return out


def test_rerun_export_has_the_runs_entities_rows_and_clock(demo_run, tmp_path, capsys):
    out = tmp_path / "demo.rrd"
    assert main(["export", str(demo_run.out_dir), "--format", "rerun", "--out", str(out)]) == 0
    assert capsys.readouterr().out == f"rerun: {out}\n"
    rows, static, timelines, uav_times, labels = Counter(), set(), set(), [], {}
    for c in rerun_chunk.RrdReader(out).stream().to_chunks():
        if c.is_static:
            static.add(c.entity_path)
            batch = c.to_record_batch()
            for n in (n for n in batch.schema.names if n.endswith(":labels")):
                labels[c.entity_path] = batch.column(n).to_pylist()[0]
            continue
        rows[c.entity_path] += c.num_rows
        timelines.update(c.timeline_names)
        if c.entity_path == "/world/uavs/uav1":
            uav_times.append(np.asarray(c.to_record_batch().column("sim_time").cast("int64")))
    expected = _expected(demo_run.record)
    assert {k: rows[k] for k in expected} == expected
    assert all(n > 0 for n in expected.values())
    ut = demo_run.record.streams["uav_truth"]
    t_uav1 = ut["t"][ut["uav"] == 0]
    assert np.array_equal(np.sort(np.concatenate(uav_times)), np.round(t_uav1 * 1e9).astype(np.int64))
    assert rows["/series/uav1/uav_truth/z"] == t_uav1.size
    assert rows["/series/links/uav1-uav2/delivery_probability"] == t_uav1.size
    assert rows["/series/uav1/target_track/p_target"] == expected["/world/tracks/uav1"]
    assert "/series/uav1/commands/vx" not in rows  # a unicycle UAV never sets it: no empty series
    with np.load(demo_run.out_dir / "geometry.npz") as g:
        assert labels["/world/roads"] == [str(r) for r in g["road_ids"]]
        assert labels["/world/buildings"] == [f"building{k}" for k in range(len(g["building_height"]))]
    assert {"/world", "/world/uavs/uav1/body", "/world/vehicles/car1/body"} <= static
    assert "sim_time" in timelines


def _mcap_summary(path):
    with open(path, "rb") as f:
        summary = mcap_reader.make_reader(f).get_summary()
    return {c.topic: (summary.schemas[c.schema_id].name, summary.schemas[c.schema_id].encoding, c.message_encoding,
                      summary.statistics.channel_message_counts[c.id]) for c in summary.channels.values()}


def test_mcap_export_has_foxglove_channels_and_the_records_counts(demo_run, tmp_path, capsys):
    out = tmp_path / "demo.mcap"
    assert main(["export", str(demo_run.out_dir), "--out", str(out)]) == 0  # format from the suffix
    assert capsys.readouterr().out == f"mcap: {out}\n"
    got = _mcap_summary(out)
    s = demo_run.record.streams
    n_uav, n_car = len(s["uav_truth"]["t"]), len(s["vehicle_truth"]["t"])
    scene = ("foxglove.SceneUpdate", "jsonschema", "json")
    expected = {"/scene/static": (*scene, 1), "/scene/bodies": (*scene, 1),
                "/tf": ("foxglove.FrameTransform", "jsonschema", "json", n_uav + n_car)}
    for name, layer in _expected(demo_run.record).items():
        topic = "/scene/" + name.split("/")[2]
        if topic in ("/scene/uavs", "/scene/vehicles"):
            continue
        expected[topic] = (*scene, expected.get(topic, (0, 0, 0, 0))[3] + layer)
    assert {k: got[k] for k in expected} == expected
    per_uav = len(s["uav_truth"]["t"]) // 2
    assert got["/series/uav1/uav_truth"] == ("skytrack.Series", "jsonschema", "json", per_uav)
    assert got["/series/links/uav1-uav2"] == ("skytrack.Series", "jsonschema", "json", per_uav)


def test_mcap_messages_are_on_the_sim_clock_with_the_records_values(demo_run, tmp_path):
    out = tmp_path / "demo.mcap"
    assert main(["export", str(demo_run.out_dir), "--format", "mcap", "--out", str(out)]) == 0
    series, static, tf_children = [], None, Counter()
    with open(out, "rb") as f:
        for _schema, channel, message in mcap_reader.make_reader(f).iter_messages():
            body = json.loads(message.data)
            if channel.topic == "/series/uav2/uav_truth":
                series.append((message.log_time, body))
            elif channel.topic == "/scene/static":
                static = body
            elif channel.topic == "/tf":
                tf_children[body["child_frame_id"]] += 1
    ut = demo_run.record.streams["uav_truth"]
    m = ut["uav"] == 1
    assert [ns for ns, _ in series] == np.round(ut["t"][m] * 1e9).astype(np.int64).tolist()
    assert np.allclose([b["z"] for _, b in series], ut["z"][m])
    assert np.allclose([b["t"] for _, b in series], ut["t"][m])
    ids = [e["id"] for e in static["entities"]]
    with np.load(demo_run.out_dir / "geometry.npz") as g:
        assert ids == ["buildings"] + [f"road/{r}" for r in g["road_ids"]]
        assert len(static["entities"][0]["cubes"]) == len(g["building_height"])
    per_car = _per(demo_run.record.streams["vehicle_truth"], "vehicle")
    assert tf_children == {"uav1": int(m.sum()), "uav2": int((ut["uav"] == 0).sum()), "car1": per_car[0],
                           "van1": per_car[1], "car2": per_car[2], "car3": per_car[3]}


def test_export_refuses_what_is_not_a_run_directory(tmp_path, capsys):
    assert main(["export", str(tmp_path), "--format", "mcap"]) == 2
    assert capsys.readouterr().err == (f"skytrack export: {tmp_path} is not a run directory (no run.json or "
                                       "timeseries/)\n")


def test_export_refuses_an_out_suffix_of_the_other_format(tmp_path, capsys):
    (tmp_path / "run.json").write_text("{}")
    assert main(["export", str(tmp_path), "--format", "rerun", "--out", str(tmp_path / "x.mcap")]) == 2
    assert capsys.readouterr().err == (f"skytrack export: --out {tmp_path / 'x.mcap'} is a mcap file name but "
                                       "--format is rerun\n")


def test_covariance_ellipse_spans_two_sigma_along_the_principal_axes():
    e = covariance_ellipse(np.array([1.0, 2.0]), np.diag([4.0, 1.0]))
    assert e.shape == (32, 2)
    assert np.isclose(e[:, 0].max(), 1.0 + 2 * 2.0) and np.isclose(e[:, 0].min(), 1.0 - 2 * 2.0)
    assert np.isclose(e[:, 1].max(), 2.0 + 2 * 1.0, atol=0.02) and np.isclose(e[:, 1].min(), 2.0 - 2.0, atol=0.02)
    P = np.array([[2.0, 1.0], [1.0, 2.0]])  # eigenvalues 3 (along (1, 1)) and 1
    r = np.linalg.norm(covariance_ellipse(np.zeros(2), P), axis=1)
    assert np.isclose(r.max(), 2 * np.sqrt(3.0)) and np.isclose(r.min(), 2.0, atol=0.02)


def _conforms(value, schema, where="") -> list[str]:
    """What in ``value`` breaks the JSON schema ``schema`` (the subset the export's schemas use)."""
    if "oneOf" in schema:
        return [] if value in [o["const"] for o in schema["oneOf"]] else [f"{where}: {value!r} not one of"]
    kinds = schema.get("type")
    kinds = kinds if isinstance(kinds, list) else [kinds]
    ok = {"object": isinstance(value, dict), "array": isinstance(value, list), "string": isinstance(value, str),
          "boolean": isinstance(value, bool), "null": value is None,
          "integer": isinstance(value, int) and not isinstance(value, bool),
          "number": isinstance(value, int | float) and not isinstance(value, bool)}
    if not any(ok[k] for k in kinds):
        return [f"{where}: {value!r} is not {kinds}"]
    if isinstance(value, dict):
        props = schema["properties"]
        bad = [f"{where}.{k}: unknown field" for k in value if k not in props]
        bad += [f"{where}.{k}: missing" for k in schema.get("required", ()) if k not in value]
        return bad + [e for k, v in value.items() if k in props for e in _conforms(v, props[k], f"{where}.{k}")]
    if isinstance(value, list):
        return [e for i, v in enumerate(value) for e in _conforms(v, schema["items"], f"{where}[{i}]")]
    return []


def test_mcap_messages_conform_to_their_channels_schemas(demo_run, tmp_path):
    out = tmp_path / "demo.mcap"
    assert main(["export", str(demo_run.out_dir), "--format", "mcap", "--out", str(out)]) == 0
    seen, problems = Counter(), []
    with open(out, "rb") as f:
        for schema, channel, message in mcap_reader.make_reader(f).iter_messages():
            seen[schema.name] += 1
            problems += _conforms(json.loads(message.data), json.loads(schema.data), channel.topic)
    assert problems == []
    assert set(seen) == {"foxglove.SceneUpdate", "foxglove.FrameTransform", "skytrack.Series"}
