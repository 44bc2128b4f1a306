"""NMPC standoff tracking in closed loop on the lagged kinematic unicycle (quadrotor scale: r_d = 120 m, v_0 = 12 m/s,
T = 0.5 s, N = 20)."""

import numpy as np
import pytest

from autonomy.guidance.keepout import footprint_distance
from autonomy.guidance.nmpc import NmpcStandoffGuidance
from autonomy.guidance.nmpc_config import NmpcConfig
from autonomy.guidance.vector_field import wrap_angle
from interfaces.setpoints import UnicycleSetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState
from simulator.kinematic.unicycle_loop import LoopConfig, run_kinematic_loop
from worlds.geometry import Building

RD = 120.0


@pytest.mark.parametrize("solver", ["sqp", "fatrop", pytest.param("ipopt", marks=pytest.mark.slow)])
def test_standoff_and_phase_against_constant_velocity_target(solver):
    cfg = NmpcConfig(standoff_radius=RD, solver=solver)
    laws = [NmpcStandoffGuidance(cfg, 0), NmpcStandoffGuidance(cfg, 1)]
    x0 = np.array([[150.0, 20.0, 1.5, 12.0, 0.0], [-100.0, -90.0, 0.0, 12.0, 0.0]])
    res = run_kinematic_loop(laws, x0, LoopConfig(dt=0.5, steps=360, target_v=(4.0, 1.0)))
    steady = slice(-160, None)
    err_r = np.abs(res.ranges[steady] - RD)
    err_ph = np.degrees(np.abs(wrap_angle(res.phases[steady, 1] - res.phases[steady, 0] - np.pi)))
    assert err_r.max() < 0.02 * RD
    assert err_ph.max() < 5.0
    assert abs(res.ranges[0, 0] - RD) > 0.2 * RD  # it really converged from elsewhere
    lo, hi = cfg.speed_bounds
    assert np.all(res.u[:, :, 0] >= lo - 1e-6) and np.all(res.u[:, :, 0] <= hi + 1e-6)
    assert np.all(np.abs(res.u[:, :, 1]) <= cfg.max_heading_rate + 1e-6)
    for law in laws:
        assert law.stats.fallbacks_vector_field == 0
        assert law.stats.failures <= 2


@pytest.mark.slow
def test_town_keeps_out_of_buildings_and_apart():
    town = [Building.cuboid((60, 110), (50, 30, 80)), Building.cuboid((150, -100), (40, 40, 90), yaw=0.4),
            Building.cuboid((-60, -120), (60, 25, 70)), Building.cuboid((260, 60), (30, 60, 100)),
            Building.cuboid((0, 0), (20, 20, 30))]  # the last one is low: flown over at 60 m
    cfg = NmpcConfig(standoff_radius=RD, separation_distance=30.0, team_size=3)
    laws = [NmpcStandoffGuidance(cfg, i, buildings=town) for i in range(3)]
    x0 = np.array([[-120.0, 20.0, -1.5, 12.0, 0.0], [-120.0, 55.0, -1.5, 12.0, 0.0], [120.0, -20.0, 1.5, 12.0, 0.0]])
    res = run_kinematic_loop(laws, x0, LoopConfig(dt=0.5, steps=300, target_v=(3.0, 0.5)))
    # sample the straight segments between steps finely
    p = res.x[:, :, :2]
    fine = np.concatenate([p[:-1] + a * (p[1:] - p[:-1]) for a in np.linspace(0, 1, 5)], axis=0).reshape(-1, 2)
    d_min = min(footprint_distance(b, q) for b in town[:4] for q in fine)
    assert d_min > 0.0
    assert res.min_separation() >= 0.9 * cfg.separation_distance
    assert np.abs(res.ranges[-100:] - RD).mean() < 0.05 * RD
    calls = sum(law.stats.calls for law in laws)
    assert sum(law.stats.failures for law in laws) <= 0.05 * calls  # rare, counted, and survived


def _states(t):
    own = OwnState(t=t, p_W=[130.0, 0.0, 60.0], v_W=[0.0, 12.0, 0.0], yaw=np.pi / 2)
    tgt = TargetEstimate(t=t, p_W=[0.0, 0.0], v_W=[2.0, 0.0])
    tm = TeammateState(id=1, t=t, p_W=[-120.0, 0.0, 60.0], v_W=[0.0, -12.0, 0.0])
    return own, tgt, [tm]


