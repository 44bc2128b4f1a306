"""Multi-target distances: OSPA (Schuhmacher et al. 2008) and GOSPA (Rahmathullah et al. 2017, α = 2)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

__all__ = ["ospa", "GospaResult", "gospa"]


def _cut_distances(X: np.ndarray, Y: np.ndarray, c: float, p: float) -> np.ndarray:
    D = np.linalg.norm(X[:, None, :] - Y[None, :, :], axis=-1)
    return np.minimum(D, c) ** p


def _as_points(X: np.ndarray) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    return X.reshape(0, 2) if X.size == 0 else np.atleast_2d(X)


def _check(c: float, p: float) -> None:
    if not c > 0:
        raise ValueError(f"c must be > 0, got {c}")
    if not p >= 1:
        raise ValueError(f"p must be >= 1, got {p}")


def ospa(X: np.ndarray, Y: np.ndarray, c: float, p: float = 2.0) -> float:
    """OSPA distance (m) between point sets ``X`` (m × d) and ``Y`` (n × d), cut-off ``c`` (m), order ``p``.

    ``d = ( (min_π Σ_{i≤m} min(c, ‖x_i − y_π(i)‖)^p + c^p (n − m)) / n )^{1/p}`` for ``m ≤ n``; 0 when both are empty.
    """
    _check(c, p)
    X, Y = _as_points(X), _as_points(Y)
    if len(X) > len(Y):
        X, Y = Y, X
    m, n = len(X), len(Y)
    if n == 0:
        return 0.0
    cost = 0.0
    if m > 0:
        D = _cut_distances(X, Y, c, p)
        r, col = linear_sum_assignment(D)
        cost = float(D[r, col].sum())
    return float(((cost + c**p * (n - m)) / n) ** (1.0 / p))


@dataclass(frozen=True, kw_only=True)
class GospaResult:
    """GOSPA distance and its decomposition (all to the power p before the root is taken in ``distance``).

    Attributes
    ----------
    distance : float
        GOSPA distance, m.
    localisation : float
        Σ ‖x − y‖^p over assigned pairs, m^p.
    missed : int
        Truths left unassigned.
    false : int
        Estimates left unassigned.
    """

    distance: float
    localisation: float
    missed: int
    false: int


def gospa(truth: np.ndarray, estimates: np.ndarray, c: float, p: float = 2.0) -> GospaResult:
    """GOSPA with α = 2: ``d = (min over assignments of Σ ‖x − y‖^p + c^p/2 (#missed + #false))^{1/p}``.

    Pairs farther apart than ``c`` are better left unassigned (each costs ``c^p/2``, as much as leaving both points
    unassigned): with ``D = min(‖x − y‖^p, c^p)``, the best assignment is a maximum matching of least
    ``Σ (D − c^p)``, solved as a rectangular assignment among the points that have some partner nearer than ``c``
    (a point without one is unassigned in every best assignment); its pairs with ``D < c^p`` are the assigned ones.
    """
    _check(c, p)
    X, Y = _as_points(truth), _as_points(estimates)
    m, n = len(X), len(Y)
    half = c**p / 2.0
    if m == 0 or n == 0:
        return GospaResult(distance=float(((m + n) * half) ** (1.0 / p)), localisation=0.0, missed=m, false=n)
    D = np.minimum(np.linalg.norm(X[:, None, :] - Y[None, :, :], axis=-1) ** p, 2.0 * half)
    near = D < 2.0 * half
    rows, cols = np.flatnonzero(near.any(axis=1)), np.flatnonzero(near.any(axis=0))
    loc, k = 0.0, 0
    if len(rows):
        sub = D[np.ix_(rows, cols)]
        r, col = linear_sum_assignment(sub - 2.0 * half)
        pairs = sorted((int(rows[i]), int(cols[j])) for i, j in zip(r, col, strict=True) if sub[i, j] < 2.0 * half)
        loc, k = float(sum(D[i, j] for i, j in pairs)), len(pairs)
    missed, false = m - k, n - k
    total = loc + half * (missed + false)
    return GospaResult(distance=float(total ** (1.0 / p)), localisation=loc, missed=missed, false=false)
