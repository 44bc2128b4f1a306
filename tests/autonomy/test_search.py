"""Set-membership search control: unicycle rollout, cost terms, sequential decisions, guidance (the kinematic
missions are tested in tests/simulator/kinematic/test_search_mission.py)."""

import numpy as np
import pytest
import shapely

from autonomy.estimation.setmem import polygons as pg
from autonomy.estimation.setmem.estimator import SetEstimate, SetMembershipConfig, SetMembershipEstimator
from autonomy.guidance.search.guidance import SetMembershipSearchGuidance, teammate_path
from autonomy.guidance.search.planner import SearchConfig, SearchPlanner, decision_order, rollout
from autonomy.guidance.search.regions import PrismViewRegion
from autonomy.sensing.box_sensor import BoxSensor, BoxSensorConfig
from autonomy.sensing.scene import SensorPose
from interfaces.setpoints import VelocitySetpoint
from interfaces.state import OwnState, TeammateState
from worlds.geometry import Building

AREA = shapely.box(0.0, 0.0, 500.0, 500.0)
CFG = SearchConfig()
FOOT = np.sqrt(2) * 100 * np.tan(np.pi / 8)


def planner(buildings=(), cfg=CFG):
    free = AREA if not buildings else shapely.difference(AREA, shapely.union_all(
        [shapely.Polygon(b.footprint) for b in buildings]))
    return SearchPlanner(cfg, PrismViewRegion(BoxSensorConfig(), buildings), free, buildings, footprint_radius=FOOT)


def test_config_validation():
    with pytest.raises(ValueError, match="n_controls"):
        SearchConfig(n_controls=4)
    with pytest.raises(ValueError, match="alpha_s1 - alpha_s2 >= d_col"):
        SearchConfig(alpha_s1=6.0, alpha_s2=3.0, d_col=5.0)


def test_rollout_holds_the_turn():
    p = rollout(np.array([0.0, 0.0]), 0.0, np.pi / 2, SearchConfig(speed=10.0, dt=1.0, horizon=2))
    np.testing.assert_allclose(p.yaw, [np.pi / 2, np.pi])
    np.testing.assert_allclose(p.p_xy, [[0.0, 10.0], [-10.0, 10.0]], atol=1e-12)


def test_decision_order_per_component_breadth_first():
    A = np.zeros((5, 5), bool)
    for i, j in [(0, 3), (3, 1), (2, 4)]:
        A[i, j] = A[j, i] = True
    assert decision_order(A) == [0, 3, 1, 2, 4]


def test_obstacle_risk_shape():
    b = Building.cuboid((250, 250), (40, 40, 100))
    pl = planner([b])
    d = np.array([CFG.alpha_s1, 60.0, CFG.d_col])
    r = pl.obstacle_risk(np.column_stack([270.0 + d, np.full(3, 250.0)]))
    assert r[0] == pytest.approx(0.5)
    assert r[1] < 1e-6
    assert r[2] == pytest.approx(0.5 * (1 - np.tanh((CFG.d_col - CFG.alpha_s1) / CFG.alpha_s2)))
    assert r[2] > 0.95


def test_turns_towards_the_unexplored_side():
    """Xbar is the west half only; a UAV flying north on the border turns west (u > 0)."""
    pl = planner()
    est = SetEstimate(t=0.0, X=pg.EMPTY, Xbar=shapely.box(0, 0, 230, 500))
    dec = pl.decide(np.array([260.0, 100.0]), np.pi / 2, est)
    assert dec.u > 0
    assert dec.terms["J_s"] == 0.0
    # mirrored: Xbar on the east half, it turns east
    est_e = SetEstimate(t=0.0, X=pg.EMPTY, Xbar=shapely.box(290, 0, 500, 500))
    assert pl.decide(np.array([260.0, 100.0]), np.pi / 2, est_e).u < 0


