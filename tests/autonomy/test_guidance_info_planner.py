"""Communication-aware information planner (Liu, Fu & Gao 2018): information and routing building blocks, the search,
and scenario 1 in closed loop on kinematic unicycles (paper speeds: 50 m/s, 30°/s, T_s = 1 s)."""

import numpy as np
import pytest

from autonomy.guidance.infoplan.config import InfoPlannerConfig
from autonomy.guidance.infoplan.guidance import InfoPlannerGuidance
from autonomy.guidance.infoplan.information import radar_information
from autonomy.guidance.infoplan.planner import TeamInfoPlanner, arc_paths
from autonomy.guidance.infoplan.routing import chain_route_probabilities, link_probabilities, mst_route_probabilities
from autonomy.guidance.unicycle import UnicycleParams
from autonomy.sensing.channel import ChannelConfig, minimum_spanning_tree_routes
from interfaces.state import OwnState, TargetEstimate, TeammateState
from simulator.kinematic.infoplan import InfoLoopConfig, fuse_at_base, run_info_loop
from simulator.kinematic.unicycle_loop import LoopConfig, run_kinematic_loop


def test_radar_information_closed_form():
    rng = np.random.default_rng(0)
    d = rng.uniform(-900, 900, size=(20, 2))
    r = np.linalg.norm(d, axis=1)
    info = radar_information(d, 2.0, 0.05)
    np.testing.assert_allclose(np.trace(info, axis1=1, axis2=2), 0.25 + 400.0 / r**2, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.det(info), 1.0 / (4.0 * 0.0025 * r**2), rtol=1e-9)
    u = d / r[:, None]
    np.testing.assert_allclose(np.einsum("ni,nij,nj->n", u, info, u), 0.25, rtol=1e-12)


def test_batched_mst_matches_channel_routes():
    channel = ChannelConfig(block_by_buildings=False)
    rng = np.random.default_rng(4)
    pts = rng.uniform(-1500, 1500, size=(60, 5, 2))
    P = link_probabilities(pts, channel)
    np.testing.assert_allclose(P[0, 0, 1], np.exp(-(np.linalg.norm(pts[0, 0] - pts[0, 1]) / 1000.0) ** 3),
                               rtol=1e-6)
    beta, hops = mst_route_probabilities(P)
    nodes = ["B", "a", "b", "c", "d"]
    for k in range(len(pts)):
        tree = minimum_spanning_tree_routes(nodes, P[k], "B")
        np.testing.assert_allclose(beta[k], [tree.route_probability(n) for n in nodes], rtol=1e-9)
        np.testing.assert_array_equal(hops[k], [tree.hops(n) for n in nodes])
    chain = chain_route_probabilities(P[:1])[0]
    assert chain[3] == pytest.approx(P[0, 1, 0] * P[0, 2, 1] * P[0, 3, 2], rel=1e-12)


def test_arc_paths_are_circles_and_lines():
    p, c = arc_paths(np.array([10.0, -5.0]), 0.3, np.array([[0.0, 0.0], [0.5, 0.5]]), 50.0, 1.0)
    np.testing.assert_allclose(p[0, 1], [10.0 + 100 * np.cos(0.3), -5.0 + 100 * np.sin(0.3)], atol=1e-9)
    centre = np.array([10.0, -5.0]) + 100.0 * np.array([-np.sin(0.3), np.cos(0.3)])  # radius v/ω = 100 m
    np.testing.assert_allclose(np.linalg.norm(p[1] - centre, axis=1), 100.0, rtol=1e-12)
    np.testing.assert_allclose(c[1], [0.8, 1.3], atol=1e-12)


@pytest.mark.parametrize("criterion", ["logdet", "trace"])
def test_coordinate_ascent_reaches_joint_optimum_on_small_problem(criterion):
    """Three heading rates, two steps (9 plans per UAV, 81 team plans): the sequential search never beats the
    exhaustive one and, from the scenario-1 start and a few random ones, reaches its value within 1 %."""
    rng = np.random.default_rng(7)
    small = dict(n_heading_rates=3, horizon=2, criterion=criterion)
    starts = [(np.array([[-400.0, -700.0], [-800.0, 200.0]]), np.deg2rad([45.0, 0.0]))]
    starts += [(rng.uniform(-1200, 0, size=(2, 2)), rng.uniform(-np.pi, np.pi, 2)) for _ in range(4)]
    for p, chi in starts:
        seq = TeamInfoPlanner(InfoPlannerConfig(**small, search="sequential", sweeps=4)).plan(
            p, chi, np.array([-800.0, 0.0]), np.array([9.4, -3.4]))
        joint = TeamInfoPlanner(InfoPlannerConfig(**small, search="joint")).plan(
            p, chi, np.array([-800.0, 0.0]), np.array([9.4, -3.4]))
        assert joint.evaluations == 81
        assert seq.value <= joint.value + 1e-9
        assert seq.value >= joint.value - 0.01 * abs(joint.value)


