"""Car parameter files and their validation."""

import dataclasses
import math

import pytest

from vehicles.car.params import CarParams, list_cars, load_car


def test_shipped_cars_load_and_are_plausible():
    assert list_cars() == ["sedan", "van"]
    sedan, van = load_car("sedan"), load_car("van")
    assert 1300 <= sedan.mass <= 1700
    assert van.mass > sedan.mass and van.wheelbase > sedan.wheelbase
    for car in (sedan, van):
        # braking torque can lock the wheels on dry asphalt: mu m g r <= brake torque (within 30 %)
        assert car.max_brake_torque >= 0.7 * car.tyre_friction * car.mass * 9.81 * car.wheel_radius
        # drive torque supports the stated acceleration: T / r >= m a
        assert car.max_drive_torque / car.wheel_radius >= car.mass * car.max_accel
        # static rollover threshold g t / (2 h) well above any driving lateral acceleration
        assert 9.81 * car.track / (2 * car.cog_height) > 8.0
    assert sedan.min_turn_radius == pytest.approx(sedan.wheelbase / math.tan(sedan.max_steer))


def test_unknown_car_rejected():
    with pytest.raises(ValueError, match="unknown car type 'tank'"):
        load_car("tank")


@pytest.mark.parametrize("field, value", [
    ("mass", -1.0), ("wheelbase", 0.0), ("tyre_friction", float("nan")), ("max_steer", 1.5), ("length", 2.0),
    ("width", 1.0), ("cog_height", 0.2), ("ground_clearance", 0.5), ("rolling_friction", -0.1), ("wheel_mass", 400.0),
    ("max_speed", float("inf")),
])
def test_invalid_params_name_the_field(field, value):
    base = load_car("sedan")
    with pytest.raises(ValueError, match=rf"CarParams\.{field}"):
        dataclasses.replace(base, **{field: value})


def test_params_are_frozen_and_keyword_only():
    base = load_car("sedan")
    with pytest.raises(dataclasses.FrozenInstanceError):
        base.mass = 2.0  # type: ignore[misc]
    with pytest.raises(TypeError):
        CarParams("x", 1500.0)  # type: ignore[misc]
