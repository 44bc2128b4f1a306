"""Fast MPC: interior point against a reference QP solver, and separation in a paper-000-like 3-UAV scenario
(paper geometry around (4500, −8); quadrotor speeds: v ≤ 18 m/s, |ω| ≤ 2 rad/s; D = 10 m)."""

import casadi as ca
import numpy as np
import pytest

from autonomy.guidance.fast_mpc import FastMpcConfig, FastMpcGuidance, build_fast_mpc_qp
from autonomy.guidance.pdip import PdipOptions, solve_qp_pdip
from autonomy.guidance.unicycle import UnicycleParams
from simulator.kinematic.unicycle_loop import LoopConfig, run_kinematic_loop


def _reference_cost(qp):
    A = np.vstack([qp.C, qp.P])
    lba = np.concatenate([qp.b, np.full(qp.m.shape[0], -np.inf)])
    uba = np.concatenate([qp.b, qp.m])
    solver = ca.conic("ref", "qpoases", {"h": ca.DM(qp.H).sparsity(), "a": ca.DM(A).sparsity()},
                      {"printLevel": "none"})
    sol = solver(h=qp.H, g=qp.f, a=A, lba=lba, uba=uba)
    assert solver.stats()["success"]
    return float(sol["cost"])


@pytest.mark.parametrize("mode", ["buffered", "paper"])
def test_interior_point_matches_reference_qp(mode):
    rng = np.random.default_rng(11)
    cfg = FastMpcConfig(separation_mode=mode, omega_max=2.0)
    opts = PdipOptions(max_iter=30)
    for _ in range(12):
        x0 = np.array([*rng.uniform(-50, 50, 2), rng.uniform(-np.pi, np.pi)])
        u_ref = np.column_stack([rng.uniform(1, 18, cfg.horizon), rng.uniform(-1, 1, cfg.horizon)])
        k = np.arange(1, cfg.horizon + 1)
        tgt = rng.uniform(-60, 60, 2) + np.outer(k, rng.uniform(-4, 4, 2))
        others = [x0[:2] + rng.uniform(-40, 40, 2) + np.outer(k, rng.uniform(-6, 6, 2)) for _ in range(2)]
        qp = build_fast_mpc_qp(cfg, x0, u_ref, tgt, others)
        sol = solve_qp_pdip(qp.H, qp.f, qp.C, qp.b, qp.P, qp.m, opts)
        ref = _reference_cost(qp)
        assert abs(sol.objective - ref) <= 1e-3 * abs(ref)
        assert sol.iterations <= opts.max_iter
        assert np.max(np.abs(qp.C @ sol.z - qp.b)) < 1e-6
        assert np.all(qp.P @ sol.z <= qp.m + 1e-6)


def test_pdip_closed_form_box_qp():
    """min ½|z − a|² s.t. z ≤ 1, z1 + z2 = 1 has a closed-form solution."""
    a = np.array([3.0, -1.0])
    sol = solve_qp_pdip(np.eye(2), -a, np.array([[1.0, 1.0]]), np.array([1.0]), np.eye(2), np.ones(2))
    # unconstrained projection onto z1 + z2 = 1: (2.5, -1.5) → z1 capped at 1, z2 = 0
    np.testing.assert_allclose(sol.z, [1.0, 0.0], atol=1e-7)
    assert sol.converged


@pytest.mark.parametrize("mode", ["buffered", "paper"])
def test_separation_never_violated_three_uavs(mode):
    cfg = FastMpcConfig(separation_mode=mode, v_max=18.0, omega_max=2.0, separation_distance=10.0)
    laws = [FastMpcGuidance(cfg) for _ in range(3)]
    x0 = np.array([[4510, -8, 2, 0, 0], [4490, -8, 2, 0, 0], [4500, 5, 2, 0, 0]], dtype=float)
    loop = LoopConfig(dt=0.5, steps=160, target_p0=(4500.0, -8.0), target_v=(3.0, 1.0),
                      plant=UnicycleParams(tau_v=0.0, tau_omega=0.0))
    res = run_kinematic_loop(laws, x0, loop, altitude=100.0)
    assert res.min_separation() >= cfg.separation_distance
    assert np.all(res.u[:, :, 0] >= cfg.v_min - 1e-9) and np.all(res.u[:, :, 0] <= cfg.v_max + 1e-9)
    assert np.all(np.abs(res.u[:, :, 1]) <= cfg.omega_max + 1e-9)
    # they follow the target (crowding each other around it): within a few tens of metres at the end
    assert np.all(res.ranges[-40:].mean(axis=0) < 40.0)
    assert min(np.min(np.linalg.norm(res.x[:, i, :2] - res.x[:, j, :2], axis=1))
               for i in range(3) for j in range(i + 1, 3)) < 25.0  # the constraint was active
