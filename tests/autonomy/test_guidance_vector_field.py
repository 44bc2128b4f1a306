"""Lyapunov vector-field guidance: field properties and closed-loop convergence (quadrotor scale: r_d = 120 m)."""

import numpy as np
import pytest

from autonomy.guidance.unicycle import UnicycleParams
from interfaces.state import OwnState
from autonomy.guidance.vector_field import VectorFieldConfig, VectorFieldGuidance, wrap_angle
from simulator.kinematic.unicycle_loop import LoopConfig, run_kinematic_loop

RD = 120.0


def test_field_magnitude_and_lyapunov_decrease():
    g = VectorFieldGuidance(VectorFieldConfig(standoff_radius=RD, nominal_speed=12.0))
    rng = np.random.default_rng(3)
    for r in rng.uniform(-500, 500, size=(200, 2)):
        v = g.field(r, 12.0)
        assert np.linalg.norm(v) == pytest.approx(12.0, rel=1e-12)
        rho = np.linalg.norm(r)
        vdot = 4 * (rho**2 - RD**2) * (r @ v)  # d/dt (ρ² − r_d²)²
        expected = -4 * 12.0 * rho * (rho**2 - RD**2) ** 2 / (rho**2 + RD**2)
        assert vdot == pytest.approx(expected, rel=1e-9, abs=1e-6)
    # on the circle the field is tangential, counter-clockwise
    np.testing.assert_allclose(g.field(np.array([RD, 0.0]), 12.0), [0.0, 12.0], atol=1e-12)


@pytest.mark.parametrize("start", [(25.0, 10.0), (450.0, -300.0)], ids=["inside", "outside"])
def test_converges_to_standoff_circle(start):
    cfg = VectorFieldConfig(standoff_radius=RD, nominal_speed=12.0, max_speed=20.0, max_heading_rate=0.6)
    loop = LoopConfig(dt=0.1, steps=2000, target_v=(4.0, 1.0), plant=UnicycleParams(tau_v=0.3, tau_omega=0.3))
    res = run_kinematic_loop([VectorFieldGuidance(cfg)], np.array([[*start, 0.5, 10.0, 0.0]]), loop)
    err = np.abs(res.ranges[-400:, 0] - RD)
    assert err.max() < 0.01 * RD
    assert abs(res.ranges[0, 0] - RD) > 50.0


def test_phase_keeping_two_uavs():
    cfg = VectorFieldConfig(standoff_radius=RD, nominal_speed=12.0, max_speed=20.0, team_size=2, phase_gain=0.5)
    laws = [VectorFieldGuidance(cfg, slot=0), VectorFieldGuidance(cfg, slot=1)]
    loop = LoopConfig(dt=0.1, steps=3000, target_v=(3.0, 0.0), plant=UnicycleParams(tau_v=0.3, tau_omega=0.3))
    res = run_kinematic_loop(laws, np.array([[150.0, 0.0, 1.5, 12.0, 0.0], [100.0, 60.0, 2.5, 12.0, 0.0]]), loop)
    ph = res.phases[-500:]
    err = np.degrees(np.abs(wrap_angle(ph[:, 1] - ph[:, 0] - np.pi)))
    assert err.max() < 3.0
    assert np.degrees(abs(wrap_angle(res.phases[0, 1] - res.phases[0, 0] - np.pi))) > 90.0


def test_no_target_loiters():
    from interfaces.state import OwnState
    g = VectorFieldGuidance(VectorFieldConfig())
    sp = g.command(OwnState(t=0, p_W=[0, 0, 50], v_W=[0, 0, 0], yaw=0.0), None, [], 0.0)
    assert sp.heading_rate == pytest.approx(12.0 / 120.0)


def test_phase_keeping_over_a_large_team_equals_the_per_teammate_formula():
    """The team's phases come from one array operation: the same speed, bit for bit, as predicting and measuring
    every teammate one by one (v_r = v_0 (1 + k_φ d mean_j e_j)), with and without shared plans."""
    from autonomy.guidance.vector_field import phase_errors
    from interfaces.state import TargetEstimate, TeammateState

    cfg = VectorFieldConfig(standoff_radius=RD, nominal_speed=12.0, team_size=30, phase_gain=0.8, direction=-1)
    law = VectorFieldGuidance(cfg, slot=4)
    rng = np.random.default_rng(11)
    target = TargetEstimate(t=9.5, p_W=[30.0, -20.0], v_W=[4.0, 1.0])
    mates = [TeammateState(id=j, t=float(rng.uniform(9, 10)), p_W=[*rng.normal(scale=150.0, size=2), 60.0],
                           v_W=[*rng.normal(scale=12.0, size=2), 0.0], phase_slot=(j * 7) % 30,
                           plan_p_W=rng.normal(scale=150.0, size=(5, 2)) if j % 4 == 0 else None, plan_dt=0.5)
             for j in range(29)]
    t, r = 10.0, np.array([80.0, 95.0])
    th = [float(np.arctan2(*(m.predict_xy(np.array([t]))[0] - target.predict_xy(t))[::-1])) for m in mates]
    e = phase_errors(float(np.arctan2(r[1], r[0])), 4, th, [m.slot for m in mates], cfg.separation, cfg.direction)
    expected = cfg.nominal_speed * float(np.clip(1.0 + cfg.phase_gain * cfg.direction * float(np.mean(e)), 0.5, 1.5))
    got = law.relative_speed(r, target, mates, t)
    assert got == expected and got != cfg.nominal_speed


def test_phase_keeping_reads_a_team_view_as_its_states():
    """The stacked arrays of a perfect-comms inbox (TeamStates) give the speed its states give one by one."""
    from interfaces.state import TargetEstimate
    from interfaces.team_states import TeamStates

    rng = np.random.default_rng(5)
    n = 40
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False) + rng.normal(scale=0.2, size=n)
    p = np.column_stack([RD * np.cos(angles), RD * np.sin(angles), np.full(n, 60.0)])
    team = TeamStates.of(3.0, p, rng.normal(scale=12.0, size=(n, 3)), rng.normal(size=n))
    cfg = VectorFieldConfig(standoff_radius=RD, nominal_speed=12.0, team_size=n, phase_gain=0.5)
    target = TargetEstimate(t=2.8, p_W=[1.0, -2.0], v_W=[3.0, 0.5])
    for k in (0, 17, n - 1):
        law = VectorFieldGuidance(cfg, slot=k)
        r = p[k, :2] - target.predict_xy(3.0)
        view, states = team.without(k), list(team.without(k))
        assert law.relative_speed(r, target, view, 3.0) == law.relative_speed(r, target, states, 3.0)
        own = OwnState(t=3.0, p_W=p[k], v_W=[5.0, 1.0, 0.0], yaw=0.0)
        assert law.command(own, target, view, 3.0) == law.command(own, target, states, 3.0)


def test_clip_of_one_number_is_numpys():
    from autonomy.guidance.vector_field import _clip

    rng = np.random.default_rng(2)
    xs = [*rng.normal(scale=3.0, size=200), -1.0, 1.0, 0.0, -0.0, np.inf, -np.inf]
    for lo, hi in ((-1.0, 1.0), (0.0, 20.0), (-0.0, 20.0), (-3.0, 0.0), (-3.0, -0.0), (0.5, 1.5)):
        for x in xs:
            got, want = _clip(float(x), lo, hi), float(np.clip(x, lo, hi))
            assert type(got) is float and got == want and np.signbit(got) == np.signbit(want)
    assert np.isnan(_clip(float("nan"), 0.0, 1.0))
