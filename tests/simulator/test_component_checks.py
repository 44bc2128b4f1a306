"""The loader refuses what a component would refuse when it is built: a sensor entry whose values pass the schema
but break its model's own cross-field rules is a load-time error with the key path, not a late one."""

import pytest

import simulator.registry  # noqa: F401  (registers the component checks)
from simulator.cli import main
from worlds.errors import WorldError
from worlds.loader import load_world


def test_radar_cross_field_rule_refused_at_load():
    # the demo radars keep clutter_range_rate_max at its default; a Doppler notch above it is refused by RadarConfig
    with pytest.raises(WorldError) as err:
        load_world("demo", ["uavs[1].sensors[0].min_detectable_velocity=1e9"])
    text = str(err.value)
    assert "uavs[1].sensors[0]" in text and "min_detectable_velocity" in text and "radar model accepts" in text


def test_radar_rule_refused_by_the_cli_with_exit_2(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["run", "demo", "--duration", "1", "--out", str(out), "--set", "uavs[0].sensors[0].pfa=0.99"])
    assert code == 2
    assert "uavs[0].sensors[0]" in capsys.readouterr().err
    assert not out.exists()


def test_valid_sensor_settings_pass():
    assert load_world("demo", ["uavs[1].sensors[0].min_detectable_velocity=2.0"]).world.uavs[1].sensors[0]