def test_distance_term_pulls_towards_a_remote_set():
    """Everything near is explored; only a far patch of Xbar remains to the east: the UAV turns towards it."""
    pl = planner()
    est = SetEstimate(t=0.0, X=pg.EMPTY, Xbar=shapely.box(450, 200, 480, 230))
    dec = pl.decide(np.array([100.0, 215.0]), np.pi / 2, est)  # heading north, patch due east
    assert dec.u < 0
    assert dec.terms["J_d"] > 0


@pytest.mark.parametrize(("choice", "west"), [("near_large", False), ("paper", True)])
def test_component_choice_of_the_distance_term(choice, west):
    """A small patch of X 148 m west, a large one 200 m east, both out of the footprints' reach: the default pulls
    towards the large one (argmin d/φ), the paper's printed formula (argmin φ·d) towards the small one."""
    pl = planner(cfg=SearchConfig(component_choice=choice))
    X = shapely.union_all([shapely.box(100, 248, 104, 252), shapely.box(450, 225, 500, 275)])
    dec = pl.decide(np.array([250.0, 250.0]), np.pi / 2, SetEstimate(t=0.0, X=X, Xbar=pg.EMPTY))
    assert (dec.u > 0) == west and dec.u != 0
    with pytest.raises(ValueError, match=r"component_choice must be near_large\|paper, got 'x'"):
        SearchConfig(component_choice="x")


def test_avoids_an_obstacle_ahead():
    b = Building.cuboid((250, 300), (60, 60, 100))
    pl = planner([b])
    est = SetEstimate(t=0.0, X=pg.EMPTY, Xbar=shapely.difference(AREA, shapely.Polygon(b.footprint)))
    p0 = np.array([250.0, 235.0])  # 35 m south of the wall, heading north at 16.7 m/s
    dec = pl.decide(p0, np.pi / 2, est)
    assert dec.u != 0.0
    assert float(shapely.Polygon(b.footprint).distance(shapely.Point(dec.path.p_xy[-1]))) > CFG.alpha_s1


def test_second_uav_accounts_for_the_first():
    """Two UAVs at the same place: the one deciding second does not pick the region the first will observe."""
    pl = planner()
    est = SetEstimate(t=0.0, X=pg.EMPTY, Xbar=AREA)
    p0 = np.array([250.0, 100.0])
    first = pl.decide(p0, np.pi / 2, est)
    second = pl.decide(p0, np.pi / 2, est, [first.path])
    assert second.u != first.u
    assert abs(second.u - first.u) >= CFG.max_turn / 2
    decisions = pl.plan_team(np.array([p0, p0]), np.array([np.pi / 2, np.pi / 2]), [est, est],
                             np.array([[False, True], [True, False]]))
    assert decisions[0].u == first.u and decisions[1].u == second.u
    # unlinked UAVs do not know each other's plans and decide alike
    alone = pl.plan_team(np.array([p0, p0]), np.array([np.pi / 2, np.pi / 2]), [est, est], np.zeros((2, 2), bool))
    assert alone[0].u == alone[1].u


def test_prism_region_matches_the_sensor():
    rng = np.random.default_rng(0)
    bs = [Building.cuboid((200, 200), (40, 60, 100)), Building.cuboid((300, 260), (50, 30, 100), yaw=0.4)]
    sensor = BoxSensor(BoxSensorConfig(), bs)
    fast = PrismViewRegion(BoxSensorConfig(), bs)
    for _ in range(20):
        p = rng.uniform(150, 350, 2)
        yaw = rng.uniform(-np.pi, np.pi)
        pose = SensorPose(p_W=np.array([*p, 100.0]), q_WB=np.array([0, 0, np.sin(yaw / 2), np.cos(yaw / 2)]))
        exact, approx = sensor.observed_region(pose), fast.observed_region(pose)
        assert shapely.symmetric_difference(exact, approx).area <= 0.01 * 82.84**2


