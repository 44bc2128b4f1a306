"""Multi-target distances: OSPA (Schuhmacher et al. 2008) and GOSPA (Rahmathullah et al. 2017, α = 2)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

__all__ = ["ospa", "GospaResult", "gospa", "gospa_of_pairs", "pairs_within"]


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
    ``Σ (D − c^p)`` over the pairs nearer than ``c`` (:func:`gospa_of_pairs`), which a k-d tree finds.
    """
    _check(c, p)
    X, Y = _as_points(truth), _as_points(estimates)
    i, j, d = pairs_within(X, Y, c)
    return gospa_of_pairs(len(X), len(Y), i, j, d, c, p)


def pairs_within(X: np.ndarray, Y: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(i, j, d): the pairs of rows of ``X`` (m, k) and ``Y`` (n, k) at most ``radius`` apart, sorted by (i, j), and
    their distances ``d = ‖X[i] − Y[j]‖`` (the same numbers as ``np.linalg.norm(X[:, None] − Y[None], axis=-1)``)."""
    X, Y = _as_points(X), _as_points(Y)
    if len(X) == 0 or len(Y) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)
    near = cKDTree(X).sparse_distance_matrix(cKDTree(Y), radius * (1.0 + 1e-9) + 1e-12, output_type="ndarray")
    order = np.lexsort((near["j"], near["i"]))  # the tree's own distances and rounding aside: only its pairs
    i, j = near["i"][order].astype(np.int64), near["j"][order].astype(np.int64)
    d = np.linalg.norm(X[i] - Y[j], axis=-1)
    keep = d <= radius
    return i[keep], j[keep], d[keep]


def gospa_of_pairs(m: int, n: int, i: np.ndarray, j: np.ndarray, d: np.ndarray, c: float,
                   p: float = 2.0) -> GospaResult:
    """:func:`gospa` of ``m`` truths and ``n`` estimates given every pair ``(i, j)`` nearer than ``c`` with its
    distance ``d`` (pairs at ``c`` or beyond may be given too; they are never assigned). The least-cost matching
    splits over the connected clusters of those pairs: a cluster of one pair (most of them among traffic) is that
    pair, and the rest are one rectangular assignment of ``D − c^p`` (0 off the pairs, i.e. unassigned)."""
    _check(c, p)
    half = c**p / 2.0
    D = np.minimum(np.asarray(d, dtype=float) ** p, 2.0 * half)
    near = D < 2.0 * half
    i, j, D = np.asarray(i)[near], np.asarray(j)[near], D[near]
    pi, pj, pv = i[:0], j[:0], D[:0]  # the assigned pairs and their costs
    if len(D):
        # a cluster of one pair (its truth and its estimate in no other pair): assigned, without a solver
        alone = (np.bincount(i, minlength=m)[i] == 1) & (np.bincount(j, minlength=n)[j] == 1)
        pi, pj, pv = i[alone], j[alone], D[alone]
        rest = np.flatnonzero(~alone)
        if len(rest):  # the contested clusters together: one rectangular assignment (0 off the pairs: unassigned)
            rows, r_at = np.unique(i[rest], return_inverse=True)
            cols, c_at = np.unique(j[rest], return_inverse=True)
            sub = np.zeros((len(rows), len(cols)))
            sub[r_at, c_at] = D[rest] - 2.0 * half
            full = np.full((len(rows), len(cols)), 2.0 * half)
            full[r_at, c_at] = D[rest]
            r, col = linear_sum_assignment(sub)
            hit = full[r, col] < 2.0 * half
            pi, pj, pv = (np.concatenate((pi, rows[r[hit]])), np.concatenate((pj, cols[col[hit]])),
                          np.concatenate((pv, full[r[hit], col[hit]])))
    # the costs summed one after another in (truth, estimate) order (np.cumsum: as a Python sum of the sorted pairs)
    pv = pv[np.lexsort((pj, pi))]
    loc, k = (float(np.cumsum(pv)[-1]) if len(pv) else 0.0), len(pv)
    missed, false = m - k, n - k
    total = loc + half * (missed + false)
    return GospaResult(distance=float(total ** (1.0 / p)), localisation=loc, missed=missed, false=false)
