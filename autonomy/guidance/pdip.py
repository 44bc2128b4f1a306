"""Primal-dual interior-point solver for the small dense QPs of the fast MPC (Hu et al. 2018, section IV-C).

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
  entry is added and the factorisation retried;
- start: z from the warm start (or 0), s = max(m − P z, s_floor), γ = 1 (an infeasible start is allowed);
- iteration cap: fixed (the paper's "fast MPC"); the solver stops earlier when all residuals and μ fall below ``tol``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import dpotrf, dpotrs

__all__ = ["PdipOptions", "QpResult", "solve_qp_pdip"]


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


def cho_factor(A: np.ndarray) -> np.ndarray:
    """Upper Cholesky factor of the symmetric positive definite ``A`` straight from LAPACK ``dpotrf`` (the matrices
    are tiny and factorised hundreds of times per second: scipy's checking wrappers cost more than the work).

    Raises
    ------
    numpy.linalg.LinAlgError
        ``A`` is not (numerically) positive definite.
    """
    c, info = dpotrf(A, lower=0, clean=0, overwrite_a=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"dpotrf failed with info = {info}")
    return c


def cho_solve(c: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``A⁻¹ B`` from the factor of :func:`cho_factor` (LAPACK ``dpotrs``)."""
    x, info = dpotrs(c, B, lower=0)
    if info != 0:  # pragma: no cover - only for invalid arguments
        raise ValueError(f"dpotrs failed with info = {info}")
    return x


def _max_step(v: np.ndarray, dv: np.ndarray) -> float:
    """Largest step ``a`` with ``v + a dv >= 0`` (inf when no component decreases)."""
    if not v.size:
        return np.inf
    return float(np.divide(-v, dv, out=np.full(v.shape, np.inf), where=dv < 0).min())


def solve_qp_pdip(H: np.ndarray, f: np.ndarray, C: np.ndarray, b: np.ndarray, P: np.ndarray, m: np.ndarray,
                  options: PdipOptions = PdipOptions(), z0: np.ndarray | None = None) -> QpResult:
    """Solve the QP of the module docstring by Mehrotra's primal-dual interior-point method (see there)."""
    n, ne, ni = H.shape[0], C.shape[0], P.shape[0]
    z = np.zeros(n) if z0 is None else np.array(z0, dtype=float)
    lam = np.zeros(ne)
    s = np.maximum(m - P @ z, options.slack_floor)
    gam = np.ones(ni)
    Hr = H + options.regularization * np.eye(n)
    it, res = 0, np.inf
    for it in range(1, options.max_iter + 1):
        r_z = Hr @ z + f + C.T @ lam + P.T @ gam
        r_l = C @ z - b
        r_g = P @ z + s - m
        mu = float(gam @ s) / max(ni, 1)
        res = max(float(np.max(np.abs(r_z), initial=0)), float(np.max(np.abs(r_l), initial=0)),
                  float(np.max(np.abs(r_g), initial=0)), mu)
        if res < options.tol:
            it -= 1
            break
        d = gam / s
        Phi_m = Hr + (P.T * d) @ P
        try:
            Phi = cho_factor(Phi_m)
            CPhi = cho_solve(Phi, C.T)  # Φ⁻¹ Cᵀ
            Y = cho_factor(C @ CPhi)
        except np.linalg.LinAlgError:  # lost definiteness to round-off near the boundary: regularise relative to scale
            Phi = cho_factor(Phi_m + 1e-10 * float(np.max(np.diag(Phi_m))) * np.eye(n))
            CPhi = cho_solve(Phi, C.T)
            YC = C @ CPhi
            Y = cho_factor(YC + 1e-12 * float(np.max(np.diag(YC))) * np.eye(ne))

        def newton(r_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
            rho = -r_z - P.T @ ((gam * r_g - r_s) / s)
            dl = cho_solve(Y, C @ cho_solve(Phi, rho) + r_l)
            dz = cho_solve(Phi, rho - C.T @ dl)
            ds = -r_g - P @ dz
            dg = (gam * r_g - r_s) / s + d * (P @ dz)
            return dz, dl, dg, ds

        # predictor (affine scaling)
        dz, dl, dg, ds = newton(gam * s)
        a_aff = min(1.0, _max_step(s, ds), _max_step(gam, dg))
        mu_aff = float((gam + a_aff * dg) @ (s + a_aff * ds)) / max(ni, 1)
        sigma = (mu_aff / mu) ** 3 if mu > 0 else 0.0
        # corrector with centring
        dz, dl, dg, ds = newton(gam * s + ds * dg - sigma * mu)
        alpha = min(1.0, options.step_fraction * min(_max_step(s, ds), _max_step(gam, dg)))
        z, lam, gam, s = z + alpha * dz, lam + alpha * dl, gam + alpha * dg, s + alpha * ds
    else:
        r_z = Hr @ z + f + C.T @ lam + P.T @ gam
        res = max(float(np.max(np.abs(r_z), initial=0)), float(np.max(np.abs(C @ z - b), initial=0)),
                  float(np.max(np.abs(P @ z + s - m), initial=0)), float(gam @ s) / max(ni, 1))
    obj = float(0.5 * z @ H @ z + f @ z)
    return QpResult(z=z, lam=lam, gam=gam, s=s, iterations=it, converged=res < options.tol, objective=obj, residual=res)
