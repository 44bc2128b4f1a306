"""Primal-dual interior-point solver for the small QPs of the fast MPC (Hu et al. 2018, section IV-C).

Problem::

    min ½ zᵀ H z + fᵀ z   s.t.   C z = b,   P z ≤ m

with slacks s = m − P z ≥ 0, multipliers λ (equalities) and γ ≥ 0 (inequalities). Each iteration solves the Newton
system of the perturbed KKT conditions

    r_z = H z + f + Cᵀ λ + Pᵀ γ,   r_λ = C z − b,   r_γ = P z + s − m,   r_s = γ ∘ s − σ μ 1,   μ = γᵀ s / n_i

by block elimination (paper eq. 37): Δs = −r_γ − P Δz, Δγ = S⁻¹(Γ r_γ − r_s) + S⁻¹ Γ P Δz and

    Φ = H + δ I + Pᵀ S⁻¹ Γ P,   (C Φ⁻¹ Cᵀ) Δλ = C Φ⁻¹ ρ + r_λ,   Φ Δz = ρ − Cᵀ Δλ,   ρ = −r_z − Pᵀ S⁻¹ (Γ r_γ − r_s),

with two Cholesky factorisations. Choices the paper leaves open (recorded here):

- centring: Mehrotra predictor–corrector — an affine step (σ = 0), then σ = (μ_aff / μ)³ and the second-order
  correction Δs_aff ∘ Δγ_aff in r_s;
- step rule: fraction to the boundary over slacks and inequality multipliers only, α = min(1, 0.99 α_max);
- regularisation: δ I added to H (the heading has zero weight in the cost, so H is singular); δ = 1e-8 by default;
  if a Cholesky factorisation still fails near the boundary (γ/s spans many decades), 1e-10 of the largest diagonal
  entry of Φ is added to Φ, Φ refactorised, and C Φ⁻¹ Cᵀ refactorised with 1e-12 of its largest diagonal entry added;
- start: z from the warm start (or 0), s = max(m − P z, s_floor), γ = 1 (an infeasible start is allowed);
- iteration cap: fixed (the paper's "fast MPC"); the solver stops earlier when all residuals and μ fall below ``tol``.

Linear algebra (the QPs have a few dozen variables and are solved hundreds of times per second, so fixed per-call
costs, not arithmetic, decide the time): the whole iteration is one function compiled by numba (``cache=True``: the
compilation, about ten seconds, is paid once per machine). H, C and P are taken dense and stored row-compressed once per
solve, so every product costs their number of non-zeros. Φ and Y = C Φ⁻¹ Cᵀ are factorised by *envelope* (profile)
Cholesky: row i of a factor is stored from the first column that is structurally non-zero in row i of the matrix,
and a Cholesky factor never fills outside that envelope. Φ's envelope follows from the patterns of H and of the rows
of P (each row couples its own non-zeros); Y = WᵀW with W = L_Φ⁻¹ Cᵀ, and Y's envelope from the ranges of rows that
each column of W actually fills. A dense QP costs what a dense Cholesky costs; a QP whose variables and equality rows
are ordered stage by stage (an MPC: each stage's inputs, states and slacks together, bounds and separation rows within
one stage, dynamics rows linking consecutive stages) has a block-diagonal Φ and a block-tridiagonal Y, and each
iteration costs O(stages), as in the Riccati-like solve of Wang & Boyd's fast MPC.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["PdipOptions", "QpResult", "solve_qp_pdip"]

_PHI_SHIFT = 1e-10  # fallback shift of Φ, relative to its largest diagonal entry
_Y_SHIFT = 1e-12  # fallback shift of C Φ⁻¹ Cᵀ, relative to its largest diagonal entry


@dataclass(frozen=True, kw_only=True)
class PdipOptions:
    """Options of :func:`solve_qp_pdip`.

    Attributes
    ----------
    max_iter : int
        Iteration cap, >= 1.
    step_fraction : float
        Fraction-to-the-boundary factor in (0, 1).
    regularization : float
        δ added to the Hessian diagonal (−), >= 0.
    slack_floor : float
        Smallest initial slack (units of the constraint), > 0.
    tol : float
        Early-exit tolerance on the residual norms and μ, > 0.
    """

    max_iter: int = 30
    step_fraction: float = 0.99
    regularization: float = 1e-8
    slack_floor: float = 1.0
    tol: float = 1e-9

    def __post_init__(self) -> None:
        if int(self.max_iter) != self.max_iter or self.max_iter < 1:
            raise ValueError(f"PdipOptions.max_iter must be an integer >= 1, got {self.max_iter}")
        if not (0 < self.step_fraction < 1):
            raise ValueError(f"PdipOptions.step_fraction must be in (0, 1), got {self.step_fraction}")
        if not (self.regularization >= 0):
            raise ValueError(f"PdipOptions.regularization must be >= 0, got {self.regularization}")
        for name in ("slack_floor", "tol"):
            if not (getattr(self, name) > 0):
                raise ValueError(f"PdipOptions.{name} must be > 0, got {getattr(self, name)}")


@dataclass(frozen=True, kw_only=True)
class QpResult:
    """Result of :func:`solve_qp_pdip`: primal z, multipliers λ and γ, slacks s, iterations used, whether the
    tolerance was met, the objective ½zᵀHz + fᵀz and the final residual norm max(|r_z|∞, |r_λ|∞, |r_γ|∞, μ)."""

    z: np.ndarray
    lam: np.ndarray
    gam: np.ndarray
    s: np.ndarray
    iterations: int
    converged: bool
    objective: float
    residual: float


# --- sparse rows ---------------------------------------------------------------------------------------------------
@numba.njit(cache=True)
def _compress(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row-compressed (pointer, column, value) form of the dense ``A``; columns ascend within a row."""
    rows, cols = A.shape
    ptr = np.zeros(rows + 1, np.int64)
    idx = np.empty(rows * cols, np.int64)
    val = np.empty(rows * cols)
    k = 0
    for i in range(rows):
        for j in range(cols):
            if A[i, j] != 0.0:
                idx[k] = j
                val[k] = A[i, j]
                k += 1
        ptr[i + 1] = k
    return ptr, idx[:k], val[:k]


