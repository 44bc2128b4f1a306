"""The car driver's settings are declared once: the world schema's ``DriverSpec`` is ``DriverConfig``'s model."""

import pytest
from pydantic import ValidationError

from vehicles.car.driver_config import DriverConfig
from worlds.loader import load_world, shipped_worlds
from worlds.schema import DriverSpec, GroundVehicleSpec
from world_files import write


def test_driver_config_is_the_schema_model_and_adds_no_setting():
    assert issubclass(DriverConfig, DriverSpec)
    assert list(DriverConfig.model_fields) == list(DriverSpec.model_fields)
    for name, field in DriverSpec.model_fields.items():
        mine = DriverConfig.model_fields[name]
        assert (mine.default, mine.annotation, mine.metadata) == (field.default, field.annotation, field.metadata)
    assert not {k for k in vars(DriverConfig).get("__annotations__", {}) if not k.startswith("model_")}
    assert DriverConfig().model_dump() == DriverSpec().model_dump()
    assert DriverConfig.model_config["frozen"] and DriverConfig.model_config["extra"] == "forbid"


def test_driver_config_is_frozen_and_validated():
    cfg = DriverConfig(accel=2.0)
    with pytest.raises(ValidationError):
        cfg.accel = 3.0  # type: ignore[misc]
    with pytest.raises(ValidationError, match="bogus"):
        DriverConfig(bogus=1)
    assert hash(cfg) == hash(DriverConfig(accel=2.0))


@pytest.mark.parametrize("name", sorted(shipped_worlds()))
def test_shipped_driver_keys_keep_their_meaning(name):
    """Every ``driver:`` key of a shipped world reaches the driver with its value (YAML lists as tuples)."""
    loaded = load_world(name)
    for raw, g in zip(loaded.raw.get("ground_vehicles", []), loaded.world.ground_vehicles, strict=True):
        cfg = DriverConfig(**g.driver.model_dump())
        for key, value in (raw.get("driver") or {}).items():
            got = getattr(cfg, key)
            assert (list(got) if isinstance(got, tuple) else got) == value, (name, key)
        stops = raw["route"].get("stop_at_junctions", True)
        if "stop_probability" not in (raw.get("driver") or {}):
            assert cfg.stop_probability == (1.0 if stops else 0.0)


def test_stop_at_junctions_false_means_no_stops_unless_the_driver_says_so(tmp_path):
    route = {"roads": ["a.f"], "stop_at_junctions": False}
    assert GroundVehicleSpec(id="c", route=route).driver.stop_probability == 0.0
    assert GroundVehicleSpec(id="c", route=route, driver={"stop_probability": 0.5}).driver.stop_probability == 0.5
    assert GroundVehicleSpec(id="c", route={"roads": ["a.f"]}).driver.stop_probability == 1.0
    # the resolved world reads the same when loaded again
    dumped = GroundVehicleSpec(id="c", route=route, driver={"accel": 1.0}).model_dump()
    again = GroundVehicleSpec.model_validate(dumped)
    assert again.driver.stop_probability == 0.0 and again.driver.accel == 1.0


def test_driver_errors_name_the_key_path(tmp_path):
    from worlds.errors import WorldError

    text = ("roads:\n  nodes: {a: [0, 0], b: [100, 0]}\n  streets: [{id: s, nodes: [a, b]}]\n"
            "ground_vehicles:\n  - id: c\n    route: {roads: [s.f]}\n"
            "    driver: {decel_max: 1.0, dwell_range: [1, 2]}\n")
    with pytest.raises(WorldError) as info:
        load_world(write(tmp_path, text))
    issue = info.value.issues[0]
    assert issue.path == "ground_vehicles[0].driver" and "decel_max >= decel_plan" in issue.expected
    assert issue.line == 7
