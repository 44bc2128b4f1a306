"""Set fusion of a team of set-membership estimators over the links that are up (paper 004, eqs. 15-16).

Each UAV fuses its post-correction sets with those of the neighbours it is linked to
(:meth:`~autonomy.estimation.setmem.estimator.SetMembershipEstimator.fuse`). UAVs linked to the same UAVs (themselves
included) fuse the same sets in the same order, so the fusion runs once per such group and the others adopt the
result, which is bit-identical to fusing themselves
(:meth:`~autonomy.estimation.setmem.estimator.SetMembershipEstimator.adopt`).

Only sets of one time can be fused. The team fuses at the newest post-correction time among its members; a UAV whose
last correction is older (it took no scan at that time) sits this fusion out: it neither fuses nor lends its sets.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from autonomy.estimation.setmem.estimator import SetEstimate, SetMembershipEstimator

__all__ = ["fuse_team_sets"]

_SAME_TIME = 1e-9  # s


def fuse_team_sets(estimators: Sequence[SetMembershipEstimator], adjacency: np.ndarray) -> np.ndarray:
    """Fuse every estimator with its linked neighbours (module docstring).

    Parameters
    ----------
    estimators : Sequence[SetMembershipEstimator]
        One per UAV, in team order.
    adjacency : np.ndarray
        (N, N) bool, symmetric: which UAVs are linked (the diagonal is ignored).

    Returns
    -------
    np.ndarray
        (N,) int: how many neighbours' sets each UAV fused (0 for a UAV that sat the fusion out).
    """
    n = len(estimators)
    A = np.asarray(adjacency, dtype=bool)
    if A.shape != (n, n):
        raise ValueError(f"adjacency must be ({n}, {n}) for {n} estimators, got {A.shape}")
    shared = [e.shared for e in estimators]
    if not n:
        return np.zeros(0, dtype=int)
    t = max(s.t for s in shared)
    current = np.array([abs(s.t - t) <= _SAME_TIME for s in shared])
    fused: dict[tuple[int, ...], SetEstimate] = {}
    used = np.zeros(n, dtype=int)
    for i, est in enumerate(estimators):
        if not current[i]:
            continue
        nbrs = [int(j) for j in np.flatnonzero(A[i] & current) if j != i]
        used[i] = len(nbrs)
        group = tuple(sorted({i, *nbrs}))
        if group in fused:
            est.adopt(fused[group])
        else:
            fused[group] = est.fuse([shared[j] for j in nbrs])
    return used
