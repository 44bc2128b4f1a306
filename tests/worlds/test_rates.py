"""One rate rule: the loader, the clock, the car drivers and the quadrotor fleet accept and refuse the same rates."""

import pytest

from simulator.clock import Clock
from vehicles.car.driver_config import DriverConfig
from vehicles.car.params import list_cars
from vehicles.quadrotor.airframes import list_airframes
from worlds.catalog import AIRFRAMES, CAR_TYPES
from worlds.rates import divisor, rate_divisor, whole_ticks


@pytest.mark.parametrize("rate, expected", [(48, 5), (240, 1), (2, 120), (0.5, 480), (7, None), (480, None),
                                            (0, None), (-48, None), (1e-300, None), (1e300, None),
                                            (float("nan"), None), (float("inf"), None),
                                            (True, None), ("48", None)])
def test_rate_divisor(rate, expected):
    assert rate_divisor(rate, 240) == expected


@pytest.mark.parametrize("rate", [1, 2, 7, 24, 40, 48, 50, 60, 120, 240, 480])
def test_clock_driver_and_loader_agree(rate):
    expected = rate_divisor(rate, 240)
    clock, driver = Clock(physics_hz=240), DriverConfig(rate_hz=rate)
    if expected is None:
        for call in (lambda: clock.divisor(rate), lambda: driver.ticks_per_update(240)):
            with pytest.raises(ValueError, match=f"{rate} Hz does not divide physics_hz = 240 Hz"):
                call()
    else:
        assert clock.divisor(rate) == driver.ticks_per_update(240) == divisor(rate, 240) == expected


def test_quadrotor_fleet_uses_the_rule():
    import inspect

    import vehicles.quadrotor.fleet as fleet

    source = inspect.getsource(fleet)
    assert "from worlds.rates import divisor" in source and "physics_hz % " not in source


def test_whole_ticks():
    assert whole_ticks(0.25, 240) == 60 and whole_ticks(1 / 240, 240) == 1
    assert whole_ticks(0.001, 240) is None and whole_ticks(float("inf"), 240) is None


def test_catalog_names_what_vehicles_can_load():
    assert CAR_TYPES == tuple(list_cars())
    assert sorted(AIRFRAMES) == sorted(list_airframes())
