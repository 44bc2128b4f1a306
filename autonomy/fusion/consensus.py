"""Hybrid consensus on measurements and consensus on information (HCMCI, Battistelli et al. 2015) in square-root form.

Each node j holds its prior ``(S⁻_j, ĥ⁻_j)`` (``S⁻ S⁻ᵀ = Ω⁻``) and its new measurement information ``(S_I,j, i_j)``.
For ℓ = 1 … L, every node replaces each quantity by the weighted average over its current neighbours (itself
included), with Metropolis weights on the active links. Information matrices are averaged, never their square roots
(``S`` and ``−S`` would average to 0): the square-root average is ``tria([√a_j1 S_1, …, √a_jN S_N])``, whose product
with its transpose is ``Σ a_jm S_m S_mᵀ``. Information vectors are averaged linearly. Finally
``Ω_j = Ω⁻_j(L) + b_j I_j(L)`` (square root ``tria([S⁻_j(L), √b_j S_I,j(L)])``; paper 000 prints ``b·S_I``) and
``ĥ_j = ĥ⁻_j(L) + b_j i_j(L)``.

The gain ``b_j``: ``b = N`` recovers centralised fusion when consensus has converged but counts a node's own
measurement up to N times when it is cut off (overconfident). The default ``b="safe"`` uses ``b_j = 1 / max_m π_jm``
with ``π = A^L`` the L-step consensus weights (which the nodes obtain by running the same consensus on indicator
vectors): no measurement is then counted more than once, and ``b_j → N`` as consensus converges.

The L iterations and the final combination run as one compiled (numba) function on the nodes' stacked square roots
(zero-padded to a common width, each node's column count carried alongside): a step is a few dozen triangularisations
of 6 × 18 matrices, which per-call numpy overhead would otherwise dominate.
"""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np

from autonomy.estimation.linalg import tria_jit
from autonomy.estimation.measurements import MeasurementLike, MeasurementModel
from autonomy.estimation.scif import SCIF, SqrtInformation

__all__ = ["metropolis_weights", "ring_adjacency", "without_links", "hcmci", "hcmci_step", "consensus_matrix_power"]


def metropolis_weights(adjacency: np.ndarray) -> np.ndarray:
    """Metropolis weights on an undirected graph: ``a_jm = 1/(1 + max(d_j, d_m))`` on links, ``a_jj = 1 − Σ_m a_jm``.

    The result is symmetric and doubly stochastic; ``adjacency`` is a symmetric boolean (N × N) matrix (its diagonal
    is ignored).
    """
    A = np.asarray(adjacency, dtype=bool).copy()
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"adjacency must be square, got shape {A.shape}")
    if not np.array_equal(A, A.T):
        raise ValueError("adjacency must be symmetric (undirected links)")
    np.fill_diagonal(A, False)
    d = A.sum(axis=1)
    W = np.where(A, 1.0 / (1.0 + np.maximum(d[:, None], d[None, :])), 0.0)
    W[np.diag_indices_from(W)] = 1.0 - W.sum(axis=1)
    return W


def ring_adjacency(order: Sequence[int], n_nodes: int | None = None) -> np.ndarray:
    """Adjacency of the ring visiting ``order`` (0-based node ids), e.g. paper 000's 1–3–2–4–1 as ``(0, 2, 1, 3)``."""
    N = n_nodes if n_nodes is not None else max(order) + 1
    A = np.zeros((N, N), dtype=bool)
    for a, b in zip(order, list(order[1:]) + [order[0]], strict=True):
        A[a, b] = A[b, a] = True
    return A


def without_links(adjacency: np.ndarray, links: Sequence[tuple[int, int]]) -> np.ndarray:
    """A copy of ``adjacency`` with the undirected ``links`` (0-based pairs) removed."""
    A = np.asarray(adjacency, dtype=bool).copy()
    for a, b in links:
        A[a, b] = A[b, a] = False
    return A


def consensus_matrix_power(adjacency: np.ndarray, L: int) -> np.ndarray:
    """``π = A^L`` for the Metropolis weights ``A`` of ``adjacency``: node j's L-step weight on node m's data."""
    return np.linalg.matrix_power(metropolis_weights(adjacency), L)


@numba.njit(cache=True)
def _put(S: np.ndarray, j: int, T: np.ndarray) -> int:
    """``S[j, :, :w] = T``; returns w, the number of columns of T."""
    for i in range(T.shape[0]):
        for q in range(T.shape[1]):
            S[j, i, q] = T[i, q]
    return T.shape[1]