def test_separation_is_kept():
    """Two UAVs flying head-on 300 m apart: every planned position pair stays d_safe = 100 m apart."""
    planner = TeamInfoPlanner(InfoPlannerConfig(d_safe=100.0))
    plan = planner.plan(np.array([[-150.0, 0.0], [150.0, 0.0]]), np.array([0.0, np.pi]), np.array([0.0, 400.0]),
                        np.zeros(2))
    assert np.linalg.norm(plan.p_W[0] - plan.p_W[1], axis=1).min() >= 100.0


@pytest.fixture(scope="module")
def scenario_1():
    """Scenario 1 for 120 s (the paper stops at 100 s; the new relay needs until about 100 s to take over)."""
    loop = InfoLoopConfig(steps=120)
    runs = {}
    for name, kw in {"team": {}, "no_comm": {"routing": "none"},
                     "literal": {"objective": "own", "criterion": "trace"}}.items():
        cfg = InfoPlannerConfig(**kw)
        runs[name] = (cfg, run_info_loop(cfg, loop, np.random.default_rng(1)))
    return runs


def _roles(res):
    """Tracker = the UAV nearer the target; the other is the relay when the tracker's next hop is that UAV."""
    d_t = np.linalg.norm(res.p_W[1:] - res.target_p_W[1:, None], axis=2)
    tracker = np.argmin(d_t, axis=1)
    relayed = res.parent[np.arange(len(tracker)), tracker] == 1 - tracker
    return tracker, relayed


def test_team_objective_relays_and_swaps_roles(scenario_1):
    _, res = scenario_1["team"]
    tracker, relayed = _roles(res)
    # first phase: A2 (index 1) tracks through A1 as relay
    assert np.mean(tracker[5:60] == 1) > 0.95 and np.mean(relayed[5:60]) > 0.95
    # last phase: roles swapped, A1 tracks through A2
    assert np.mean(tracker[105:] == 0) > 0.95 and np.mean(relayed[105:]) > 0.95
    swaps = np.flatnonzero(np.diff(tracker))
    assert 1 <= len(swaps) <= 3
    # the tracker orbits the target while the relay stays between target and base
    d_t = np.linalg.norm(res.p_W[1:] - res.target_p_W[1:, None], axis=2)
    assert np.median(d_t[5:60, 1]) < 250.0 and np.median(d_t[105:, 0]) < 250.0
    assert res.beta[5:].mean() > 0.8


def test_team_objective_beats_no_communication_baseline(scenario_1):
    """Same trajectories of packet fates drawn 200 times per policy: the base's expected information is larger
    (log det) and its position CRLB √tr(Y⁻¹)_pp smaller with the delivered-information objective."""
    out = {}
    rng = np.random.default_rng(21)
    for name in ("team", "no_comm"):
        cfg, res = scenario_1[name]
        Y_exp = fuse_at_base(res.information, res.beta, cfg)
        xi = (rng.uniform(size=(200, *res.beta.shape)) < res.beta).astype(float)
        Y = fuse_at_base(res.information, xi, cfg)
        std = np.sqrt(np.trace(np.linalg.inv(Y)[..., :2, :2], axis1=-2, axis2=-1)).mean(axis=-1)
        out[name] = (np.linalg.slogdet(Y_exp)[1].mean(), std, res.beta.mean())
    assert out["team"][0] > out["no_comm"][0] + 0.5
    assert out["team"][1].mean() < 0.8 * out["no_comm"][1].mean()
    assert np.mean(out["team"][1] < out["no_comm"][1]) > 0.95  # per packet-fate draw
    assert out["team"][2] > out["no_comm"][2] + 0.2


