"""Small dense linear-algebra helpers shared by the filters and the fusion code (hot-path friendly: the matrices are
a few rows, so closed forms and compiled loops replace LAPACK wrappers whose fixed call cost dominates)."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["tria", "tria_jit", "psd_sqrt", "symmetrise", "log_gaussian", "small_inv"]

_LOG_2PI = float(np.log(2.0 * np.pi))


@numba.njit(cache=True)
def tria_jit(A: np.ndarray) -> np.ndarray:
    """:func:`tria` for compiled callers (``A`` float64, C-contiguous)."""
    n, k = A.shape
    B = A.copy()  # row c of B is column c of Aᵀ, the matrix being reduced
    p = min(n, k)
    for j in range(p):
        # Householder reflector H = I − τ v vᵀ (v_j = 1) mapping Aᵀ[j:, j] onto β e_j (LAPACK dlarfg's convention)
        alpha = B[j, j]
        ss = 0.0
        for i in range(j + 1, k):
            ss += B[j, i] * B[j, i]
        if ss == 0.0:
            continue  # already reduced: H = I
        beta = -np.copysign(np.sqrt(alpha * alpha + ss), alpha)
        tau = (beta - alpha) / beta
        scale = 1.0 / (alpha - beta)
        for i in range(j + 1, k):
            B[j, i] *= scale
        B[j, j] = beta
        for c in range(j + 1, n):
            w = B[c, j]
            for i in range(j + 1, k):
                w += B[j, i] * B[c, i]
            w *= tau
            B[c, j] -= w
            for i in range(j + 1, k):
                B[c, i] -= w * B[j, i]
    S = np.zeros((n, p))
    for c in range(n):
        for j in range(min(c + 1, p)):
            S[c, j] = B[c, j]
    return S


def tria(A: np.ndarray) -> np.ndarray:
    """Triangularisation: a lower-triangular ``S`` (n × min(n, k)) with ``S Sᵀ = A Aᵀ`` for ``A`` of shape (n, k).

    ``Sᵀ`` is the R factor of the QR decomposition of ``Aᵀ`` (``Aᵀ = Q R`` ⇒ ``A Aᵀ = Rᵀ R``), by Householder
    reflections with LAPACK's sign convention (compiled; :func:`tria_jit` for compiled callers). Diagonal signs are
    not normalised (they do not affect ``S Sᵀ``).
    """
    return tria_jit(np.ascontiguousarray(A, dtype=np.float64))


def psd_sqrt(P: np.ndarray) -> np.ndarray:
    """A square root ``S`` with ``S Sᵀ = P`` for a symmetric positive semi-definite ``P``.

    Cholesky factor when ``P`` is positive definite; otherwise ``V diag(√max(λ, 0))`` from the eigen-decomposition
    (e.g. the rank-deficient process noise of an Euler-discretised Singer model).
    """
    try:
        return np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        w, V = np.linalg.eigh(0.5 * (P + P.T))
        return V * np.sqrt(np.clip(w, 0.0, None))


def symmetrise(P: np.ndarray) -> np.ndarray:
    """``(P + Pᵀ)/2``."""
    return 0.5 * (P + P.T)


def log_gaussian(nis: float, S: np.ndarray) -> float:
    """``log N(ν; 0, S)`` given the normalised innovation squared ``nis = νᵀ S⁻¹ ν``: ``−½(nis + log det(2π S))``."""
    sign, logdet = np.linalg.slogdet(S)
    if sign <= 0:
        return -np.inf
    return -0.5 * (nis + logdet + S.shape[0] * _LOG_2PI)


def small_inv(S: np.ndarray) -> tuple[np.ndarray, float]:
    """Inverse and determinant of a small (1 × 1 to 3 × 3) matrix by cofactors; ``np.linalg`` for larger ones.

    The closed forms avoid the fixed call overhead of LAPACK wrappers, which dominates at these sizes.
    """
    m = S.shape[0]
    if m == 1:
        d = float(S[0, 0])
        return np.array([[1.0 / d]]), d
    if m == 2:
        a, b, c, e = S.ravel().tolist()
        d = a * e - b * c
        return np.array([[e / d, -b / d], [-c / d, a / d]]), d
    if m == 3:
        a, b, c, d_, e, f, g, h, i = S.ravel().tolist()
        A, B, C = e * i - f * h, f * g - d_ * i, d_ * h - e * g
        det = a * A + b * B + c * C
        k = 1.0 / det
        return np.array([[A * k, (c * h - b * i) * k, (b * f - c * e) * k],
                         [B * k, (a * i - c * g) * k, (c * d_ - a * f) * k],
                         [C * k, (b * g - a * h) * k, (a * e - b * d_) * k]]), det
    sign, logdet = np.linalg.slogdet(S)
    return np.linalg.inv(S), float(sign * np.exp(logdet))