def test_guidance_command_and_shared_plan():
    est = SetMembershipEstimator(SetMembershipConfig(), AREA)
    pl = planner()
    g = SetMembershipSearchGuidance(pl, est)
    own = OwnState(t=3.0, p_W=np.array([250.0, 100.0, 95.0]), v_W=np.array([0.0, 16.0, 0.0]), yaw=np.pi / 2)
    sp = g.command(own, None, [], 3.0)
    assert isinstance(sp, VelocitySetpoint)
    assert np.hypot(*sp.v_W[:2]) == pytest.approx(CFG.speed)
    assert sp.v_W[2] == pytest.approx(CFG.altitude_gain * 5.0)
    assert sp.yaw == pytest.approx(np.pi / 2 + g.last_decision.u)
    plan = g.planned_path()
    assert plan.shape == (2, 2)
    # a teammate that already decided this step, at the same place, shares its plan: this UAV picks another turn
    tm = TeammateState(id=1, t=3.0, p_W=own.p_W, v_W=own.v_W, yaw=own.yaw, plan_p_W=plan)
    np.testing.assert_allclose(teammate_path(tm).p_xy, plan)
    g2 = SetMembershipSearchGuidance(pl, est)
    g2.command(own, None, [tm], 3.0)
    assert g2.last_decision.u != g.last_decision.u
    # a stale plan (stamped at an earlier step) is ignored
    stale = TeammateState(id=1, t=2.0, p_W=own.p_W, v_W=own.v_W, yaw=own.yaw, plan_p_W=plan)
    g3 = SetMembershipSearchGuidance(pl, est)
    g3.command(own, None, [stale], 3.0)
    assert g3.last_decision.u == g.last_decision.u
    assert g.stats.calls == 1 and len(g.stats.solve_times_s) == 1


@pytest.mark.parametrize("u_deg", [0.0, 10.0, -20.0])
def test_lag_compensated_setpoint_ends_the_step_on_the_chord(u_deg):
    """A first-order velocity lag (tau) driven by the compensated set-point for one step moves the UAV by exactly the
    planner's chord V T (cos(psi + u), sin(psi + u)), from a velocity along the old heading; without compensation
    it falls short of a turn."""
    est = SetMembershipEstimator(SetMembershipConfig(), AREA)
    tau, T = 0.5, CFG.dt
    own = OwnState(t=3.0, p_W=np.array([250.0, 100.0, 100.0]), v_W=np.array([0.0, CFG.speed, 0.0]), yaw=np.pi / 2)

    def step(g):
        g.planner.decide = lambda p, h, e, d: _decision_with(np.radians(u_deg), p, h)
        v_c = g.command(own, None, [], 3.0).v_W[:2]
        t = np.linspace(0.0, T, 2001)  # v(t) = v_c + (v0 - v_c) exp(-t / tau), integrated by trapezoids
        v = v_c[None] + (own.v_W[:2] - v_c)[None] * np.exp(-t / tau)[:, None]
        return np.trapezoid(v, t, axis=0), v_c

    chord = CFG.speed * T * np.array([np.cos(np.pi / 2 + np.radians(u_deg)), np.sin(np.pi / 2 + np.radians(u_deg))])
    moved, v_c = step(SetMembershipSearchGuidance(planner(), est, velocity_lag_s=tau))
    np.testing.assert_allclose(moved, chord, atol=1e-5)
    assert np.hypot(*v_c) >= CFG.speed - 1e-9
    plain, _ = step(SetMembershipSearchGuidance(planner(), est))
    assert np.hypot(*(plain - chord)) > (0.0 if u_deg == 0 else 0.5) - 1e-9
    capped = SetMembershipSearchGuidance(planner(), est, velocity_lag_s=tau, max_speed=CFG.speed)
    assert np.hypot(*step(capped)[1]) <= CFG.speed + 1e-9


def _decision_with(u, p, heading):
    from autonomy.guidance.search.planner import SearchDecision, rollout

    path = rollout(np.asarray(p, float), heading, u, CFG)
    return SearchDecision(u=u, path=path, cost=0.0, terms={}, costs=np.zeros(1), controls=np.array([u]),
                          admissible=np.ones(1, bool))