def test_literal_per_uav_trace_objective_hugs_the_base(scenario_1):
    """The paper's eq. 42 with its noise values: tr I = 0.25 + 400/r² is nearly flat in range, so both UAVs stay
    near the base and the base's position CRLB is worse than with the team objective."""
    _, lit = scenario_1["literal"]
    cfg, team = scenario_1["team"]
    d_b = np.linalg.norm(lit.p_W[20:] - np.asarray(cfg.base_p_W), axis=2)
    d_t = np.linalg.norm(lit.p_W[20:] - lit.target_p_W[20:, None], axis=2)
    assert np.all(np.median(d_b, axis=0) < np.median(d_t, axis=0))
    assert lit.beta.mean() > 0.95
    lit_std = np.sqrt(np.trace(np.linalg.inv(fuse_at_base(lit.information, lit.beta, cfg))[:, :2, :2], axis1=1,
                               axis2=2))
    team_std = np.sqrt(np.trace(np.linalg.inv(fuse_at_base(team.information, team.beta, cfg))[:, :2, :2],
                                axis1=1, axis2=2))
    assert team_std[20:].mean() < 0.7 * lit_std[20:].mean()


def test_guidance_command_is_the_team_plan_row():
    cfg = InfoPlannerConfig()
    p = np.array([[-400.0, -700.0], [-800.0, 200.0], [-600.0, -300.0]])
    chi = np.deg2rad([45.0, 0.0, 90.0])
    P = np.diag([9.0, 9.0, 1.0, 1.0])
    target = TargetEstimate(t=0.0, p_W=[-800.0, 0.0], v_W=[9.4, -3.4], P=P)
    ref = TeamInfoPlanner(cfg).plan(p, chi, target.p_W, target.v_W, np.linalg.inv(P))
    v = 50.0 * np.stack([np.cos(chi), np.sin(chi)], axis=1)
    for i in range(3):
        g = InfoPlannerGuidance(cfg, i)
        own = OwnState(t=0.0, p_W=[*p[i], 60.0], v_W=[*v[i], 0.0], yaw=chi[i])
        mates = [TeammateState(id=j, t=0.0, p_W=[*p[j], 60.0], v_W=[*v[j], 0.0]) for j in range(3) if j != i]
        sp = g.command(own, target, mates, 0.0)
        assert sp.heading_rate == pytest.approx(ref.heading_rates[i, 0], abs=1e-12)
        assert sp.speed == 50.0
        np.testing.assert_allclose(g.planned_path(), ref.p_W[i])


@pytest.mark.parametrize("age_steps", [0.0, 0.5, 1.0, 2.0])
def test_an_old_teammate_state_is_brought_forward_along_its_shared_plan(age_steps):
    cfg = InfoPlannerConfig()
    rates = np.array([[0.3, -0.2, 0.1]])
    p0, chi0 = np.array([-600.0, -300.0]), 0.7
    plan, courses = arc_paths(p0, chi0, rates, cfg.speed, cfg.dt)  # what the teammate planned at t = 4
    mate = TeammateState(id=1, t=4.0, p_W=[*p0, 60.0], v_W=[50 * np.cos(chi0), 50 * np.sin(chi0), 0.0],
                         plan_p_W=plan[0], plan_dt=cfg.dt)
    p, chi = InfoPlannerGuidance(cfg, 0)._teammate_now(mate, 4.0 + age_steps * cfg.dt)
    k = int(age_steps)
    if age_steps == k:  # at a plan step: its planned position and the course at the end of that arc, exactly
        np.testing.assert_allclose(p, p0 if k == 0 else plan[0, k - 1], atol=1e-9)
        assert chi == pytest.approx(chi0 if k == 0 else courses[0, k - 1], abs=1e-9)
    else:  # halfway along an arc: the chord's midpoint, half the arc's turn
        np.testing.assert_allclose(p, 0.5 * (p0 + plan[0, 0]), atol=1e-9)
        assert chi == pytest.approx(chi0 + 0.5 * rates[0, 0] * cfg.dt, abs=1e-9)
    stale = TeammateState(id=1, t=4.0, p_W=[*p0, 60.0], v_W=[30.0, -40.0, 0.0])  # no plan: straight on
    p, chi = InfoPlannerGuidance(cfg, 0)._teammate_now(stale, 4.0 + age_steps)
    np.testing.assert_allclose(p, p0 + age_steps * np.array([30.0, -40.0]), atol=1e-9)
    assert chi == pytest.approx(np.arctan2(-40.0, 30.0))


