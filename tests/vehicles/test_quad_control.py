"""Flight controllers closed around the PyBullet bodies: hover, velocity step, unicycle tracking, mixer, rates."""

from __future__ import annotations

import math

import numpy as np
import pytest

from interfaces.setpoints import PositionSetpoint, UnicycleSetpoint, VelocitySetpoint
from vehicles.quadrotor.airframes import load_airframe
from vehicles.quadrotor.fleet import FleetOptions, QuadrotorFleet
from vehicles.quadrotor.mixer import MotorMixer
from vehicles.quadrotor.setpoints import WrenchSetpoint
from vehicles.quadrotor.stack import AirframeStack
from vehicles.quadrotor.wind import WindConfig

HZ = 240


def make_fleet(cid: int, name: str, p0, rng, yaw0: float = 0.0, options: FleetOptions | None = None) -> QuadrotorFleet:
    return QuadrotorFleet(cid, [load_airframe(name)], np.array([p0], dtype=float), np.array([yaw0]), HZ,
                          options or FleetOptions(), rng)


def record(fleet, run_fleet, n_ticks: int, start: int = 1) -> tuple[dict[str, np.ndarray], int]:
    log: dict[str, list] = {"p": [], "v": [], "tilt": [], "thrust": [], "yaw": []}

    def on_tick(_tick: int) -> None:
        st = fleet.state
        log["p"].append(st.p_W[0])
        log["v"].append(st.v_W[0])
        log["tilt"].append(math.acos(min(1.0, st.R_WB[0, 2, 2])))
        log["thrust"].append(st.thrust[0].sum())
        log["yaw"].append(math.atan2(st.R_WB[0, 1, 0], st.R_WB[0, 0, 0]))

    nxt = run_fleet(fleet, n_ticks, start_tick=start, on_tick=on_tick)
    return {k: np.array(v) for k, v in log.items()}, nxt


@pytest.mark.parametrize("name", ["survey_quad", "crazyflie"])
def test_hover_holds_altitude_and_thrust_equals_weight(bullet_client, rng, run_fleet, name) -> None:
    """After a 0.5 m climb, altitude holds within +-2 cm and the rotor thrusts sum to m g within 1 %."""
    a = load_airframe(name)
    fleet = make_fleet(bullet_client, name, [1.0, -2.0, 5.0], rng, yaw0=0.4)
    fleet.set_command(0, PositionSetpoint(p_W=[1.0, -2.0, 5.5]))
    _, tick = record(fleet, run_fleet, HZ * 8)
    log, _ = record(fleet, run_fleet, HZ * 6, start=tick)
    assert np.abs(log["p"][:, 2] - 5.5).max() < 0.02
    assert np.abs(log["p"][:, :2] - [1.0, -2.0]).max() < 0.02
    assert np.abs(log["thrust"] / a.weight - 1.0).max() < 0.01
    assert np.abs(log["yaw"] - 0.4).max() < 1e-3  # yaw=None holds the heading at command time


def _settling(v: np.ndarray, target: float, band: float) -> float:
    outside = np.flatnonzero(np.abs(v - target) > band * abs(target))
    return 0.0 if outside.size == 0 else (outside[-1] + 1) / HZ


@pytest.mark.parametrize(("name", "speed", "t_settle", "overshoot"),
                         [("survey_quad", 10.0, 4.0, 0.05), ("crazyflie", 3.0, 2.5, 0.05)])
def test_velocity_step(bullet_client, rng, run_fleet, name, speed, t_settle, overshoot) -> None:
    """0 -> speed along a heading of 30 deg: within 5 % after t_settle s, overshoot below 5 %, tilt within the limit."""
    a = load_airframe(name)
    fleet = make_fleet(bullet_client, name, [0, 0, 20], rng)
    direction = np.array([math.cos(math.pi / 6), math.sin(math.pi / 6), 0.0])
    fleet.set_command(0, VelocitySetpoint(v_W=speed * direction))
    log, _ = record(fleet, run_fleet, HZ * 10)
    v_along = log["v"] @ direction
    v_cross = log["v"] @ np.array([-direction[1], direction[0], 0.0])
    assert _settling(v_along, speed, 0.05) < t_settle
    assert v_along.max() < (1.0 + overshoot) * speed
    assert np.abs(v_cross).max() < 0.05 * speed
    assert np.abs(log["p"][:, 2] - 20.0).max() < 0.5
    assert log["tilt"].max() <= a.tilt_max
    assert log["tilt"].max() > a.tilt_max - 0.15  # the step really used the tilt envelope
    assert abs(v_along[-1] - speed) < 0.01 * speed
    assert abs(log["yaw"][-1] - math.pi / 6) < 0.02  # yaw=None faces the velocity
    events = fleet.pop_events()
    assert [e["field"] for e in events] == ["tilt"] and events[0]["limit"] == "tilt_max"


