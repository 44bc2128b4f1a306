"""Small dense linear-algebra helpers shared by the filters and the fusion code (plain numpy, hot-path friendly)."""

from __future__ import annotations

import numpy as np

__all__ = ["tria", "psd_sqrt", "symmetrise", "log_gaussian", "small_inv"]

_LOG_2PI = float(np.log(2.0 * np.pi))


def tria(A: np.ndarray) -> np.ndarray:
    """Triangularisation: a lower-triangular ``S`` (n × n) with ``S Sᵀ = A Aᵀ`` for ``A`` of shape (n, k), k ≥ n.

    Computed as the transpose of the R factor of the QR decomposition of ``Aᵀ`` (``Aᵀ = Q R`` ⇒ ``A Aᵀ = Rᵀ R``).
    Diagonal signs are not normalised (they do not affect ``S Sᵀ``).
    """
    return np.linalg.qr(A.T, mode="r").T


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