def test_guidance_flies_in_the_kinematic_loop():
    cfg = InfoPlannerConfig(base_p_W=(0.0, 0.0), speed=15.0, max_heading_rate=0.5, d_safe=30.0)
    laws = [InfoPlannerGuidance(cfg, i) for i in range(2)]
    x0 = np.array([[50.0, 0.0, 0.0, 15.0, 0.0], [0.0, 80.0, 1.0, 15.0, 0.0]])
    res = run_kinematic_loop(laws, x0, LoopConfig(dt=1.0, steps=40, target_p0=(400.0, 300.0), target_v=(-2.0, 0.0),
                                                  plant=UnicycleParams(tau_v=0.0, tau_omega=0.0)))
    assert np.all(np.abs(res.u[:, :, 1]) <= 0.5 + 1e-12)
    assert res.min_separation() > 25.0
    assert res.ranges[-10:].min() < 0.5 * res.ranges[0].max()  # someone went to look at the target


@pytest.mark.parametrize("kw", [{}, {"criterion": "trace", "objective": "own"}, {"routing": "chain"},
                                {"routing": "none"}])
def test_evaluate_with_one_varying_uav_gives_the_same_numbers(kw):
    """The sequential search's shortcut (links and information of the fixed UAVs computed once) changes no bit."""
    rng = np.random.default_rng(3)
    planner = TeamInfoPlanner(InfoPlannerConfig(**kw))
    n = 4
    p, chi = rng.uniform(-1000, 1000, (n, 2)), rng.uniform(-3, 3, n)
    cand = np.stack([arc_paths(p[i], chi[i], planner.candidate_rates, 50.0, 1.0)[0] for i in range(n)])
    choice = rng.integers(0, len(planner.candidate_rates), n)
    tgt = np.array([[-800.0, 0.0], [-790.0, -3.0], [-780.0, -6.0]])
    Y0 = planner.config.default_prior_information()
    for i in range(n):
        team = np.array(cand[np.arange(n), choice][None].repeat(len(cand[i]), axis=0))
        team[:, i] = cand[i]
        w = rng.uniform(0.0, 1.0, n)
        full, fast = planner.evaluate(team, tgt, Y0, w), planner.evaluate(team, tgt, Y0, w, vary=i)
        assert np.array_equal(full[0], fast[0]) and np.array_equal(full[1], fast[1])


def test_per_uav_estimates_steer_each_uav_by_its_own():
    """With one estimate per UAV, UAV i scores its candidates on its own predicted track: identical estimates give the
    shared plan; a UAV told the target lies elsewhere plans differently."""
    cfg = InfoPlannerConfig(objective="own", criterion="trace", routing="none", d_safe=0.0)
    p, chi = np.array([[0.0, 0.0], [0.0, 500.0]]), np.zeros(2)
    tgt, v = np.array([60.0, 0.0]), np.zeros(2)
    shared = TeamInfoPlanner(cfg).plan(p, chi, tgt, v)
    same = TeamInfoPlanner(cfg).plan(p, chi, np.array([tgt, tgt]), np.zeros((2, 2)))
    np.testing.assert_array_equal(shared.heading_rates, same.heading_rates)
    moved = TeamInfoPlanner(cfg).plan(p, chi, np.array([[-60.0, 0.0], tgt]), np.zeros((2, 2)))
    assert not np.array_equal(moved.heading_rates[0], shared.heading_rates[0])
    np.testing.assert_array_equal(moved.heading_rates[1], shared.heading_rates[1])
    with pytest.raises(ValueError, match="one row per UAV \\(2\\), got 3 positions"):
        TeamInfoPlanner(cfg).plan(p, chi, np.zeros((3, 2)), np.zeros((3, 2)))
    with pytest.raises(ValueError, match="per-UAV target estimates need the sequential search"):
        TeamInfoPlanner(InfoPlannerConfig(search="joint")).plan(p, chi, np.array([tgt, tgt]), np.zeros((2, 2)))


def test_evaluate_with_a_varying_uav_needs_the_candidates_in_order():
    planner = TeamInfoPlanner(InfoPlannerConfig())
    paths = np.zeros((5, 2, 3, 2))
    with pytest.raises(ValueError, match="needs the 343 candidate paths of that UAV in candidate order, got 5"):
        planner.evaluate(paths, np.zeros((3, 2)), planner.config.default_prior_information(), vary=0)