def test_unicycle_tracking(bullet_client, rng, run_fleet) -> None:
    """(15 m/s, 0.1 rad/s, 100 m): horizontal distance to the ideal unicycle circle < 1 m after the transient."""
    fleet = make_fleet(bullet_client, "survey_quad", [0, 0, 100], rng)
    fleet.set_command(0, VelocitySetpoint(v_W=[15.0, 0.0, 0.0], yaw=0.0))
    _, tick = record(fleet, run_fleet, HZ * 8)
    st = fleet.state
    psi0 = math.atan2(st.R_WB[0, 1, 0], st.R_WB[0, 0, 0])
    fleet.set_command(0, UnicycleSetpoint(speed=15.0, heading_rate=0.1, altitude=100.0))
    assert fleet.pop_events() == [] or all(e["field"] == "tilt" for e in fleet.pop_events())
    log, _ = record(fleet, run_fleet, HZ * 70, start=tick)  # more than one full turn (62.8 s)
    radius = 15.0 / 0.1
    centre = st.p_W[0, :2] + radius * np.array([-math.sin(psi0), math.cos(psi0)])
    path_error = np.abs(np.linalg.norm(log["p"][:, :2] - centre, axis=1) - radius)
    after = slice(HZ * 5, None)
    assert path_error[after].max() < 1.0
    assert np.abs(log["p"][after, 2] - 100.0).max() < 0.3
    speed = np.linalg.norm(log["v"][after, :2], axis=1)
    assert np.abs(speed - 15.0).max() < 0.3
    # Heading follows psi0 + r t (integrated from integer ticks).
    t = np.arange(1, HZ * 70 + 1) / HZ
    heading_err = np.angle(np.exp(1j * (log["yaw"] - (psi0 + 0.1 * t))))
    assert np.abs(heading_err[after]).max() < 0.01


@pytest.mark.parametrize(
    ("first", "second", "wind"),
    [
        ([20.0, 0.0, 0.0], [0.0, 20.0, 0.0], None),  # 90 deg turn at full speed, facing the new velocity
        ([15.0, 0.0, -5.0], [-15.0, 0.0, 5.0], WindConfig(mean_W=(4.0, -2.0, 0.0))),  # reversal in wind
    ],
    ids=["turn90", "reverse_in_wind"],
)
def test_aggressive_manoeuvres_respect_tilt_limit(bullet_client, rng, run_fleet, first, second, wind) -> None:
    """Thrust-axis priority: a new velocity and heading at full speed never tilt the body past tilt_max."""
    a = load_airframe("survey_quad")
    fleet = make_fleet(bullet_client, "survey_quad", [0, 0, 60], rng, options=FleetOptions(wind=wind))
    fleet.set_command(0, VelocitySetpoint(v_W=first))
    log1, tick = record(fleet, run_fleet, HZ * 6)
    fleet.set_command(0, VelocitySetpoint(v_W=second))
    log2, _ = record(fleet, run_fleet, HZ * 8, start=tick)
    tilt = np.concatenate([log1["tilt"], log2["tilt"]])
    assert tilt.max() <= a.tilt_max
    assert tilt.max() > a.tilt_max - a.gains.tilt_margin - 0.01  # the envelope was used
    np.testing.assert_allclose(log2["v"][-1], second, atol=0.5)  # turbulence: sigma 1 m/s on the airspeed


def test_position_command_flies_to_point(bullet_client, rng, run_fleet) -> None:
    a = load_airframe("survey_quad")
    fleet = make_fleet(bullet_client, "survey_quad", [0, 0, 10], rng)
    fleet.set_command(0, PositionSetpoint(p_W=[60.0, -30.0, 25.0], yaw=1.0))
    log, _ = record(fleet, run_fleet, HZ * 20)
    assert np.linalg.norm(log["p"][-1] - [60.0, -30.0, 25.0]) < 0.1
    assert np.linalg.norm(log["v"][:, :2], axis=1).max() <= a.max_speed * 1.05
    assert np.abs(log["v"][:, 2]).max() <= a.max_climb_rate * 1.1
    assert abs(log["yaw"][-1] - 1.0) < 1e-2


@pytest.mark.parametrize("outer_hz", [48, 60, 240])
def test_outer_loop_rates_that_divide_physics_rate(bullet_client, rng, run_fleet, outer_hz) -> None:
    fleet = make_fleet(bullet_client, "crazyflie", [0, 0, 2], rng, options=FleetOptions(outer_loop_hz=outer_hz))
    fleet.set_command(0, PositionSetpoint(p_W=[1.0, 0.0, 2.0]))
    log, _ = record(fleet, run_fleet, HZ * 6)
    assert np.linalg.norm(log["p"][-1] - [1.0, 0.0, 2.0]) < 0.02


@pytest.mark.parametrize(("outer_hz", "match"), [(50, "outer_loop_hz = 50 Hz does not divide physics_hz = 240 Hz"),
                                                 (7, "outer_loop_hz = 7 Hz"), (480, "outer_loop_hz = 480 Hz")])