def test_injected_failure_falls_back_and_is_counted():
    cfg = NmpcConfig(standoff_radius=RD, fallback_max_shift=3)
    g = NmpcStandoffGuidance(cfg, 0)
    ok = g.command(*_states(0.0), 0.0)
    assert g.stats.failures == 0
    g.inject_failures(2)
    sp1 = g.command(*_states(0.5), 0.5)
    assert g.stats.failures == 1 and g.stats.fallbacks_shifted == 1
    np.testing.assert_allclose([sp1.speed, sp1.heading_rate], g._plan_u[1])  # the plan shifted by one step
    np.testing.assert_allclose(g.planned_path()[:-1], g._plan_x[2:, :2])  # shared plan starts after t = 0.5 s
    g.command(*_states(1.0), 1.0)
    assert g.stats.fallbacks_shifted == 2
    g.inject_failures(1)  # plan now too old (4 steps > fallback_max_shift = 3): vector field
    sp = g.command(*_states(2.0), 2.0)
    assert g.stats.failures == 3 and g.stats.fallbacks_vector_field == 1
    assert isinstance(sp, UnicycleSetpoint) and np.isfinite(sp.speed) and sp.altitude == cfg.planning_altitude
    g.command(*_states(2.5), 2.5)  # recovers: a successful solve, no new failure
    assert g.stats.failures == 3 and g.stats.solves == 5
    assert isinstance(ok, UnicycleSetpoint)


def test_altitude_is_clamped_into_band_and_no_target_loiters():
    cfg = NmpcConfig(altitude=500.0, max_altitude=120.0)
    g = NmpcStandoffGuidance(cfg, 0)
    own, _, _ = _states(0.0)
    sp = g.command(own, None, [], 0.0)
    assert sp.altitude == 120.0
    assert sp.heading_rate == pytest.approx(cfg.nominal_speed / cfg.standoff_radius)


def test_paper_phase_cost_variant():
    """The printed cost (q_d d̃², quartic in the phase error) also converges, less tightly than the chord form."""
    cfg = NmpcConfig(standoff_radius=RD, phase_cost="paper")
    laws = [NmpcStandoffGuidance(cfg, 0), NmpcStandoffGuidance(cfg, 1)]
    x0 = np.array([[150.0, 20.0, 1.5, 12.0, 0.0], [-100.0, -90.0, 0.0, 12.0, 0.0]])
    res = run_kinematic_loop(laws, x0, LoopConfig(dt=0.5, steps=360, target_v=(4.0, 1.0)))
    err_ph = np.degrees(np.abs(wrap_angle(res.phases[-160:, 1] - res.phases[-160:, 0] - np.pi)))
    assert np.abs(res.ranges[-160:] - RD).max() < 0.02 * RD
    assert err_ph.max() < 12.0
    with pytest.raises(ValueError, match="phase_cost"):
        NmpcConfig(phase_cost="paper", team_size=3)


def test_called_faster_than_its_step():
    """Commands at 10 Hz with a 0.5 s prediction step: warm starts and the heading-rate state are interpolated."""
    cfg = NmpcConfig(standoff_radius=RD)
    laws = [NmpcStandoffGuidance(cfg, 0, buildings=())]
    x0 = np.array([[RD + 20.0, 0.0, np.pi / 2, 12.0, 0.0]])
    res = run_kinematic_loop(laws, x0, LoopConfig(dt=0.1, steps=900, target_v=(3.0, 0.0)))
    assert np.abs(res.ranges[-300:, 0] - RD).max() < 0.02 * RD
    assert laws[0].stats.failures <= 0.01 * laws[0].stats.calls and laws[0].stats.fallbacks_vector_field == 0


class _Broken:
    """A fast solver that fails every call the way CasADi reports an evaluation error."""

    def __call__(self, **kwargs):
        raise RuntimeError("evaluation failed")

    def stats(self):
        return {}


@pytest.mark.parametrize("retry", [True, False])
def test_failed_fast_solve_is_retried_with_the_robust_solver(retry):
    g = NmpcStandoffGuidance(NmpcConfig(standoff_radius=RD, robust_retry=retry), 0)
    g.command(*_states(0.0), 0.0)  # cold start (IPOPT) gives a plan to warm-start from
    for tier in g.fast.tiers:  # both SQP tiers
        tier.solver = _Broken()
    sp = g.command(*_states(0.5), 0.5)
    assert g.stats.retries == (1 if retry else 0)
    assert g.stats.failures == (0 if retry else 1) and g.stats.fallbacks_shifted == (0 if retry else 1)
    assert np.isfinite(sp.speed) and np.isfinite(sp.heading_rate)
    if retry:  # the command is the robust solve's first input, not a shifted plan
        np.testing.assert_allclose([sp.speed, sp.heading_rate], g._plan_u[0])
        assert g._plan_t == 0.5


