"""Team metrics: consensus disagreement and average trace of the information matrix."""

from __future__ import annotations

import numpy as np

__all__ = ["consensus_disagreement", "max_consensus_disagreement", "average_information_trace"]


def consensus_disagreement(estimates: np.ndarray) -> np.ndarray:
    """Distance of each node's estimate from the mean of all nodes' estimates.

    Parameters
    ----------
    estimates : ndarray, shape (..., N, d)
        One estimate (e.g. a position, m) per node along axis −2.

    Returns
    -------
    ndarray, shape (..., N)
        ``‖x̂_j − (1/N) Σ_m x̂_m‖`` (paper 000's consensus error), same unit as the estimates.
    """
    E = np.asarray(estimates, dtype=float)
    return np.linalg.norm(E - E.mean(axis=-2, keepdims=True), axis=-1)


def max_consensus_disagreement(estimates: np.ndarray) -> float:
    """Largest :func:`consensus_disagreement` over nodes (and leading axes)."""
    return float(np.max(consensus_disagreement(estimates)))


def average_information_trace(Y: np.ndarray) -> float:
    """Mean of ``tr(Y)`` over information matrices ``Y`` of shape (..., n, n) (paper 001's "avg tr(FIM)")."""
    return float(np.mean(np.trace(np.asarray(Y, dtype=float), axis1=-2, axis2=-1)))
