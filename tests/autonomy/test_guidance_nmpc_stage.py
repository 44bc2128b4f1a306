"""The NMPC's stage-wise form and its Fatrop solver (``NmpcConfig.solver="fatrop"``): the index maps are
permutations and Fatrop reaches the same optimum as IPOPT on the by-kind problem (the closed loop on Fatrop is in
test_guidance_nmpc.py)."""

import numpy as np
import pytest

from autonomy.guidance.nmpc import NmpcStandoffGuidance
from autonomy.guidance.nmpc_config import NmpcConfig
from autonomy.guidance.nmpc_problem import NU, NX
from autonomy.guidance.nmpc_stage import StageLayout
from interfaces.state import OwnState, TargetEstimate, TeammateState
from worlds.geometry import Building

RD = 120.0


@pytest.mark.parametrize("n, n_path", [(2, 0), (5, 1), (20, 4)])
def test_layout_maps_are_permutations(n, n_path):
    lay = StageLayout(n, n_path)
    n_kind = (NX + NU + 1) * n
    assert lay.n_w == n * (NX + NU + 2) + NX + 1
    w_idx, kind_idx, g_idx = lay.w_from_kind(), lay.kind_from_w(), lay.g_from_kind()
    rng = np.random.default_rng(0)
    v = rng.normal(size=n_kind)
    stage = v[np.maximum(w_idx, 0)]
    np.testing.assert_array_equal(stage[kind_idx], v)  # by kind -> stage -> by kind is the identity
    assert np.sum(w_idx < 0) == NX + 1  # only z_0 has no by-kind entry
    assert sorted(set(w_idx[w_idx >= 0])) == list(range(n_kind))
    # every by-kind row once, plus one slack row per step
    assert sorted(g_idx[g_idx >= 0]) == list(range(n * (NX + n_path)))
    assert np.sum(g_idx < 0) == n


def _problem_states():
    own = OwnState(t=0.0, p_W=[130.0, 0.0, 60.0], v_W=[0.0, 12.0, 0.0], yaw=np.pi / 2)
    tgt = TargetEstimate(t=0.0, p_W=[0.0, 0.0], v_W=[2.0, 0.0])
    mate = TeammateState(id=1, t=0.0, p_W=[95.0, 60.0, 60.0], v_W=[-12.0, 0.0, 0.0])  # close: separation binds
    return own, tgt, [mate]


def test_fatrop_reaches_the_ipopt_optimum_with_active_soft_constraints():
    """Same problem, same guess: Fatrop on the stage-wise form and IPOPT (exact Hessian) on the by-kind form agree
    on the plan, the cost and the multipliers' signs; a building and the teammate constrain the plan."""
    town = [Building.cuboid((150.0, 70.0), (30.0, 30.0, 90.0))]
    cfg = NmpcConfig(standoff_radius=RD, separation_distance=40.0, solver="fatrop")
    g = NmpcStandoffGuidance(cfg, 0, buildings=town)
    own, tgt, mates = _problem_states()
    x0 = g._initial_state(own, 0.0)
    par = g._parameters(x0, own, tgt, mates, 0.0)
    w0 = g._initial_guess(x0, 0.0, tgt, mates)
    w0[-cfg.horizon:] = g._feasible_slacks(w0, par)
    args = {"x0": w0, "p": par, "lbx": g._lbx, "ubx": g._ubx, "lbg": g._lbg, "ubg": g._ubg}
    [fatrop], [ipopt] = g.fast.tiers, g.cold.tiers
    fat = fatrop.solver(**args)
    assert fatrop.solver.stats()["success"]
    ref = ipopt.solver(**args)
    assert ipopt.solver.stats()["success"]
    assert float(fat["f"][0]) == pytest.approx(float(ref["f"][0]), rel=1e-5)
    np.testing.assert_allclose(fat["x"], ref["x"], atol=2e-2)
    gv = fat["g"]
    assert np.all(gv >= g._lbg - 1e-6) and np.all(np.where(np.isfinite(g._ubg), gv <= g._ubg + 1e-6, True))
    # the soft rows were really active somewhere (else this test would not exercise the path constraints)
    path = gv.reshape(cfg.horizon, -1)[:, NX:]
    assert path.min() < 1e-4
    np.testing.assert_allclose(fat["lam_g"], ref["lam_g"], atol=1e-2 * max(1.0, np.abs(ref["lam_g"]).max()))
    # bound multipliers too, the slack's among them (its bound sits on the stage state alone)
    np.testing.assert_allclose(fat["lam_x"], ref["lam_x"], atol=1e-2 * max(1.0, np.abs(ref["lam_x"]).max()))
    n = cfg.horizon
    assert np.abs(ref["lam_x"][-n:]).max() > 0.5  # the slack bounds are active here
    np.testing.assert_allclose(fat["lam_x"][-n:], ref["lam_x"][-n:], atol=2e-2)


@pytest.mark.parametrize("field, value", [("fatrop_max_iter", 0), ("fatrop_tol", 0.0), ("solver", "hpipm")])
def test_fatrop_settings_are_checked(field, value):
    with pytest.raises(ValueError, match=field):
        NmpcConfig(**{field: value})
