"""The NMPC's parameter layout (packed by the guidance, unpacked by the problem) and its solver tiers."""

import casadi as ca
import numpy as np
import pytest

from autonomy.guidance.nmpc import NmpcStandoffGuidance
from autonomy.guidance.nmpc_config import NmpcConfig
from autonomy.guidance.nmpc_layout import NX, ParameterLayout
from autonomy.guidance.nmpc_problem import build_problem
from interfaces.state import OwnState, TargetEstimate, TeammateState
from worlds.geometry import Building


def _quantities(rng, lay, n_mates, n_kos):
    n = lay.horizon
    mates = [(float(np.cos(a)), float(np.sin(a)), rng.normal(size=(n, 2))) for a in rng.uniform(0, 6, n_mates)]
    return dict(x0=rng.normal(size=NX), target_position=rng.normal(size=2), target_velocity=rng.normal(size=2),
                teammates=mates, keepouts=[rng.normal(size=6) for _ in range(n_kos)])


@pytest.mark.parametrize("n, m, nb, n_mates, n_kos", [(2, 0, 0, 0, 0), (5, 2, 3, 1, 2), (20, 3, 4, 3, 4)])
def test_pack_then_unpack_is_the_identity_numerically_and_symbolically(n, m, nb, n_mates, n_kos):
    lay = ParameterLayout(n, m, nb)
    q = _quantities(np.random.default_rng(n), lay, n_mates, n_kos)
    p = lay.pack(**q)
    assert p.shape == (lay.size,) and lay.size == NX + 4 + m * (3 + 2 * n) + nb * 7
    P = ca.SX.sym("p", lay.size)
    sym = lay.unpack(P)
    flat = [sym.x0, sym.target_position, sym.target_velocity]
    for tm in sym.teammates:
        flat += [tm.active, tm.cos_phase, tm.sin_phase, ca.vec(tm.plan)]
    flat += sym.keepouts
    evaluated = np.asarray(ca.Function("unpack", [P], [ca.vertcat(*flat)])(p)).reshape(-1)
    for got in (lay.unpack(p), evaluated):
        if isinstance(got, np.ndarray):  # the symbolic unpacking, evaluated at p: the same numbers in order
            np.testing.assert_array_equal(got, np.concatenate(
                [p[lay.x0], p[lay.target_position], p[lay.target_velocity]]
                + [np.r_[p[lay.teammate(j)]] for j in range(m)] + [p[lay.keepout(b)] for b in range(nb)]))
            continue
        np.testing.assert_array_equal(got.x0, q["x0"])
        np.testing.assert_array_equal(got.target_position, q["target_position"])
        np.testing.assert_array_equal(got.target_velocity, q["target_velocity"])
        for j, tm in enumerate(got.teammates):
            if j < n_mates:
                c, s, plan = q["teammates"][j]
                assert (tm.active, tm.cos_phase, tm.sin_phase) == (1.0, c, s)
                np.testing.assert_array_equal(tm.plan, plan.T)  # (2, N): column k is step k + 1
            else:
                assert tm.active == 0.0 and np.all(np.abs(tm.plan) >= 1e5)
        for b, ko in enumerate(got.keepouts):
            if b < n_kos:
                assert ko[0] == 1.0
                np.testing.assert_array_equal(ko[1:], q["keepouts"][b])
            else:
                assert ko[0] == 0.0 and np.all(np.abs(ko[1:3]) >= 1e5)
    with pytest.raises(ValueError, match="slots"):
        lay.pack(**{**q, "keepouts": [np.zeros(6)] * (nb + 1)})


def test_the_problem_reads_a_packed_teammate_where_the_guidance_put_it():
    """The separation row of step k is |p_k − q_k|²/d² − 1 + s_k with q_k the teammate's packed position at k + 1."""
    cfg = NmpcConfig(horizon=4, separation_distance=10.0)
    pb = build_problem(cfg, 1, 0, slack_scale=1.0)
    rng = np.random.default_rng(3)
    plan = rng.normal(scale=30.0, size=(4, 2))
    p = pb.layout.pack(x0=np.zeros(NX), target_position=np.zeros(2), target_velocity=np.zeros(2),
                       teammates=[(1.0, 0.0, plan)])
    X = rng.normal(scale=30.0, size=(4, NX))
    w = np.concatenate([X.reshape(-1), np.zeros(2 * 4), np.zeros(4)])
    g = np.asarray(ca.Function("g", [pb.nlp["x"], pb.nlp["p"]], [pb.nlp["g"]])(w, p)).reshape(4, -1)
    expected = np.sum((X[:, :2] - plan) ** 2, axis=1) / 10.0 ** 2 - 1.0
    np.testing.assert_allclose(g[:, NX], expected, rtol=1e-12)


def test_the_guidance_packs_through_the_layout():
    town = [Building.cuboid((150.0, 70.0), (30.0, 30.0, 90.0))]
    g = NmpcStandoffGuidance(NmpcConfig(team_size=3, max_buildings=2), 0, buildings=town)
    own = OwnState(t=0.0, p_W=[130.0, 0.0, 60.0], v_W=[0.0, 12.0, 0.0], yaw=np.pi / 2)
    tgt = TargetEstimate(t=0.0, p_W=[1.0, 2.0], v_W=[2.0, 0.5])
    mate = TeammateState(id=1, t=0.0, p_W=[-120.0, 0.0, 60.0], v_W=[0.0, -12.0, 0.0])
    x0 = g._initial_state(own, 0.0)
    got = g.layout.unpack(g._parameters(x0, own, tgt, [mate], 0.0))
    assert (g.layout.n_teammates, g.layout.n_keepouts) == (2, 1)
    np.testing.assert_array_equal(got.x0, x0)
    np.testing.assert_array_equal(got.target_velocity, [2.0, 0.5])
    first, second = got.teammates
    phi = g.config.separation
    assert first.active == 1.0 and (first.cos_phase, first.sin_phase) == (np.cos(phi), np.sin(phi))
    np.testing.assert_allclose(first.plan[:, 0], [-120.0, -12.0 * g.config.dt])
    assert second.active == 0.0 and got.keepouts[0][0] == 1.0


@pytest.mark.parametrize("solver, hessian, tiers", [
    ("sqp", "tiered", ["gauss_newton", "constraint_curvature"]), ("sqp", "gauss_newton", ["gauss_newton"]),
    ("sqp", "constraint_curvature", ["constraint_curvature"]), ("fatrop", "tiered", ["fatrop"]),
    ("rti", "tiered", ["gauss_newton", "constraint_curvature"])])
def test_solver_tiers(solver, hessian, tiers):
    g = NmpcStandoffGuidance(NmpcConfig(solver=solver, hessian=hessian, compiled=False), 0)
    assert [t.name for t in g.fast.tiers] == tiers and [t.name for t in g.cold.tiers] == ["ipopt_exact"]
    assert [t.accept_capped for t in g.fast.tiers] == [False] * (len(tiers) - 1) + [True]  # only the last tier
    assert all(t.real_time == (solver == "rti") for t in g.fast.tiers[-1:])
    assert g.cold.tiers[0].keep_active_multipliers and not any(t.keep_active_multipliers for t in g.fast.tiers)
