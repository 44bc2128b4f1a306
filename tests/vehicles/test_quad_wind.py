"""Wind: Dryden turbulence statistics, position hold in wind, and invariants under random set-points."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import stats

from interfaces.setpoints import PositionSetpoint, UnicycleSetpoint, VelocitySetpoint
from vehicles.quadrotor.airframes import load_airframe
from vehicles.quadrotor.fleet import FleetOptions, QuadrotorFleet
from vehicles.quadrotor.wind import DrydenWind, WindConfig

DT = 1.0 / 240.0


def test_wind_config_validation() -> None:
    with pytest.raises(ValueError, match="sigma"):
        WindConfig(sigma=(1.0, -1.0, 0.5))
    with pytest.raises(ValueError, match="length_scale"):
        WindConfig(length_scale=(200.0, 0.0, 50.0))
    with pytest.raises(ValueError, match="airspeed"):
        WindConfig(airspeed=0.0)
    with pytest.raises(ValueError, match="mean_W"):
        WindConfig(mean_W=(1.0, float("nan"), 0.0))


def test_dryden_variance_and_correlation() -> None:
    """Across 2000 independent UAVs: variance in its chi^2 band, lag correlation in its Fisher-z band.

    Longitudinal: R(tau) = sigma^2 exp(-tau/T); lateral/vertical: R(tau) = sigma^2 (1 - tau/(2T)) exp(-tau/T), T = L/V.
    """
    cfg = WindConfig(mean_W=(3.0, 4.0, 0.0), sigma=(1.5, 1.2, 0.6), length_scale=(100.0, 80.0, 30.0), airspeed=10.0)
    n, lag = 2000, 240
    wind = DrydenWind(cfg, n, DT, np.random.default_rng(7))
    w0 = wind.step()
    for _ in range(lag - 1):
        wind.step()
    w1 = wind.step()
    c, s = 0.6, 0.8  # mean wind direction: turbulence axes u along it, v across, w vertical
    to_uvw = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    g0, g1 = (w0 - cfg.mean_W) @ to_uvw.T, (w1 - cfg.mean_W) @ to_uvw.T
    alpha = 1e-3
    lo, hi = stats.chi2.ppf(alpha / 2, n), stats.chi2.ppf(1 - alpha / 2, n)
    z = stats.norm.ppf(1 - alpha / 2) / math.sqrt(n - 3)
    tau = lag * DT
    for k in range(3):
        sigma, T = cfg.sigma[k], cfg.length_scale[k] / cfg.airspeed
        assert lo < np.sum(g0[:, k] ** 2) / sigma**2 < hi  # known zero mean -> chi^2 with n dof
        rho = math.exp(-tau / T) * (1.0 if k == 0 else 1.0 - tau / (2.0 * T))
        r = np.corrcoef(g0[:, k], g1[:, k])[0, 1]
        assert abs(math.atanh(r) - math.atanh(rho)) < z
    assert abs(np.corrcoef(g0[:, 0], g0[:, 1])[0, 1]) < z  # axes independent


def test_wind_is_reproducible_from_the_generator() -> None:
    cfg = WindConfig(mean_W=(5.0, 0.0, 0.0))
    a = DrydenWind(cfg, 3, DT, np.random.default_rng(11))
    b = DrydenWind(cfg, 3, DT, np.random.default_rng(11))
    for _ in range(50):
        np.testing.assert_array_equal(a.step(), b.step())


def test_position_hold_in_gusty_wind(bullet_client, run_fleet) -> None:
    """5 m/s mean wind plus moderate turbulence (sigma 1.5/1.5/0.75 m/s): after 5 s the survey quad stays within
    0.5 m horizontally and 0.25 m vertically of its hold point over 40 s; nothing is ever NaN."""
    a = load_airframe("survey_quad")
    opts = FleetOptions(wind=WindConfig(mean_W=(5.0, 0.0, 0.0), sigma=(1.5, 1.5, 0.75)))
    fleet = QuadrotorFleet(bullet_client, [a, a], np.array([[0.0, 0.0, 50.0], [20.0, 0.0, 50.0]]), np.zeros(2), 240,
                           opts, np.random.default_rng(3))
    err = []

    def check(_tick: int) -> None:
        s = fleet.state
        for arr in (s.p_W, s.q_WB, s.v_W, s.omega_B, s.rotor_speed, s.thrust, fleet.force_W, fleet.torque_W):
            assert np.all(np.isfinite(arr))
        err.append(s.p_W - [[0.0, 0.0, 50.0], [20.0, 0.0, 50.0]])

    run_fleet(fleet, 240 * 45, on_tick=check)
    err = np.array(err)[240 * 5:]
    assert np.linalg.norm(err[:, :, :2], axis=2).max() < 0.5
    assert np.abs(err[:, :, 2]).max() < 0.25
    assert np.abs(err).max() > 0.01  # the wind really disturbed it
    assert not np.allclose(err[:, 0], err[:, 1])  # independent turbulence per UAV


command_strategy = st.one_of(
    st.builds(lambda x, y, z, yaw: PositionSetpoint(p_W=[x, y, z], yaw=yaw),
              st.floats(-80, 80), st.floats(-80, 80), st.floats(5, 120),
              st.one_of(st.none(), st.floats(-10, 10))),
    st.builds(lambda vx, vy, vz, yaw: VelocitySetpoint(v_W=[vx, vy, vz], yaw=yaw),
              st.floats(-40, 40), st.floats(-40, 40), st.floats(-10, 10), st.one_of(st.none(), st.floats(-4, 4))),
    st.builds(lambda v, r, h: UnicycleSetpoint(speed=v, heading_rate=r, altitude=h),
              st.floats(0, 30), st.floats(-3, 3), st.floats(10, 120)),
)


@settings(max_examples=12, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(commands=st.lists(st.tuples(st.sampled_from([0, 1]), command_strategy), min_size=1, max_size=3),
       seed=st.integers(0, 2**32 - 1))
def test_invariants_under_random_setpoints(new_bullet_session, run_fleet, commands, seed) -> None:
    """Quaternions stay unit, rotor speeds within [0, w_max], tilt within tilt_max, everything finite; saturation
    is always reported."""
    with new_bullet_session() as cid:
        _fly_random_commands(cid, run_fleet, commands, seed)


def _fly_random_commands(cid: int, run_fleet, commands, seed: int) -> None:
    airframes = [load_airframe("survey_quad"), load_airframe("crazyflie")]
    opts = FleetOptions(wind=WindConfig(mean_W=(4.0, -2.0, 0.0)), downwash=True, ground_effect=True)
    fleet = QuadrotorFleet(cid, airframes, np.array([[0.0, 0.0, 40.0], [3.0, 0.0, 40.0]]),
                           np.zeros(2), 240, opts, np.random.default_rng(seed))
    w_max = np.array([[a.rotor_speed_max] for a in airframes])
    tilt_max = np.array([a.tilt_max for a in airframes])
    tick = 1

    def check(_tick: int) -> None:
        s = fleet.state
        assert np.all(np.isfinite(s.p_W)) and np.all(np.isfinite(s.v_W)) and np.all(np.isfinite(s.omega_B))
        np.testing.assert_allclose(np.linalg.norm(s.q_WB, axis=1), 1.0, atol=1e-9)
        assert np.all(s.rotor_speed >= 0.0) and np.all(s.rotor_speed <= w_max)
        assert np.all(np.arccos(np.clip(s.R_WB[:, 2, 2], -1.0, 1.0)) <= tilt_max)
        assert np.all(np.isfinite(fleet.force_W)) and np.all(np.isfinite(fleet.torque_W))

    for uav, cmd in commands:
        fleet.set_command(uav, cmd)
        tick = run_fleet(fleet, 240, start_tick=tick, on_tick=check)
        a = airframes[uav]
        saturated = {e["field"] for e in fleet.pop_events() if e["uav"] == uav}
        if isinstance(cmd, VelocitySetpoint):
            assert (math.hypot(cmd.v_W[0], cmd.v_W[1]) > a.max_speed) == ("speed" in saturated)
            assert (abs(cmd.v_W[2]) > a.max_climb_rate) == ("climb_rate" in saturated)
        if isinstance(cmd, UnicycleSetpoint):
            assert (cmd.speed > a.max_speed) == ("speed" in saturated)
            if abs(cmd.heading_rate) > a.max_heading_rate:
                assert "heading_rate" in saturated