@numba.njit(cache=True)
def _mv(ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """``out = A x``."""
    for i in range(ptr.shape[0] - 1):
        acc = 0.0
        for k in range(ptr[i], ptr[i + 1]):
            acc += val[k] * x[idx[k]]
        out[i] = acc


@numba.njit(cache=True)
def _mtv_add(ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, y: np.ndarray, a: float, out: np.ndarray) -> None:
    """``out += a Aᵀ y``."""
    for i in range(ptr.shape[0] - 1):
        yi = a * y[i]
        if yi != 0.0:
            for k in range(ptr[i], ptr[i + 1]):
                out[idx[k]] += val[k] * yi


# --- envelope Cholesky ---------------------------------------------------------------------------------------------
@numba.njit(cache=True)
def _chol(A: np.ndarray, first: np.ndarray) -> bool:
    """Lower Cholesky factor in place of the envelope of ``A`` (row i from column ``first[i]``); False when a pivot
    is not positive (the matrix is not numerically positive definite)."""
    for i in range(A.shape[0]):
        fi = first[i]
        for j in range(fi, i):
            k0 = max(fi, first[j])
            acc = A[i, j]
            for k in range(k0, j):
                acc -= A[i, k] * A[j, k]
            A[i, j] = acc / A[j, j]
        acc = A[i, i]
        for k in range(fi, i):
            acc -= A[i, k] * A[i, k]
        if not acc > 0.0:
            return False
        A[i, i] = np.sqrt(acc)
    return True


@numba.njit(cache=True)
def _chol_solve(L: np.ndarray, first: np.ndarray, x: np.ndarray) -> None:
    """``x ← (L Lᵀ)⁻¹ x`` in place for an envelope factor of :func:`_chol`."""
    n = L.shape[0]
    for i in range(n):
        acc = x[i]
        for k in range(first[i], i):
            acc -= L[i, k] * x[k]
        x[i] = acc / L[i, i]
    for i in range(n - 1, -1, -1):
        xi = x[i] / L[i, i]
        x[i] = xi
        for k in range(first[i], i):
            x[k] -= L[i, k] * xi


@numba.njit(cache=True)
def _max_diag(A: np.ndarray) -> float:
    out = -np.inf
    for i in range(A.shape[0]):
        out = max(out, A[i, i])
    return out


# --- Newton system -------------------------------------------------------------------------------------------------
@numba.njit(cache=True)
def _assemble_phi(Phi: np.ndarray, first: np.ndarray, Hp: np.ndarray, Hi: np.ndarray, Hv: np.ndarray, delta: float,
                  Pp: np.ndarray, Pi: np.ndarray, Pv: np.ndarray, d: np.ndarray) -> None:
    """Lower envelope of Φ = H + δ I + Pᵀ diag(d) P."""
    n = Phi.shape[0]
    for i in range(n):
        for j in range(first[i], i + 1):
            Phi[i, j] = 0.0
        Phi[i, i] = delta
    for i in range(n):
        for k in range(Hp[i], Hp[i + 1]):
            if Hi[k] <= i:
                Phi[i, Hi[k]] += Hv[k]
    for r in range(Pp.shape[0] - 1):
        dr = d[r]
        for a in range(Pp[r], Pp[r + 1]):
            wa = dr * Pv[a]
            for c in range(Pp[r], a + 1):
                Phi[Pi[a], Pi[c]] += wa * Pv[c]


@numba.njit(cache=True)
def _schur(L: np.ndarray, first: np.ndarray, reach: np.ndarray, Cp: np.ndarray, Ci: np.ndarray, Cv: np.ndarray,
           Wt: np.ndarray, lo: np.ndarray, hi: np.ndarray, Y: np.ndarray, firstY: np.ndarray) -> None:
    """Y = C Φ⁻¹ Cᵀ = Wᵀ W with W = L⁻¹ Cᵀ (row j of ``Wt`` non-zero in [lo[j], hi[j]] only), and Y's envelope.

    ``reach[i]`` = min(first[i:]): once past the last non-zero of a row of C, the forward substitution stops at the
    first i whose later rows all start beyond the last non-zero so far (no fill can reach them). ``lo``, ``hi`` come
    in with the previous call's ranges (``Wt`` is zero outside them)."""
    ne, n = Wt.shape
    for j in range(ne):
        w = Wt[j]
        for i in range(lo[j], hi[j] + 1):
            w[i] = 0.0
        if Cp[j + 1] == Cp[j]:
            lo[j], hi[j] = n, -1
            continue
        for k in range(Cp[j], Cp[j + 1]):
            w[Ci[k]] = Cv[k]
        start, stop = Ci[Cp[j]], Ci[Cp[j + 1] - 1]
        last = -1
        for i in range(start, n):
            if i > stop and reach[i] > last:
                break
            acc = w[i]
            if first[i] <= last:
                for k in range(max(first[i], start), i):
                    acc -= L[i, k] * w[k]
            if acc != 0.0:
                w[i] = acc / L[i, i]
                last = i
            else:
                w[i] = 0.0
        lo[j], hi[j] = start, last
    for i in range(ne):
        firstY[i] = i
        j0, top = 0, hi[0]  # top = max(hi[:j0 + 1]): while below lo[i], no row up to j0 meets row i
        while j0 < i and top < lo[i]:
            j0 += 1
            top = max(top, hi[j0])
        for j in range(j0, i + 1):
            a, b = max(lo[i], lo[j]), min(hi[i], hi[j])
            if a > b:
                Y[i, j] = 0.0
                continue
            if j < firstY[i]:
                firstY[i] = j
            acc = 0.0
            for k in range(a, b + 1):
                acc += Wt[i, k] * Wt[j, k]
            Y[i, j] = acc


@numba.njit(cache=True)
def _direction(r_s: np.ndarray, r_z: np.ndarray, r_l: np.ndarray, r_g: np.ndarray, gam: np.ndarray, s: np.ndarray,
               d: np.ndarray, L: np.ndarray, first: np.ndarray, LY: np.ndarray, firstY: np.ndarray, Cp: np.ndarray,
               Ci: np.ndarray, Cv: np.ndarray, Pp: np.ndarray, Pi: np.ndarray, Pv: np.ndarray, dz: np.ndarray,
               dl: np.ndarray, dg: np.ndarray, ds: np.ndarray) -> None:
    """Newton direction (Δz, Δλ, Δγ, Δs) for the complementarity residual ``r_s`` (module docstring)."""
    n, ne, ni = r_z.shape[0], r_l.shape[0], r_g.shape[0]
    q = np.empty(ni)  # S⁻¹ (Γ r_γ − r_s)
    for i in range(ni):
        q[i] = (gam[i] * r_g[i] - r_s[i]) / s[i]
    rho = np.empty(n)
    for i in range(n):
        rho[i] = -r_z[i]
    _mtv_add(Pp, Pi, Pv, q, -1.0, rho)
    x = rho.copy()
    _chol_solve(L, first, x)
    _mv(Cp, Ci, Cv, x, dl)
    for i in range(ne):
        dl[i] += r_l[i]
    _chol_solve(LY, firstY, dl)
    for i in range(n):
        dz[i] = rho[i]
    _mtv_add(Cp, Ci, Cv, dl, -1.0, dz)
    _chol_solve(L, first, dz)
    _mv(Pp, Pi, Pv, dz, ds)
    for i in range(ni):
        dg[i] = q[i] + d[i] * ds[i]
        ds[i] = -r_g[i] - ds[i]


@numba.njit(cache=True)
def _dot(x: np.ndarray, y: np.ndarray) -> float:
    acc = 0.0
    for i in range(x.shape[0]):
        acc += x[i] * y[i]
    return acc


@numba.njit(cache=True)
def _axpy(a: float, x: np.ndarray, y: np.ndarray) -> None:
    """``y += a x``."""
    for i in range(x.shape[0]):
        y[i] += a * x[i]


@numba.njit(cache=True)
def _max_abs(x: np.ndarray) -> float:
    out = 0.0
    for i in range(x.shape[0]):
        out = max(out, abs(x[i]))
    return out


@numba.njit(cache=True)
def _max_step(v: np.ndarray, dv: np.ndarray) -> float:
    """Largest step ``a`` with ``v + a dv >= 0`` (inf when no component decreases)."""
    out = np.inf
    for i in range(v.shape[0]):
        if dv[i] < 0.0:
            out = min(out, -v[i] / dv[i])
    return out


@numba.njit(cache=True)
def _residuals(z: np.ndarray, lam: np.ndarray, gam: np.ndarray, s: np.ndarray, f: np.ndarray, b: np.ndarray,
               m: np.ndarray, delta: float, Hp: np.ndarray, Hi: np.ndarray, Hv: np.ndarray, Cp: np.ndarray,
               Ci: np.ndarray, Cv: np.ndarray, Pp: np.ndarray, Pi: np.ndarray, Pv: np.ndarray, r_z: np.ndarray,
               r_l: np.ndarray, r_g: np.ndarray) -> tuple[float, float]:
    """KKT residuals in place; returns (μ, max(|r_z|∞, |r_λ|∞, |r_γ|∞, μ))."""
    _mv(Hp, Hi, Hv, z, r_z)
    for i in range(r_z.shape[0]):
        r_z[i] += delta * z[i] + f[i]
    _mtv_add(Cp, Ci, Cv, lam, 1.0, r_z)
    _mtv_add(Pp, Pi, Pv, gam, 1.0, r_z)
    _mv(Cp, Ci, Cv, z, r_l)
    for i in range(r_l.shape[0]):
        r_l[i] -= b[i]
    _mv(Pp, Pi, Pv, z, r_g)
    for i in range(r_g.shape[0]):
        r_g[i] += s[i] - m[i]
    mu = _dot(gam, s) / max(s.shape[0], 1)
    return mu, max(mu, _max_abs(r_z), _max_abs(r_l), _max_abs(r_g))


@numba.njit(cache=True)
def _pdip(H: np.ndarray, f: np.ndarray, C: np.ndarray, b: np.ndarray, P: np.ndarray, m: np.ndarray, z0: np.ndarray,
          max_iter: int, step_fraction: float, delta: float, slack_floor: float, tol: float):
    """The interior point of the module docstring; returns (z, λ, γ, s, iterations, residual, status), status 0 when
    every factorisation succeeded, 1 when Φ or C Φ⁻¹ Cᵀ was not positive definite even after the fallback shift."""
    n, ne, ni = H.shape[0], C.shape[0], P.shape[0]
    Hp, Hi, Hv = _compress(H)
    Cp, Ci, Cv = _compress(C)
    Pp, Pi, Pv = _compress(P)
    first = np.arange(n)  # envelope of Φ: the patterns of H and of each row of P
    for i in range(n):
        for k in range(Hp[i], Hp[i + 1]):
            first[max(i, Hi[k])] = min(first[max(i, Hi[k])], min(i, Hi[k]))
    for r in range(ni):
        if Pp[r + 1] > Pp[r]:
            c0 = Pi[Pp[r]]
            for k in range(Pp[r], Pp[r + 1]):
                first[Pi[k]] = min(first[Pi[k]], c0)
    reach = first.copy()
    for i in range(n - 2, -1, -1):
        reach[i] = min(reach[i], reach[i + 1])
    L, LY, Wt = np.zeros((n, n)), np.zeros((ne, ne)), np.zeros((ne, n))
    firstY, lo, hi = np.arange(ne), np.zeros(ne, np.int64), np.full(ne, -1, np.int64)
    z = z0.copy()
    lam, gam = np.zeros(ne), np.ones(ni)
    s = np.empty(ni)
    _mv(Pp, Pi, Pv, z, s)
    for i in range(ni):
        s[i] = max(m[i] - s[i], slack_floor)
    r_z, r_l, r_g = np.empty(n), np.empty(ne), np.empty(ni)
    dz, dl, dg, ds = np.empty(n), np.empty(ne), np.empty(ni), np.empty(ni)
    d, r_s = np.empty(ni), np.empty(ni)
    it, res, done = 0, np.inf, False
    for it in range(1, max_iter + 1):
        mu, res = _residuals(z, lam, gam, s, f, b, m, delta, Hp, Hi, Hv, Cp, Ci, Cv, Pp, Pi, Pv, r_z, r_l, r_g)
        if res < tol:
            it -= 1
            done = True
            break
        for i in range(ni):
            d[i] = gam[i] / s[i]
            r_s[i] = gam[i] * s[i]
        _assemble_phi(L, first, Hp, Hi, Hv, delta, Pp, Pi, Pv, d)
        ok = _chol(L, first)
        if ok:
            _schur(L, first, reach, Cp, Ci, Cv, Wt, lo, hi, LY, firstY)
            ok = _chol(LY, firstY)
        if not ok:  # lost definiteness to round-off near the boundary: regularise relative to scale
            _assemble_phi(L, first, Hp, Hi, Hv, delta, Pp, Pi, Pv, d)
            shift = _PHI_SHIFT * _max_diag(L)
            for i in range(n):
                L[i, i] += shift
            if not _chol(L, first):
                return z, lam, gam, s, it, res, 1
            _schur(L, first, reach, Cp, Ci, Cv, Wt, lo, hi, LY, firstY)
            shift = _Y_SHIFT * _max_diag(LY)
            for i in range(ne):
                LY[i, i] += shift
            if not _chol(LY, firstY):
                return z, lam, gam, s, it, res, 1
        # predictor (affine scaling)
        _direction(r_s, r_z, r_l, r_g, gam, s, d, L, first, LY, firstY, Cp, Ci, Cv, Pp, Pi, Pv, dz, dl, dg, ds)
        a_aff = min(1.0, _max_step(s, ds), _max_step(gam, dg))
        mu_aff = 0.0
        for i in range(ni):
            mu_aff += (gam[i] + a_aff * dg[i]) * (s[i] + a_aff * ds[i])
        mu_aff /= max(ni, 1)
        sigma = (mu_aff / mu) ** 3 if mu > 0 else 0.0
        # corrector with centring
        for i in range(ni):
            r_s[i] = gam[i] * s[i] + ds[i] * dg[i] - sigma * mu
        _direction(r_s, r_z, r_l, r_g, gam, s, d, L, first, LY, firstY, Cp, Ci, Cv, Pp, Pi, Pv, dz, dl, dg, ds)
        alpha = min(1.0, step_fraction * min(_max_step(s, ds), _max_step(gam, dg)))
        _axpy(alpha, dz, z)
        _axpy(alpha, dl, lam)
        _axpy(alpha, dg, gam)
        _axpy(alpha, ds, s)
    if not done:
        mu, res = _residuals(z, lam, gam, s, f, b, m, delta, Hp, Hi, Hv, Cp, Ci, Cv, Pp, Pi, Pv, r_z, r_l, r_g)
    return z, lam, gam, s, it, res, 0


def solve_qp_pdip(H: np.ndarray, f: np.ndarray, C: np.ndarray, b: np.ndarray, P: np.ndarray, m: np.ndarray,
                  options: PdipOptions = PdipOptions(), z0: np.ndarray | None = None) -> QpResult:
    """Solve the QP of the module docstring by Mehrotra's primal-dual interior-point method (see there).

    Parameters
    ----------
    H : np.ndarray
        (n, n) symmetric positive semi-definite Hessian.
    f : np.ndarray
        (n,) linear cost.
    C, b : np.ndarray
        (n_e, n) and (n_e,) equality constraints C z = b (C of full row rank).
    P, m : np.ndarray
        (n_i, n) and (n_i,) inequality constraints P z ≤ m.
    options : PdipOptions
        Iteration cap, step rule, regularisation and tolerance.
    z0 : np.ndarray, optional
        (n,) warm start (need not be feasible); zeros when omitted.

    Returns
    -------
    QpResult

    Raises
    ------
    numpy.linalg.LinAlgError
        Φ or C Φ⁻¹ Cᵀ is not positive definite even after the fallback shift (e.g. C = 0, or non-finite data;
        a merely rank-deficient C is absorbed by the shift).
    """
    H = np.ascontiguousarray(H, dtype=np.float64)
    n = H.shape[0]
    C = np.ascontiguousarray(np.asarray(C, dtype=np.float64).reshape(-1, n))
    P = np.ascontiguousarray(np.asarray(P, dtype=np.float64).reshape(-1, n))
    f, b, m = (np.ascontiguousarray(v, dtype=np.float64).reshape(-1) for v in (f, b, m))
    z0 = np.zeros(n) if z0 is None else np.array(z0, dtype=np.float64).reshape(-1)
    z, lam, gam, s, it, res, status = _pdip(H, f, C, b, P, m, z0, int(options.max_iter), float(options.step_fraction),
                                           float(options.regularization), float(options.slack_floor),
                                           float(options.tol))
    if status:
        raise np.linalg.LinAlgError("interior point: the Newton system is not positive definite even after the "
                                    "fallback shift (C = 0? non-finite data?)")
    obj = float(0.5 * z @ H @ z + f @ z)
    return QpResult(z=z, lam=lam, gam=gam, s=s, iterations=int(it), converged=bool(res < options.tol), objective=obj,
                    residual=float(res))
