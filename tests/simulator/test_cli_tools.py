"""``skytrack --version``, ``validate``, ``inspect`` and ``worlds``: exit codes and what they print."""

from __future__ import annotations

import json
from importlib.metadata import version

import pytest
import yaml

from simulator.cli import main
from worlds.loader import shipped_worlds


def test_version_is_the_package_metadatas(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out == f"skytrack {version('skytrack')}\n"


def test_validate_prints_one_ok_line(capsys):
    assert main(["validate", "demo"]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1
    assert out.startswith("OK demo: 2 UAVs, ground vehicles: 1 target, 3 traffic, 8 roads, 5 buildings, 60 s at "
                          "240 Hz (")
    assert out.rstrip().endswith("worlds/demo.yaml)")


def test_validate_applies_overrides(capsys):
    assert main(["validate", "demo", "--set", "sim.duration_s=12", "--set", "uavs[1]=null"]) == 2  # a null UAV
    assert "uavs[1]" in capsys.readouterr().err
    assert main(["validate", "demo", "--set", "sim.duration_s=12"]) == 0
    assert ", 12 s at 240 Hz (" in capsys.readouterr().out


def test_validate_reports_the_world_error_with_exit_2(capsys):
    assert main(["validate", "demo", "--set", "uavs[0].sensors[0].rate_hz=7"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("skytrack validate: invalid world ")
    assert "uavs[0].sensors[0].rate_hz = 7.0: expected a rate in Hz that divides sim.physics_hz=240" in captured.err


def test_validate_builds_the_map_so_a_route_on_no_road_fails(capsys):
    # the loader cannot see an OpenStreetMap network's road ids: only building the map finds this one
    assert main(["validate", "helsinki_drive", "--set", "ground_vehicles[0].route.random_walk_from=nowhere"]) == 2
    err = capsys.readouterr().err
    assert "ground_vehicles[0].route.random_walk_from = 'nowhere': expected a road id of the network" in err


def test_validate_names_a_missing_file(tmp_path, capsys):
    assert main(["validate", str(tmp_path / "nope.yaml")]) == 2
    assert "an existing world file or a shipped world name" in capsys.readouterr().err


def test_inspect_prints_roads_junctions_buildings_and_the_target_route(capsys):
    assert main(["inspect", "demo"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "world: demo"
    assert "extent: x 0 .. 335 m, y -57.5 .. 260 m (roads and buildings)" in lines
    assert "roads: 8" in lines
    assert "  south.f      300.0      12.00     43      1  a -> b" in lines
    assert "  west.r       200.0      12.00     43      1  a -> d" in lines
    assert "junctions: 4" in lines
    assert "  c  (300, 200)  out: east.r, north.f" in lines
    assert "buildings: 5 (heights 15 .. 35 m)" in lines
    assert "ground vehicles: 1 target, 3 traffic" in lines
    assert lines[-1] == "target route (car1): random walk from south.f (start_s 0 m, lane 0)"


def test_inspect_json_lists_every_road_of_a_town(capsys):
    assert main(["inspect", "road_standoff", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["name"] == "road_standoff"
    assert len(s["roads"]) == 168 and len(s["junctions"]) == 49
    assert {r["speed_limit_mps"] for r in s["roads"]} == {13.9, 16.7}
    assert s["roads"][0] == {"id": "h0_0.f", "length_m": 103.5, "speed_limit_mps": 16.7, "lanes": 2, "from": "n0_0",
                             "to": "n1_0"}
    assert s["target_routes"] == [{"vehicle": "car1", "start_s": 0.0, "lane": 0, "random_walk_from": "h2_0.f"}]
    assert s["buildings"] == 206 and s["uavs"] == ["uav1", "uav2"]


def test_inspect_gives_a_fixed_routes_roads_and_length(capsys):
    assert main(["inspect", "formation_imm"]) == 0
    out = capsys.readouterr().out
    lengths = {line.split()[0]: float(line.split()[1]) for line in out.splitlines() if line.startswith("  ")
               and line.split()[0] in ("lead.f", "straight.f")}
    assert f"target route (car1): lead.f -> straight.f (start_s 0 m, lane 0, {sum(lengths.values()):g} m)" in out
    assert sum(lengths.values()) == pytest.approx(970.0, abs=0.2)


def test_inspect_bad_world_exits_2(capsys):
    assert main(["inspect", "demo", "--set", "roads.streets[0].speed_limit=-1"]) == 2
    assert capsys.readouterr().err.startswith("skytrack inspect: invalid world ")


def test_worlds_prints_every_description_whole_and_wrapped(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    assert main(["worlds"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert all(len(line) <= 80 for line in lines)
    worlds = shipped_worlds()
    col = max(len(n) for n in worlds) + 2
    starts = [k for k, line in enumerate(lines) if not line.startswith(" ")]
    assert [lines[k][:col].strip() for k in starts] == list(worlds)
    for k, end, (name, path) in zip(starts, [*starts[1:], len(lines)], worlds.items(), strict=True):
        text = " ".join(line[col:] for line in lines[k:end])
        assert text == yaml.safe_load(path.read_text(encoding="utf-8"))["description"], name
    assert any(len(range(k, end)) > 1 for k, end in zip(starts, [*starts[1:], len(lines)], strict=True))
