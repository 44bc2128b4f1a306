"""Route probabilities to the base station for many candidate team geometries at once.

Link probabilities come from :meth:`autonomy.sensing.channel.ChannelConfig.delivery_probability` (Rayleigh fading,
``Pr(d) = exp(−k d^α)``). Routes are the paths of the minimum spanning tree with weights ``−ln Pr`` rooted at the base
(Liu, Fu & Gao 2018, §4.2), the tree :func:`autonomy.sensing.channel.minimum_spanning_tree_routes` builds for one
geometry. A planner scores thousands of candidate geometries per step, so :func:`mst_route_probabilities` runs Prim's
algorithm vectorised over a batch (same tree, same ``β``; the tests check the two agree). The fixed relay chain of the
baseline routes UAV i through UAVs i−1, …, 0 to the base.
"""

from __future__ import annotations

import numpy as np

from autonomy.sensing.channel import ChannelConfig, minimum_spanning_tree_routes

__all__ = ["link_probabilities", "mst_route_probabilities", "chain_route_probabilities", "planning_hierarchy"]


def link_probabilities(p_W: np.ndarray, channel: ChannelConfig) -> np.ndarray:
    """(..., M, M) link delivery probabilities between the M nodes at horizontal positions ``p_W`` (..., M, 2) (m)."""
    p = np.asarray(p_W, dtype=float)
    d = np.linalg.norm(p[..., :, None, :] - p[..., None, :, :], axis=-1)
    P = channel.delivery_probability(d)
    idx = np.arange(p.shape[-2])
    P[..., idx, idx] = 1.0
    return P


def mst_route_probabilities(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Route probabilities β and hop counts over the minimum spanning tree, for a batch of graphs.

    Parameters
    ----------
    P : np.ndarray
        (B, M, M) symmetric link probabilities; node 0 is the base station (the root).

    Returns
    -------
    beta : np.ndarray
        (B, M) product of the hop probabilities along each node's tree path (1 for the root, 0 if cut off).
    hops : np.ndarray
        (B, M) hop counts to the root (0 for the root, -1 if cut off).
    """
    P = np.asarray(P, dtype=float)
    B, M, _ = P.shape
    with np.errstate(divide="ignore"):
        W = np.where(P > 0, -np.log(np.clip(P, 1e-300, 1.0)), np.inf)
    rows = np.arange(B)
    in_tree = np.zeros((B, M), dtype=bool)
    in_tree[:, 0] = True
    best = W[:, 0, :].copy()
    parent = np.zeros((B, M), dtype=int)
    beta = np.zeros((B, M))
    beta[:, 0] = 1.0
    hops = np.full((B, M), -1)
    hops[:, 0] = 0
    for _ in range(M - 1):
        cand = np.where(in_tree, np.inf, best)
        j = np.argmin(cand, axis=1)
        ok = np.isfinite(cand[rows, j])
        pj = parent[rows, j]
        in_tree[rows, j] = True
        beta[rows, j] = np.where(ok, beta[rows, pj] * P[rows, pj, j], 0.0)
        hops[rows, j] = np.where(ok, hops[rows, pj] + 1, -1)
        w_new = np.where(ok[:, None], W[rows, j, :], np.inf)
        better = w_new < best
        best = np.where(better, w_new, best)
        parent = np.where(better, j[:, None], parent)
    return beta, hops


def chain_route_probabilities(P: np.ndarray) -> np.ndarray:
    """(B, M) route probabilities of the fixed chain: node m relays through m−1, …, 1 to the base (node 0)."""
    P = np.asarray(P, dtype=float)
    M = P.shape[-1]
    hop = P[..., np.arange(1, M), np.arange(0, M - 1)]
    return np.concatenate([np.ones(P.shape[:-2] + (1,)), np.cumprod(hop, axis=-1)], axis=-1)


def planning_hierarchy(p_base_W: np.ndarray, p_uav_W: np.ndarray, channel: ChannelConfig) -> tuple[list[int],
                                                                                                    np.ndarray]:
    """Planning order and current route probabilities (§4.2).

    UAVs are sorted by hop count over the current minimum spanning tree, then by index; cut-off UAVs come last.

    Returns
    -------
    order : list[int]
        UAV indices in planning order.
    parent : np.ndarray
        (N,) next hop of each UAV: a UAV index, -1 for the base, -2 if cut off.
    """
    p_uav = np.asarray(p_uav_W, dtype=float)[:, :2]
    n = p_uav.shape[0]
    nodes = ["base", *[f"uav{i}" for i in range(n)]]
    P = link_probabilities(np.vstack([np.asarray(p_base_W, float)[:2], p_uav]), channel)
    tree = minimum_spanning_tree_routes(nodes, P, "base")
    hops = [tree.hops(f"uav{i}") for i in range(n)]
    order = sorted(range(n), key=lambda i: (hops[i] if hops[i] >= 0 else n + 1, i))
    parent = np.full(n, -2)
    for i in range(n):
        nxt = tree.parent[f"uav{i}"]
        if nxt is not None:
            parent[i] = -1 if nxt == "base" else int(nxt[3:])
    return order, parent
