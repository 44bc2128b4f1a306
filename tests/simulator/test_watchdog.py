"""The divergence watchdog: which state it refuses, what it names, where in the tick it looks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simulator.clock import Clock
from simulator.fake_engine import FakePhysics, ScriptedUavs, fake_assembly
from simulator.record import RunRecorder
from simulator.streams import STREAMS
from simulator.watchdog import BELOW_GROUND_M, SPEED_MARGIN, Divergence, Watchdog, airframe_top_speed, world_watchdog
from tests.simulator.fakes import HZ
from vehicles.quadrotor.airframes import load_airframe
from vehicles.quadrotor.state import FleetState
from worlds.loader import load_world


def _state(n: int = 2, **set_row: np.ndarray) -> FleetState:
    """``n`` UAVs hovering at 50 m, with row 1 of the named fields replaced."""
    f = {"p_W": np.tile([0.0, 0.0, 50.0], (n, 1)), "q_WB": np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
         "v_W": np.zeros((n, 3)), "omega_B": np.zeros((n, 3))}
    for k, v in set_row.items():
        f[k][1] = v
    return FleetState(R_WB=np.tile(np.eye(3), (n, 1, 1)), rotor_speed=np.zeros((n, 4)), thrust=np.zeros((n, 4)), **f)


DOG = Watchdog(["a", "b"], [], speed_max=np.array([30.0, 30.0]))


def test_a_sane_state_passes():
    DOG.check(5, _state(v_W=np.array([17.0, 17.0, 17.0])), None)  # 29.4 m/s, under the 30 m/s limit


@pytest.mark.parametrize(("row", "quantity", "value", "limit"), [
    ({"p_W": np.array([1.0, np.nan, 50.0])}, "p_W", "[ 1., nan, 50.]", "not finite"),
    ({"v_W": np.array([np.inf, 0.0, 0.0])}, "v_W", "[inf,  0.,  0.]", "not finite"),
    ({"q_WB": np.array([np.nan] * 4)}, "q_WB", "[nan, nan, nan, nan]", "not finite"),
    ({"omega_B": np.array([0.0, 0.0, -np.inf])}, "omega_B", "[  0.,   0., -inf]", "not finite"),
    ({"p_W": np.array([0.0, 0.0, np.inf])}, "p_W", "[ 0.,  0., inf]", "not finite"),
    ({"p_W": np.array([3.0, 4.0, -1.5])}, "z", "-1.5 m", "under the ground: below -1 m"),
    # PyBullet's clamp of each velocity component at 100 m/s: a blown-up body at 100·√3 m/s
    ({"v_W": np.array([100.0, 100.0, 100.0])}, "speed", "173.2 m/s",
     "faster than the airframe can fly: above 30 m/s"),
], ids=["nan-position", "inf-velocity", "nan-attitude", "inf-rate", "inf-height", "under-ground", "clamped-speed"])
def test_each_insane_quantity_is_named_with_the_body_and_tick(row, quantity, value, limit):
    with pytest.raises(Divergence) as err:
        DOG.check(1234, _state(**row), None)
    d = err.value
    assert (d.body, d.tick, d.quantity, d.value, d.limit) == ("b", 1234, quantity, value, limit)
    assert str(d) == f"b diverged at tick 1234: {quantity} = {value} ({limit})"


def test_a_body_resting_on_the_ground_is_sane_and_the_limit_is_a_metre_under_it():
    DOG.check(1, _state(p_W=np.array([0.0, 0.0, -BELOW_GROUND_M + 1e-9])), None)
    with pytest.raises(Divergence, match=r"z = -1.001 m \(under the ground: below -1 m\)"):
        DOG.check(1, _state(p_W=np.array([0.0, 0.0, -BELOW_GROUND_M - 1e-3])), None)


def test_a_car_with_a_non_finite_state_is_named():
    class Cars:
        p_W = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 0.0]])
        v_W = np.array([[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]])

    with pytest.raises(Divergence, match=r"^car2 diverged at tick 7: v_W = \[nan,  0.,  0.\] \(not finite\)$"):
        Watchdog([], ["car1", "car2"], np.zeros(0)).check(7, None, Cars())


def test_top_speed_balances_drag_against_full_thrust_and_weight():
    # c2 v² + c1 v = T + m g with c2 = 0.02, c1 = 0.1, T + m g = 50 N: v = (-0.1 + sqrt(0.01 + 4.0)) / 0.04
    v = airframe_top_speed(mass=1.0, max_thrust=50.0 - 9.81, drag_linear=(0.1, 0.2, 0.3),
                           drag_quadratic=(0.02, 0.05, 0.05), gravity=9.81)
    assert v == pytest.approx((-0.1 + math.sqrt(4.01)) / 0.04, rel=1e-12)
    assert airframe_top_speed(mass=1.0, max_thrust=10.0, drag_linear=(0.5,) * 3, drag_quadratic=(0.0,) * 3,
                              gravity=10.0) == pytest.approx(40.0)
    assert airframe_top_speed(mass=1.0, max_thrust=10.0, drag_linear=(0.0,) * 3, drag_quadratic=(0.0,) * 3,
                              gravity=10.0) == math.inf


def test_the_world_limits_are_above_every_speed_the_airframe_reaches():
    loaded = load_world("demo", ["environment.wind.mean_W=[3,4,0]"])
    dog = world_watchdog(loaded.world)
    a = load_airframe(loaded.world.uavs[0].airframe)
    top = airframe_top_speed(mass=a.mass, max_thrust=4 * a.k_f * a.rotor_speed_max**2, drag_linear=a.drag_linear,
                             drag_quadratic=a.drag_quadratic, gravity=9.81)
    assert dog.speed_max[0] == pytest.approx(SPEED_MARGIN * top + 5.0)
    assert a.max_speed < top and dog.speed_max[0] < 100.0  # under PyBullet's clamp of each component
    assert dog.uav_ids == [u.id for u in loaded.world.uavs]


def test_the_tick_stops_before_sensors_and_agents_see_a_diverged_state(tmp_path):
    log: list = []

    def dive(tick: int) -> np.ndarray:  # the second UAV goes through the ground at tick 5
        return np.array([[0.0, 0.0, 50.0], [10.0, 0.0, 50.0 if tick < 5 else -20.0]])

    uavs = ScriptedUavs(dive, HZ, log)
    recorder = RunRecorder(tmp_path, schemas=STREAMS)
    asm = fake_assembly(clock=Clock(physics_hz=HZ), recorder=recorder, uavs=uavs, uav_ids=["a", "b"], agents=[],
                        methods=[], physics=FakePhysics(log))
    asm.watchdog = Watchdog(["a", "b"], [], speed_max=np.array([1e6, 1e6]))
    for tick in range(1, 5):
        asm.step(tick)
    with pytest.raises(Divergence, match=r"^b diverged at tick 5: z = -20 m"):
        asm.step(5)
    assert log[-1] == ("uavs.after_step", 5)  # right after the truth read, nothing after it
    recorder.close()