@numba.njit(cache=True)
def _average(W: np.ndarray, S: np.ndarray, w: np.ndarray, h: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One consensus iteration: node j's ``(S, h)`` ← ``(tria([√a_jm S_m]), Σ a_jm h_m)`` over its neighbours m
    (a_jm > 0, itself included). ``S`` (N, n, c) holds each node's square root in its first ``w[j]`` columns."""
    N, n, c = S.shape
    S2, w2, h2 = np.zeros((N, n, c)), np.zeros(N, np.int64), np.zeros((N, n))
    for j in range(N):
        tot = 0
        for m in range(N):
            if W[j, m] > 0:
                tot += w[m]
                for i in range(n):
                    h2[j, i] += W[j, m] * h[m, i]
        if tot == 0:
            continue
        A = np.empty((n, tot))
        col = 0
        for m in range(N):
            if W[j, m] > 0 and w[m] > 0:
                r = np.sqrt(W[j, m])
                for i in range(n):
                    for q in range(w[m]):
                        A[i, col + q] = r * S[m, i, q]
                col += w[m]
        w2[j] = _put(S2, j, tria_jit(A))
    return S2, w2, h2


@numba.njit(cache=True)
def _hcmci(W: np.ndarray, L: int, gains: np.ndarray, Sp: np.ndarray, wp: np.ndarray, hp: np.ndarray, Sc: np.ndarray,
           wc: np.ndarray, hc: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """L consensus iterations on priors (p) and contributions (c), then ``(tria([S⁻, √b S_I]), ĥ⁻ + b i)`` per node."""
    for _ in range(L):
        Sp, wp, hp = _average(W, Sp, wp, hp)
        Sc, wc, hc = _average(W, Sc, wc, hc)
    N, n, c = Sp.shape
    S_out, w_out, h_out = np.zeros((N, n, n)), np.zeros(N, np.int64), np.zeros((N, n))
    for j in range(N):
        A = np.empty((n, wp[j] + wc[j]))
        g = np.sqrt(gains[j])
        for i in range(n):
            for q in range(wp[j]):
                A[i, q] = Sp[j, i, q]
            for q in range(wc[j]):
                A[i, wp[j] + q] = g * Sc[j, i, q]
            h_out[j, i] = hp[j, i] + gains[j] * hc[j, i]
        w_out[j] = _put(S_out, j, tria_jit(A))
    return S_out, w_out, h_out


def _stack(infos: Sequence[SqrtInformation | None], n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(S (N, n, c) zero-padded, widths (N,), h (N, n)) of ``infos`` (None: no columns, h = 0)."""
    widths = np.array([0 if x is None else np.shape(x.S)[1] for x in infos], dtype=np.int64)
    S = np.zeros((len(infos), n, max(n, int(widths.max(initial=0)))))
    h = np.zeros((len(infos), n))
    for j, x in enumerate(infos):
        if x is not None:
            S[j, :, :widths[j]] = x.S
            h[j] = x.h
    return S, widths, h


def hcmci(priors: Sequence[SqrtInformation], contributions: Sequence[SqrtInformation | None], adjacency: np.ndarray,
          L: int, b: float | str = "safe") -> list[SqrtInformation]:
    """One HCMCI fusion step over the currently active graph (see the module docstring).

    Parameters
    ----------
    priors : sequence of SqrtInformation
        Each node's predicted ``(S⁻, ĥ⁻)``.
    contributions : sequence of SqrtInformation or None
        Each node's new measurement information ``(S_I, i)``; None if it measured nothing.
    adjacency : ndarray (N, N) of bool
        Active undirected links at this step.
    L : int
        Number of consensus iterations (≥ 0).
    b : float or "safe"
        Gain on the averaged measurement information (a number, e.g. N, or "safe", see the module docstring).

    Returns
    -------
    list of SqrtInformation
        Each node's posterior ``(S_h, ĥ)``.
    """
    N = len(priors)
    if len(contributions) != N:
        raise ValueError(f"contributions must have one entry per node ({N}), got {len(contributions)}")
    if L < 0:
        raise ValueError(f"L must be >= 0, got {L}")
    W = metropolis_weights(adjacency)
    if W.shape != (N, N):
        raise ValueError(f"adjacency must be {N}×{N}, got {W.shape}")
    if isinstance(b, str):
        if b != "safe":
            raise ValueError(f"b must be a positive number or 'safe', got {b!r}")
        gains = 1.0 / np.linalg.matrix_power(W, L).max(axis=1)
    else:
        if not b > 0:
            raise ValueError(f"b must be > 0, got {b}")
        gains = np.full(N, float(b))
    n = priors[0].h.size
    Sp, wp, hp = _stack(priors, n)
    Sc, wc, hc = _stack(contributions, n)
    S, w, h = _hcmci(W, int(L), gains, Sp, wp, hp, Sc, wc, hc)
    return [SqrtInformation(S[j, :, :w[j]], h[j]) for j in range(N)]


def hcmci_step(nodes: Sequence[SCIF], measurements: Sequence[MeasurementLike | None], adjacency: np.ndarray, L: int,
               b: float | str = "safe", t: float | None = None,
               models: Sequence[MeasurementModel | None] | None = None) -> None:
    """One team step: every SCIF node predicts (to its measurement's ``t_meas``, or to ``t`` if it has none), computes
    its measurement information (with ``models[j]`` if given, e.g. paper 000's nadir-angle radar, else the model of the
    measurement's kind), and the nodes' estimates are replaced by the HCMCI result over ``adjacency``."""
    if len(nodes) != len(measurements):
        raise ValueError(f"measurements must have one entry per node ({len(nodes)}), got {len(measurements)}")
    if models is None:
        models = [None] * len(nodes)
    contributions: list[SqrtInformation | None] = []
    for node, meas, model in zip(nodes, measurements, models, strict=True):
        if meas is None:
            if t is None:
                raise ValueError("t must be given when a node has no measurement")
            node.predict(t)
            contributions.append(None)
        else:
            contributions.append(node.information(meas, model)[0])
    fused = hcmci([nd.information_state for nd in nodes], contributions, adjacency, L, b)
    for node, info in zip(nodes, fused, strict=True):
        node.set_information(info)
