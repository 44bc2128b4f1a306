"""Interior point (autonomy.guidance.pdip): the envelope-Cholesky iteration against a dense numpy transcription of
the same algorithm (module docstring), on random dense QPs, fast-MPC QPs and degenerate cases, with infeasible warm
starts; and invariance under reordering variables and rows (which moves the solver between its banded and dense
regimes)."""

import subprocess
import sys

import numpy as np
import pytest

from autonomy.guidance.fast_mpc import FastMpcConfig, build_fast_mpc_qp, euler_rollout
from autonomy.guidance.pdip import PdipOptions, solve_qp_pdip

_TOL = 1e-9
_TOL_MPC = 1e-7  # the MPC QPs are ill-conditioned (weights 1e-4 … 1e4, δ = 1e-8): LAPACK's dense Cholesky differs
# from the numpy transcription by up to 3e-8 after 8 iterations, the same spread as the envelope factorisation


def _dense_pdip(H, f, C, b, P, m, iters, z0=None, delta=1e-8, slack_floor=1.0, frac=0.99):
    """The module docstring's iteration with dense numpy solves (no early exit): (z, λ, γ, s)."""
    n, ne, ni = H.shape[0], C.shape[0], P.shape[0]
    z = np.zeros(n) if z0 is None else np.array(z0, dtype=float)
    lam, gam, s = np.zeros(ne), np.ones(ni), np.maximum(m - P @ z, slack_floor)
    Hr = H + delta * np.eye(n)

    def max_step(v, dv):
        neg = dv < 0
        return float(np.min(-v[neg] / dv[neg])) if np.any(neg) else np.inf

    for _ in range(iters):
        r_z, r_l, r_g = Hr @ z + f + C.T @ lam + P.T @ gam, C @ z - b, P @ z + s - m
        mu = float(gam @ s) / max(ni, 1)
        d = gam / s
        Phi = Hr + (P.T * d) @ P
        try:
            np.linalg.cholesky(Phi)
            Y = C @ np.linalg.solve(Phi, C.T)
            np.linalg.cholesky(Y)
        except np.linalg.LinAlgError:
            Phi = Phi + 1e-10 * np.max(np.diag(Phi)) * np.eye(n)
            Y = C @ np.linalg.solve(Phi, C.T)
            Y = Y + 1e-12 * np.max(np.diag(Y)) * np.eye(ne)

        def newton(r_s):
            q = (gam * r_g - r_s) / s
            rho = -r_z - P.T @ q
            dl = np.linalg.solve(Y, C @ np.linalg.solve(Phi, rho) + r_l) if ne else np.zeros(0)
            dz = np.linalg.solve(Phi, rho - C.T @ dl)
            return dz, dl, q + d * (P @ dz), -r_g - P @ dz

        dz, dl, dg, ds = newton(gam * s)
        a_aff = min(1.0, max_step(s, ds), max_step(gam, dg))
        sigma = (float((gam + a_aff * dg) @ (s + a_aff * ds)) / max(ni, 1) / mu) ** 3 if mu > 0 else 0.0
        dz, dl, dg, ds = newton(gam * s + ds * dg - sigma * mu)
        alpha = min(1.0, frac * min(max_step(s, ds), max_step(gam, dg)))
        z, lam, gam, s = z + alpha * dz, lam + alpha * dl, gam + alpha * dg, s + alpha * ds
    return z, lam, gam, s


def _close(a, b, tol=_TOL):
    return np.max(np.abs(a - b), initial=0.0) <= tol * max(1.0, np.max(np.abs(b), initial=0.0))


def _random_qp(rng, n, ne, ni, rank=None):
    A = rng.normal(size=(rank or n, n))
    H = A.T @ A + np.diag(rng.uniform(0, 1, n))
    C = rng.normal(size=(ne, n))
    P = rng.normal(size=(ni, n))
    z_feas = rng.normal(size=n)
    return H, rng.normal(size=n) * 5, C, C @ z_feas, P, P @ z_feas + rng.uniform(0, 1, ni)


def _mpc_qp(rng, mode, teammates):
    cfg = FastMpcConfig(separation_mode=mode, omega_max=2.0)
    M = cfg.horizon
    x0 = np.array([*rng.uniform(-50, 50, 2), rng.uniform(-np.pi, np.pi)])
    u_ref = np.column_stack([rng.uniform(1, 18, M), rng.uniform(-1, 1, M)])
    k = np.arange(1, M + 1)
    tgt = rng.uniform(-60, 60, 2) + np.outer(k, rng.uniform(-4, 4, 2))
    others = [x0[:2] + rng.uniform(-40, 40, 2) + np.outer(k, rng.uniform(-6, 6, 2)) for _ in range(teammates)]
    if teammates:
        others[0] = euler_rollout(x0, u_ref, cfg.dt)[1:, :2]  # coincident with the reference: the sideways push
    qp = build_fast_mpc_qp(cfg, x0, u_ref, tgt, others)
    return qp.H, qp.f, qp.C, qp.b, qp.P, qp.m


