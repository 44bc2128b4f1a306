"""Track-to-track fusion of two or more Gaussian estimates: convex (state-vector) fusion and covariance intersection."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.optimize import minimize, minimize_scalar

__all__ = ["FusedEstimate", "state_vector_fusion", "covariance_intersection"]


@dataclass(frozen=True, kw_only=True, eq=False)
class FusedEstimate:
    """A fused estimate.

    Attributes
    ----------
    x : ndarray
        Fused state.
    P : ndarray
        Fused covariance.
    weights : ndarray
        Covariance-intersection weights ω_i (empty for convex fusion).
    """

    x: np.ndarray
    P: np.ndarray
    weights: np.ndarray


def state_vector_fusion(x_a: np.ndarray, P_a: np.ndarray, x_b: np.ndarray, P_b: np.ndarray) -> FusedEstimate:
    """Convex combination ignoring cross-covariance (paper 002).

    ``x = x_a + P_a (P_a + P_b)⁻¹ (x_b − x_a)``, ``P = P_a − P_a (P_a + P_b)⁻¹ P_a``. Optimal for independent errors;
    overconfident when the errors are correlated (use :func:`covariance_intersection` then).
    """
    x_a, x_b = np.asarray(x_a, dtype=float), np.asarray(x_b, dtype=float)
    P_a, P_b = np.asarray(P_a, dtype=float), np.asarray(P_b, dtype=float)
    K = np.linalg.solve(P_a + P_b, P_a).T  # P_a (P_a + P_b)⁻¹ (both symmetric)
    P = P_a - K @ P_a
    return FusedEstimate(x=x_a + K @ (x_b - x_a), P=0.5 * (P + P.T), weights=np.empty(0))


def _ci_cost(P: np.ndarray, criterion: str) -> float:
    if criterion == "trace":
        return float(np.trace(P))
    sign, logdet = np.linalg.slogdet(P)
    return float(logdet) if sign > 0 else np.inf


def covariance_intersection(xs: Sequence[np.ndarray], Ps: Sequence[np.ndarray],
                            criterion: Literal["trace", "det"] = "trace") -> FusedEstimate:
    """Covariance intersection (Julier & Uhlmann 1997): consistent for any unknown cross-correlation.

    ``P⁻¹ = Σ ω_i P_i⁻¹``, ``P⁻¹ x = Σ ω_i P_i⁻¹ x_i``, ω on the simplex, chosen to minimise ``tr P`` or ``det P``
    (bounded scalar search for two inputs; for more, SLSQP on the simplex with the analytic gradient — both costs are
    convex in ω, so the optimum is global).
    """
    if criterion not in ("trace", "det"):
        raise ValueError(f"criterion must be 'trace' or 'det', got {criterion!r}")
    if len(xs) != len(Ps) or len(xs) == 0:
        raise ValueError(f"xs and Ps must be non-empty and of equal length, got {len(xs)} and {len(Ps)}")
    Ys = np.array([np.linalg.inv(np.asarray(P, dtype=float)) for P in Ps])
    ys = np.array([Y @ np.asarray(x, dtype=float) for Y, x in zip(Ys, xs, strict=True)])

    def fused_P(w: np.ndarray) -> np.ndarray:
        return np.linalg.inv(np.tensordot(w, Ys, axes=1))

    N = len(xs)
    if N == 1:
        w = np.ones(1)
    elif N == 2:
        res = minimize_scalar(lambda a: _ci_cost(fused_P(np.array([a, 1.0 - a])), criterion), bounds=(0.0, 1.0),
                              method="bounded", options={"xatol": 1e-6})
        w = np.array([res.x, 1.0 - res.x])
    else:
        w = _simplex_weights(Ys, criterion)
    P = fused_P(w)
    P = 0.5 * (P + P.T)
    return FusedEstimate(x=P @ np.tensordot(w, ys, axes=1), P=P, weights=w)


def _simplex_weights(Ys: np.ndarray, criterion: str) -> np.ndarray:
    """CI weights of three or more informations ``Ys`` (N, n, n) minimising tr P or log det P, P = (Σ ω_i Y_i)⁻¹.

    Both are convex in ω (tr J⁻¹ and −log det J are convex in J ≻ 0, and J is linear in ω), with gradients
    ∂ tr P / ∂ω_i = −tr(P Y_i P) and ∂ log det P / ∂ω_i = −tr(P Y_i). SLSQP on the simplex from equal weights needs
    ≈ 5–15 evaluations of an n × n inverse, where Nelder–Mead over softmax weights needed hundreds (≈ 19 ms with
    three 4-state tracks in ``helsinki_chase``).
    """
    N = len(Ys)

    def cost_grad(w: np.ndarray) -> tuple[float, np.ndarray]:
        J = np.tensordot(w, Ys, axes=1)
        try:
            P = np.linalg.inv(J)
        except np.linalg.LinAlgError:
            return np.inf, np.zeros(N)
        if criterion == "trace":
            PP = P @ P
            return float(np.trace(P)), -np.einsum("ij,kji->k", PP, Ys)
        sign, logdet = np.linalg.slogdet(J)
        if sign <= 0:
            return np.inf, np.zeros(N)
        return float(-logdet), -np.einsum("ij,kji->k", P, Ys)

    res = minimize(cost_grad, np.full(N, 1.0 / N), jac=True, method="SLSQP", bounds=[(0.0, 1.0)] * N,
                   constraints=({"type": "eq", "fun": lambda w: np.sum(w) - 1.0, "jac": lambda w: np.ones(N)},),
                   options={"ftol": 1e-12, "maxiter": 200})
    w = np.clip(res.x, 0.0, None)
    return w / w.sum()