@pytest.mark.parametrize("hessian", ["gauss_newton", "constraint_curvature", "tiered"])
def test_each_hessian_holds_standoff_and_phase(hessian):
    cfg = NmpcConfig(standoff_radius=RD, hessian=hessian)
    laws = [NmpcStandoffGuidance(cfg, 0), NmpcStandoffGuidance(cfg, 1)]
    x0 = np.array([[150.0, 20.0, 1.5, 12.0, 0.0], [-100.0, -90.0, 0.0, 12.0, 0.0]])
    res = run_kinematic_loop(laws, x0, LoopConfig(dt=0.5, steps=240, target_v=(4.0, 1.0)))
    err_ph = np.degrees(np.abs(wrap_angle(res.phases[-80:, 1] - res.phases[-80:, 0] - np.pi)))
    assert np.abs(res.ranges[-80:] - RD).max() < 0.02 * RD and err_ph.max() < 5.0
    assert sum(law.stats.retries for law in laws) == 0
    with pytest.raises(ValueError, match="hessian"):
        NmpcConfig(hessian="bfgs")


def test_unused_constraint_slots_never_bind():
    """Rows of absent teammates and buildings are 1 + s >= 0, not copies of the slack bound s >= 0."""
    far = [Building.cuboid((5000.0, 5000.0), (20, 20, 90)), Building.cuboid((-5000.0, 0.0), (20, 20, 90))]
    g = NmpcStandoffGuidance(NmpcConfig(standoff_radius=RD, max_buildings=3), 0, buildings=far)
    assert g._n_bld == 2
    own, tgt, _ = _states(0.0)
    x0 = g._initial_state(own, 0.0)
    par = g._parameters(x0, own, tgt, [], 0.0)  # no teammate, no building
    w = g._initial_guess(x0, 0.0, tgt, [])
    gv = g._g_fun(x=w, p=par)["g"].reshape(g.config.horizon, -1)[:, 5:]
    np.testing.assert_allclose(gv, 1.0)
    np.testing.assert_allclose(g._feasible_slacks(w, par), 0.0)


def test_warm_start_is_dynamically_consistent_and_shifts_multipliers():
    g = NmpcStandoffGuidance(NmpcConfig(standoff_radius=RD), 0)
    g.command(*_states(0.0), 0.0)  # cold start (IPOPT): active multipliers only
    g.command(*_states(0.5), 0.5)  # warm SQP
    n = g.config.horizon
    w = g._initial_guess(g._plan_x[1], 1.5, *_states(1.5)[1:])  # two steps later: two tail steps rolled out
    X = w[: 5 * n].reshape(n, 5)
    U = w[5 * n: 7 * n].reshape(n, 2)
    np.testing.assert_allclose(X[:-2], g._plan_x[3:])
    for k in (n - 2, n - 1):
        np.testing.assert_allclose(X[k], np.asarray(g._f_d(X[k - 1], U[k])).reshape(-1), atol=1e-12)
    lam_g, lam_x = g._shifted_multipliers(2)
    rows = g._lam_g0.reshape(n, -1)
    np.testing.assert_allclose(lam_g.reshape(n, -1)[: n - 2], rows[2:])
    np.testing.assert_allclose(lam_x[5 * n: 7 * n].reshape(n, 2)[: n - 2], g._lam_x0[5 * n: 7 * n].reshape(n, 2)[2:])


def test_building_slots_only_for_buildings_that_can_be_constrained():
    low = [Building.cuboid((60.0, 110.0), (50, 30, 40))]  # flown over at 60 m (top below 60 − 5 m)
    tall = low + [Building.cuboid((150.0, -100.0), (40, 40, 90))]
    assert NmpcStandoffGuidance(NmpcConfig(max_buildings=4), 0, buildings=low)._n_bld == 0
    assert NmpcStandoffGuidance(NmpcConfig(max_buildings=4), 0, buildings=tall)._n_bld == 1
    assert NmpcStandoffGuidance(NmpcConfig(max_buildings=0), 0, buildings=tall)._n_bld == 0


class _Capped:
    """The Gauss-Newton tier stopped by its iteration cap: runs the real solver, reports the cap."""

    def __init__(self, inner):
        self.inner, self.calls = inner, 0

    def __call__(self, **kwargs):
        self.calls += 1
        return self.inner(**kwargs)

    def stats(self):
        return {**self.inner.stats(), "success": False, "return_status": "Maximum_Iterations_Exceeded"}