def _cases():
    rng = np.random.default_rng(5)
    cases = []
    for i in range(6):
        cases.append((f"dense{i}", _random_qp(rng, 12, 4, 15, rank=6 if i % 2 else None)))
    for mode in ("buffered", "paper"):
        for tm in (0, 1, 3):
            cases.append((f"mpc-{mode}-{tm}", _mpc_qp(rng, mode, tm)))
    H, f, C, b, P, m = _random_qp(rng, 8, 3, 6)
    cases.append(("duplicate-rows", (H, f, C, b, np.vstack([P, P[:2], np.zeros((1, 8))]),
                                     np.concatenate([m, m[:2], [1.0]]))))
    H[5:, :], H[:, 5:] = 0.0, 0.0  # free variables with zero curvature held only by δ and the constraints
    cases.append(("singular-H", (H, f, C, b, P, m)))
    cases.append(("no-equalities", (H + np.eye(8), f, C[:0], b[:0], P, m)))
    cases.append(("no-inequalities", (H + np.eye(8), f, C, b, P[:0], m[:0])))
    return cases


_CASES = _cases()


@pytest.mark.parametrize("warm", ["zero", "infeasible"])
@pytest.mark.parametrize("iters", [1, 3, 8])
@pytest.mark.parametrize("case", _CASES, ids=[c[0] for c in _CASES])
def test_iterates_match_dense_transcription(case, iters, warm):
    H, f, C, b, P, m = case[1]
    z0 = None if warm == "zero" else np.random.default_rng(iters).normal(scale=100.0, size=H.shape[0])
    sol = solve_qp_pdip(H, f, C, b, P, m, PdipOptions(max_iter=iters, tol=1e-300), z0=z0)
    z, lam, gam, s = _dense_pdip(H, f, C, b, P, m, iters, z0=z0)
    assert sol.iterations == iters
    tol = _TOL_MPC if case[0].startswith("mpc") else _TOL
    for got, ref in ((sol.z, z), (sol.lam, lam), (sol.gam, gam), (sol.s, s)):
        assert _close(got, ref, tol)


@pytest.mark.parametrize("case", _CASES, ids=[c[0] for c in _CASES])
def test_solution_invariant_under_reordering(case):
    """Random orders of variables and rows defeat the stage ordering (dense envelopes): same primal answer.

    (Some of these QPs stall in the multipliers short of ``tol``, in either order and as they did with LAPACK's dense
    factorisation, while z has converged: only the primal solution is compared.)"""
    H, f, C, b, P, m = case[1]
    rng = np.random.default_rng(0)
    pz, pe, pi = rng.permutation(H.shape[0]), rng.permutation(C.shape[0]), rng.permutation(P.shape[0])
    opts = PdipOptions(max_iter=100)
    a = solve_qp_pdip(H, f, C, b, P, m, opts)
    p = solve_qp_pdip(H[np.ix_(pz, pz)], f[pz], C[np.ix_(pe, pz)], b[pe], P[np.ix_(pi, pz)], m[pi], opts)
    assert _close(p.z, a.z[pz], _TOL_MPC)
    assert abs(p.objective - a.objective) <= _TOL * max(1.0, abs(a.objective))
    assert np.max(np.abs(C @ a.z - b), initial=0.0) < 1e-7
    assert np.all(P @ a.z <= m + 1e-7)


def test_rank_deficient_equalities_solve():
    """Duplicated equality rows make C Φ⁻¹ Cᵀ singular: the fallback shift still yields a feasible solution."""
    H, f, C, b, P, m = _random_qp(np.random.default_rng(2), 6, 2, 4)
    sol = solve_qp_pdip(H, f, np.vstack([C, C[:1]]), np.concatenate([b, b[:1]]), P, m)
    assert np.max(np.abs(C @ sol.z - b)) < 1e-6
    assert np.all(P @ sol.z <= m + 1e-6)



def test_all_zero_equalities_raise():
    """C = 0: C Φ⁻¹ Cᵀ = 0 and its fallback shift is 0 too."""
    H, f, C, b, P, m = _random_qp(np.random.default_rng(3), 6, 1, 4)
    with pytest.raises(np.linalg.LinAlgError):
        solve_qp_pdip(H, f, np.zeros((1, 6)), np.zeros(1), P, m)


def test_compiled_iteration_is_cached():
    """A fresh process loads the compiled iteration from numba's cache (written by this one) instead of compiling."""
    solve_qp_pdip(np.eye(2), np.ones(2), np.ones((1, 2)), np.ones(1), np.eye(2), np.ones(2))
    code = ("import numpy as np\n"
            "from autonomy.guidance import pdip\n"
            "r = pdip.solve_qp_pdip(np.eye(2), -np.array([3.0, -1.0]), np.ones((1, 2)), np.ones(1), np.eye(2), "
            "np.ones(2))\n"
            "st = pdip._pdip.stats\n"
            "print(sum(st.cache_hits.values()), sum(st.cache_misses.values()), *r.z)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=300)
    hits, misses, z1, z2 = out.stdout.split()
    assert (int(hits), int(misses)) == (1, 0)
    assert float(z1) == pytest.approx(1.0, abs=1e-7) and float(z2) == pytest.approx(0.0, abs=1e-7)
