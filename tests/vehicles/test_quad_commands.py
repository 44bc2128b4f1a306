"""Typed set-points: validation, envelope saturation reported as events, yaw conventions, determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from interfaces.setpoints import PositionSetpoint, UnicycleSetpoint, VelocitySetpoint
from vehicles.quadrotor.airframes import load_airframe
from vehicles.quadrotor.command_shaping import TURN_ACCEL_FRACTION, sqrt_speed
from vehicles.quadrotor.fleet import FleetOptions, QuadrotorFleet
from vehicles.quadrotor.params import GRAVITY
from vehicles.quadrotor.wind import WindConfig


def fleet_of(cid: int, names: list[str], rng, options: FleetOptions | None = None) -> QuadrotorFleet:
    p0 = np.array([[5.0 * i, 0.0, 30.0] for i in range(len(names))])
    return QuadrotorFleet(cid, [load_airframe(n) for n in names], p0, np.zeros(len(names)), 240,
                          options or FleetOptions(), rng)


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: PositionSetpoint(p_W=[0.0, 1.0]), "PositionSetpoint.p_W"),
        (lambda: PositionSetpoint(p_W=[0.0, 1.0, float("nan")]), "PositionSetpoint.p_W"),
        (lambda: PositionSetpoint(p_W=[0.0, 1.0, 2.0], yaw=float("inf")), "PositionSetpoint.yaw"),
        (lambda: VelocitySetpoint(v_W=[1.0, 2.0, 3.0, 4.0]), "VelocitySetpoint.v_W"),
        (lambda: UnicycleSetpoint(speed=-1.0, heading_rate=0.0, altitude=10.0), "UnicycleSetpoint.speed"),
        (lambda: UnicycleSetpoint(speed=1.0, heading_rate=float("nan"), altitude=10.0),
         "UnicycleSetpoint.heading_rate"),
    ],
)
def test_invalid_commands_rejected(make, match) -> None:
    with pytest.raises(ValueError, match=match):
        make()


def test_commands_are_immutable() -> None:
    cmd = VelocitySetpoint(v_W=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError):
        cmd.v_W[0] = 5.0


def test_velocity_saturation_events(bullet_client, rng, run_fleet) -> None:
    a = load_airframe("survey_quad")
    fleet = fleet_of(bullet_client, ["survey_quad"], rng)
    fleet.set_command(0, VelocitySetpoint(v_W=[15.0, 20.0, -8.0]))
    events = fleet.pop_events()
    assert fleet.pop_events() == []  # popping clears
    by_field = {e["field"]: e for e in events}
    assert by_field["speed"] == {"type": "command_saturated", "uav": 0, "tick": 0, "field": "speed",
                                 "requested": 25.0, "applied": a.max_speed, "limit": "max_speed"}
    assert by_field["climb_rate"]["requested"] == -8.0 and by_field["climb_rate"]["applied"] == -a.max_climb_rate
    run_fleet(fleet, 240 * 12)
    v = fleet.state.v_W[0]
    np.testing.assert_allclose(v, [12.0, 16.0, -5.0], atol=0.1)  # direction kept, magnitude at the envelope


def test_unicycle_saturation_events(bullet_client, rng) -> None:
    a = load_airframe("survey_quad")
    fleet = fleet_of(bullet_client, ["survey_quad"], rng)
    fleet.set_command(0, UnicycleSetpoint(speed=25.0, heading_rate=-2.0, altitude=30.0))
    by_field = {(e["field"], e["limit"]): e for e in fleet.pop_events()}
    assert by_field[("speed", "max_speed")]["applied"] == a.max_speed
    assert by_field[("heading_rate", "max_heading_rate")]["applied"] == -a.max_heading_rate
    turn_limit = TURN_ACCEL_FRACTION * GRAVITY * math.tan(a.tilt_max - a.gains.tilt_margin) / a.max_speed
    tilt_event = by_field[("heading_rate", "tilt_max")]
    assert tilt_event["requested"] == -a.max_heading_rate
    assert tilt_event["applied"] == pytest.approx(-turn_limit)
    fleet.set_command(0, UnicycleSetpoint(speed=10.0, heading_rate=0.2, altitude=30.0))
    assert fleet.pop_events() == []  # inside the envelope: nothing to report


def test_tilt_saturation_reported_once_per_episode(bullet_client, rng, run_fleet) -> None:
    fleet = fleet_of(bullet_client, ["survey_quad", "crazyflie"], rng)
    fleet.set_command(1, VelocitySetpoint(v_W=[0.0, 3.0, 0.0]))
    run_fleet(fleet, 240 * 4)
    events = fleet.pop_events()
    assert [(e["uav"], e["field"]) for e in events] == [(1, "tilt")]
    assert events[0]["requested"] > events[0]["applied"] == pytest.approx(float(fleet.tilt_limit[1]))
    fleet.set_command(1, VelocitySetpoint(v_W=[0.0, -3.0, 0.0]))
    run_fleet(fleet, 240 * 4, start_tick=240 * 4 + 1)
    assert [(e["uav"], e["field"]) for e in fleet.pop_events()] == [(1, "tilt")]


def test_velocity_yaw_none_faces_velocity_and_explicit_yaw_holds(bullet_client, rng, run_fleet) -> None:
    fleet = fleet_of(bullet_client, ["survey_quad", "survey_quad"], rng)
    fleet.set_command(0, VelocitySetpoint(v_W=[-3.0, -3.0, 0.0]))
    fleet.set_command(1, VelocitySetpoint(v_W=[-3.0, -3.0, 0.0], yaw=0.5))
    run_fleet(fleet, 240 * 6)
    R = fleet.state.R_WB
    assert math.atan2(R[0, 1, 0], R[0, 0, 0]) == pytest.approx(-3.0 * math.pi / 4, abs=1e-3)
    assert math.atan2(R[1, 1, 0], R[1, 0, 0]) == pytest.approx(0.5, abs=1e-3)


def test_sqrt_speed_is_continuous_and_brakes_in_time() -> None:
    k, a = 1.0, 3.0
    d = np.linspace(0.0, 50.0, 5001)
    v = np.array([sqrt_speed(x, k, a) for x in d])
    assert np.all(np.diff(v) >= 0) and np.max(np.abs(np.diff(v))) < 0.02  # continuous, monotone
    np.testing.assert_allclose(v[d <= 3.0], d[d <= 3.0])  # linear zone k d up to a / k^2
    far = d > 3.0
    assert np.all(v[far] ** 2 / (2 * a) <= d[far])  # braking distance at a never exceeds the distance left


def test_same_seed_same_flight_bit_for_bit(run_fleet, new_bullet_session) -> None:
    def flight(seed: int) -> np.ndarray:
        with new_bullet_session() as cid:
            opts = FleetOptions(wind=WindConfig(mean_W=(3.0, 1.0, 0.0)), downwash=True)
            fleet = fleet_of(cid, ["survey_quad", "crazyflie"], np.random.default_rng(seed), opts)
            fleet.set_command(0, UnicycleSetpoint(speed=8.0, heading_rate=0.3, altitude=35.0))
            fleet.set_command(1, PositionSetpoint(p_W=[6.0, 2.0, 31.0]))
            run_fleet(fleet, 480)
            s = fleet.state
            return np.concatenate([s.p_W.ravel(), s.q_WB.ravel(), s.rotor_speed.ravel()])

    a, b, c = flight(1), flight(1), flight(2)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_set_command_checks_index_and_type(bullet_client, rng) -> None:
    fleet = fleet_of(bullet_client, ["crazyflie"], rng)
    with pytest.raises(IndexError):
        fleet.set_command(1, PositionSetpoint(p_W=[0.0, 0.0, 1.0]))
    with pytest.raises(TypeError, match="dict"):
        fleet.set_command(0, {"p_W": [0, 0, 1]})  # type: ignore[arg-type]


def test_initial_state_hovers_at_p0(bullet_client, rng) -> None:
    fleet = fleet_of(bullet_client, ["survey_quad", "crazyflie"], rng)
    s = fleet.state
    np.testing.assert_allclose(s.p_W, [[0.0, 0.0, 30.0], [5.0, 0.0, 30.0]])
    np.testing.assert_allclose(s.thrust.sum(axis=1), [a.weight for a in fleet.airframes], rtol=1e-12)
    np.testing.assert_allclose(s.rotor_speed[:, 0], [a.hover_rotor_speed for a in fleet.airframes], rtol=1e-12)
    assert s.p_W.shape == (2, 3) and s.q_WB.shape == (2, 4) and s.omega_B.shape == (2, 3)
    assert fleet.body_ids.shape == (2,)


def test_initial_arrays_validated(bullet_client, rng) -> None:
    cf = load_airframe("crazyflie")
    with pytest.raises(ValueError, match="p0_W"):
        QuadrotorFleet(bullet_client, [cf, cf], np.zeros((1, 3)), np.zeros(2), 240, FleetOptions(), rng)
    with pytest.raises(ValueError, match="yaw0"):
        QuadrotorFleet(bullet_client, [cf], np.zeros((1, 3)), np.array([np.nan]), 240, FleetOptions(), rng)


def test_command_takes_effect_at_next_outer_tick(bullet_client, rng, run_fleet) -> None:
    """With outer_loop_hz = 48 at 240 Hz the velocity loop runs on ticks 5, 10, ...: a command set after tick 6
    changes nothing until tick 10."""
    fleet = fleet_of(bullet_client, ["survey_quad"], rng, FleetOptions(outer_loop_hz=48))
    run_fleet(fleet, 6)
    fleet.set_command(0, VelocitySetpoint(v_W=[5.0, 0.0, 0.0]))
    omegas = []
    run_fleet(fleet, 6, start_tick=7, on_tick=lambda _t: omegas.append(fleet.state.rotor_speed[0].copy()))
    omegas = np.array(omegas)  # after ticks 7..12
    np.testing.assert_allclose(omegas[:4] - omegas[0], 0.0, atol=1e-9)  # up to tick 10's loops: hovering
    assert np.ptp(omegas[5]) > 1.0  # the rotors spun up in tick 11-12 differ to pitch forward


def test_state_is_a_copy(bullet_client, rng) -> None:
    fleet = fleet_of(bullet_client, ["crazyflie"], rng)
    s = fleet.state
    s.p_W[0, 2] = -100.0
    s.rotor_speed[:] = 0.0
    assert fleet.state.p_W[0, 2] == pytest.approx(30.0) and fleet.state.rotor_speed.min() > 0