def test_tiered_escalates_a_capped_gauss_newton_solve_to_the_curvature_tier():
    g = NmpcStandoffGuidance(NmpcConfig(standoff_radius=RD, hessian="tiered", gauss_newton_max_iter=1), 0)
    g.command(*_states(0.0), 0.0)  # cold start (IPOPT)
    g.command(*_states(0.5), 0.5)  # warm: Gauss-Newton tier, one iteration, from a good guess
    esc = g.stats.escalations
    gauss_newton = g.fast.tiers[0]
    gauss_newton.solver = _Capped(gauss_newton.solver)
    sp = g.command(*_states(1.0), 1.0)
    assert gauss_newton.solver.calls == 1 and g.stats.escalations == esc + 1
    assert g.stats.retries == 0 and g.stats.failures == 0 and g._plan_t == 1.0
    np.testing.assert_allclose([sp.speed, sp.heading_rate], g._plan_u[0])
    assert g.stats.summary()["escalations"] == g.stats.escalations
    g2 = NmpcStandoffGuidance(NmpcConfig(standoff_radius=RD, hessian="gauss_newton"), 0)
    assert len(g2.fast.tiers) == 1  # a single tier: nothing to escalate to


def _looping_warm_start(probe: bool):
    """A UAV on the orbit of a stopped target, flying clockwise against the counter-clockwise orbit at the speed
    floor, warm-started from a plan that loops at the floor speed and full turn rate (the state road_standoff's
    UAVs were found in after the car stopped)."""
    cfg = NmpcConfig(standoff_radius=RD, team_size=2, restart_probe=probe)
    g = NmpcStandoffGuidance(cfg, 0)
    ang, a2 = np.radians(-146.0), np.radians(52.0)
    yaw = ang - np.pi / 2
    own = OwnState(t=0.0, p_W=[RD * np.cos(ang), RD * np.sin(ang), 60.0],
                   v_W=[6 * np.cos(yaw), 6 * np.sin(yaw), 0.0], yaw=yaw)
    tgt = TargetEstimate(t=0.0, p_W=np.zeros(3), v_W=np.zeros(3))
    mate = TeammateState(id=1, t=0.0, p_W=[RD * np.cos(a2), RD * np.sin(a2), 60.0],
                         v_W=[-12 * np.sin(a2), 12 * np.cos(a2), 0.0], yaw=a2 + np.pi / 2)
    n = cfg.horizon
    x = g._initial_state(own, 0.0)
    U = np.tile([cfg.speed_bounds[0], cfg.max_heading_rate], (n, 1))
    X = [x := np.asarray(g._f_d(x, u)).reshape(-1) for u in U]
    g._plan_x, g._plan_u, g._plan_t = np.vstack([g._initial_state(own, 0.0), X]), U, -0.5
    g._w0 = np.concatenate([np.array(X).reshape(-1), U.reshape(-1), np.zeros(n)])
    g._lam_g0, g._lam_x0 = np.zeros(g._n_g), np.zeros(g._lbx.size)
    return g, own, tgt, mate


def test_restart_probe_keeps_the_cheaper_plan():
    costs = {}
    for probe in (False, True):
        g, own, tgt, mate = _looping_warm_start(probe)
        g.command(own, tgt, [mate], 0.0)
        par = g._parameters(g._initial_state(own, 0.0), own, tgt, [mate], 0.0)
        costs[probe] = g._cost(g._w0, par)
        assert g.stats.failures == 0
        if probe:  # the warm solution rode the floor: probed from the vector-field guess, and that plan was cheaper
            assert g.stats.restart_probes == 1 and g.stats.restarts == 1
            assert g.stats.summary()["restarts"] == 1
        else:
            assert np.mean(g._plan_u[:, 0] <= g.config.speed_bounds[0] + 1e-3) >= 0.5 and g.stats.restart_probes == 0
    assert costs[True] < costs[False] - 1e-3 * abs(costs[False])


def test_an_enforced_overrun_falls_back_to_the_previous_plan():
    """A solve that finishes after the time budget is not used, and the fallback shifts the plan of the last
    solve that was (not the late one, which would be stamped with the old time)."""
    import dataclasses

    g = NmpcStandoffGuidance(NmpcConfig(standoff_radius=RD, time_budget_s=60.0), 0)  # a cold first solve is slow
    g.command(*_states(0.0), 0.0)
    first_u, first_x = g._plan_u.copy(), g._plan_x.copy()
    assert g.stats.overruns == 0 and g.stats.failures == 0
    g.config = dataclasses.replace(g.config, time_budget_s=1e-9, enforce_time_budget=True)
    sp = g.command(*_states(0.5), 0.5)
    assert g.stats.overruns == 1 and g.stats.failures == 1 and g.stats.fallbacks_shifted == 1
    np.testing.assert_allclose([sp.speed, sp.heading_rate], first_u[1])
    np.testing.assert_array_equal(g._plan_x, first_x) and np.testing.assert_array_equal(g._plan_u, first_u)
    assert g._plan_t == 0.0