def test_rate_not_dividing_physics_rate_rejected(bullet_client, rng, outer_hz, match) -> None:
    with pytest.raises(ValueError, match=match):
        make_fleet(bullet_client, "crazyflie", [0, 0, 2], rng, options=FleetOptions(outer_loop_hz=outer_hz))


@pytest.mark.parametrize("bad", [0, -48, 48.0, True])
def test_rate_must_be_positive_integer(bad) -> None:
    with pytest.raises(ValueError, match="outer_loop_hz"):
        FleetOptions(outer_loop_hz=bad)


def test_physics_rate_must_be_positive_integer(bullet_client, rng) -> None:
    with pytest.raises(ValueError, match="physics_hz"):
        QuadrotorFleet(bullet_client, [load_airframe("crazyflie")], np.zeros((1, 3)), np.zeros(1), 240.0,
                       FleetOptions(), rng)


# ---------------------------------------------------------------- mixer
@pytest.fixture
def mixer_setup():
    stack = AirframeStack.from_params([load_airframe("survey_quad")])
    a = load_airframe("survey_quad")
    alloc = np.linalg.inv(stack.alloc_inv[0])
    return MotorMixer(stack), alloc, a.k_f * a.rotor_speed_min**2, a.k_f * a.rotor_speed_max**2, a


def test_mixer_exact_when_feasible(mixer_setup) -> None:
    mixer, alloc, f_min, f_max, a = mixer_setup
    sp = WrenchSetpoint(thrust=np.array([20.0]), torque_B=np.array([[0.3, -0.2, 0.05]]))
    f = mixer.allocate(sp)
    np.testing.assert_allclose(alloc @ f[0], [20.0, 0.3, -0.2, 0.05], rtol=1e-12, atol=1e-12)
    omega = mixer.update(sp, None).omega
    np.testing.assert_allclose(a.k_f * omega**2, f, rtol=1e-12)
    # Allocation rows: roll torque = sum y_i f_i, pitch = -sum x_i f_i, yaw = -sum s_i k_m/k_f f_i.
    r = a.arm_length / math.sqrt(2.0)
    np.testing.assert_allclose(alloc[1], [r, r, -r, -r])
    np.testing.assert_allclose(alloc[2], [-r, r, r, -r])
    np.testing.assert_allclose(alloc[3], np.array([1, -1, 1, -1]) * a.k_m / a.k_f)


def test_mixer_gives_up_yaw_before_thrust_and_attitude(mixer_setup) -> None:
    mixer, alloc, f_min, f_max, a = mixer_setup
    sp = WrenchSetpoint(thrust=np.array([30.0]), torque_B=np.array([[0.5, 0.0, 5.0]]))
    f = mixer.allocate(sp)[0]
    w = alloc @ f
    assert np.all(f >= f_min - 1e-12) and np.all(f <= f_max + 1e-12)
    np.testing.assert_allclose(w[:3], [30.0, 0.5, 0.0], atol=1e-9)  # thrust and roll kept
    assert 0.0 < w[3] < 5.0 and np.isclose(f, f_max).any()  # yaw reduced to what fits


def test_mixer_keeps_attitude_over_collective_at_full_thrust(mixer_setup) -> None:
    mixer, alloc, f_min, f_max, a = mixer_setup
    sp = WrenchSetpoint(thrust=np.array([4.0 * f_max]), torque_B=np.array([[0.0, 1.0, 0.0]]))
    w = alloc @ mixer.allocate(sp)[0]
    np.testing.assert_allclose(w[1:3], [0.0, 1.0], atol=1e-9)
    assert w[0] < 4.0 * f_max  # collective gave way
    huge = WrenchSetpoint(thrust=np.array([20.0]), torque_B=np.array([[100.0, 0.0, 0.0]]))
    f = mixer.allocate(huge)[0]
    assert np.all(f >= f_min - 1e-12) and np.all(f <= f_max + 1e-12)
    assert (alloc @ f)[1] > 0.0  # still rolls the right way, at the largest feasible torque
    np.testing.assert_allclose(np.sort(f), [f_min, f_min, f_max, f_max])


def test_mixer_allocates_each_airframe_of_a_mixed_fleet_with_its_own_matrix() -> None:
    """A fleet of one airframe and a mixed fleet give the same numbers for the same airframe."""
    survey, cf = load_airframe("survey_quad"), load_airframe("crazyflie")
    uniform, mixed = AirframeStack.from_params([survey, survey]), AirframeStack.from_params([survey, cf])
    sp = WrenchSetpoint(thrust=np.array([30.0, 0.3]), torque_B=np.array([[0.5, -0.2, 5.0], [1e-4, 0.0, 0.0]]))
    f_uniform = MotorMixer(uniform).allocate(sp)
    f_mixed = MotorMixer(mixed).allocate(sp)
    np.testing.assert_allclose(f_uniform[0], f_mixed[0], rtol=1e-12)
    alloc_cf = np.linalg.inv(mixed.alloc_inv[1])
    np.testing.assert_allclose(alloc_cf @ f_mixed[1], [0.3, 1e-4, 0.0, 0.0], atol=1e-12)
