"""Compiled inner loops of the batched gating and of the cluster-wise assignment (:mod:`.scan_gate`,
:mod:`.assignment`, :mod:`.jpda`): per-track innovation terms of the radar and position models, the NIS of
(track, detection) pairs, the connected components of the gating graph, the trivial GNN clusters and the JPDA
enumeration. Each repeats in compiled form a formula whose reference is given in its docstring."""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["predict_linear", "radar_terms", "position_terms", "inv_logdet", "gate_pairs", "gate_all_pairs",
           "pair_clusters", "gnn_clusters", "cluster_matrix", "enumerate_events", "jpda_clusters"]

_TWO_PI = 2.0 * math.pi
_LOG_2PI = math.log(2.0 * math.pi)
_LIMIT_REL = 1e-9  # relative widening of a component bound against round-off


@numba.njit(cache=True)
def predict_linear(X, P, F, Q):
    """``F xᵢ`` and ``F Pᵢ Fᵀ + Q`` of a stack of states ``(T, n)`` and covariances ``(T, n, n)``."""
    T, n = X.shape
    Xo = np.zeros((T, n))
    Po = np.empty((T, n, n))
    FP = np.empty((n, n))
    for t in range(T):
        for a in range(n):
            s = 0.0
            for k in range(n):
                s += F[a, k] * X[t, k]
            Xo[t, a] = s
        for a in range(n):
            for b in range(n):
                s = 0.0
                for k in range(n):
                    s += F[a, k] * P[t, k, b]
                FP[a, b] = s
        for a in range(n):
            for b in range(n):
                s = 0.0
                for k in range(n):
                    s += FP[a, k] * F[b, k]
                Po[t, a, b] = s + Q[a, b]
    return Xo, Po


@numba.njit(cache=True)
def radar_terms(X, P, pos, m, p_s, R, target_height):
    """``h(x̂ᵢ)`` ``(T, m)`` and ``Sᵢ = Hᵢ Pᵢ Hᵢᵀ + R`` ``(T, m, m)`` of a radar ``[r, az(, el)]`` (m = 2, 3):
    :class:`~autonomy.estimation.measurement_models.RadarModel` (``linearise``). ``pos``: position indices (2 or 3)."""
    T, n = X.shape
    has_z = pos.size == 3
    Zp = np.empty((T, m))
    S = np.empty((T, m, m))
    H = np.zeros((m, n))
    for t in range(T):
        dx = X[t, pos[0]] - p_s[0]
        dy = X[t, pos[1]] - p_s[1]
        dz = (X[t, pos[2]] if has_z else target_height) - p_s[2]
        rho2 = dx * dx + dy * dy
        rho = math.sqrt(rho2)
        r2 = rho2 + dz * dz
        r = math.sqrt(r2)
        H[:, :] = 0.0
        H[0, pos[0]] = dx / r
        H[0, pos[1]] = dy / r
        H[1, pos[0]] = -dy / rho2
        H[1, pos[1]] = dx / rho2
        if has_z:
            H[0, pos[2]] = dz / r
        Zp[t, 0] = r
        Zp[t, 1] = math.atan2(dy, dx)
        if m == 3:
            c = -dz / (rho * r2)
            H[2, pos[0]] = c * dx
            H[2, pos[1]] = c * dy
            if has_z:
                H[2, pos[2]] = rho / r2
            Zp[t, 2] = math.atan2(dz, rho)
        _hph(H, P[t], R, S[t])
    return Zp, S


@numba.njit(cache=True)
def position_terms(X, P, idx, R):
    """``x̂ᵢ[idx]`` and ``Sᵢ = P_idx,idx + R`` of a position measurement
    (:class:`~autonomy.estimation.measurement_models.PositionModel`)."""
    T = X.shape[0]
    m = idx.size
    Zp = np.empty((T, m))
    S = np.empty((T, m, m))
    for t in range(T):
        for a in range(m):
            Zp[t, a] = X[t, idx[a]]
            for b in range(m):
                S[t, a, b] = P[t, idx[a], idx[b]] + R[a, b]
    return Zp, S


@numba.njit(cache=True)
def _hph(H, P, R, out):
    m, n = H.shape
    for a in range(m):
        for b in range(a, m):
            s = 0.0
            for k in range(n):
                if H[a, k] == 0.0:
                    continue
                hk = 0.0
                for q in range(n):
                    hk += P[k, q] * H[b, q]
                s += H[a, k] * hk
            out[a, b] = s + R[a, b]
            out[b, a] = s + R[b, a]


@numba.njit(cache=True)
def inv_logdet(S):
    """``S⁻¹`` and ``log det S`` (NaN where ``det S <= 0``) of a stack ``(T, m, m)``."""
    T, m, _ = S.shape
    inv = np.empty_like(S)
    logdet = np.empty(T)
    for t in range(T):
        if m == 1:
            d = S[t, 0, 0]
            inv[t, 0, 0] = 1.0 / d
        elif m == 2:
            a, b, c, e = S[t, 0, 0], S[t, 0, 1], S[t, 1, 0], S[t, 1, 1]
            d = a * e - b * c
            inv[t, 0, 0], inv[t, 0, 1], inv[t, 1, 0], inv[t, 1, 1] = e / d, -b / d, -c / d, a / d
        else:
            inv[t] = np.linalg.inv(S[t])
            d = np.linalg.det(S[t])
        logdet[t] = math.log(d) if d > 0.0 else np.nan
    return inv, logdet


@numba.njit(cache=True)
def _limits(S, gamma):
    T, m, _ = S.shape
    lim = np.empty((T, m))
    for t in range(T):
        for k in range(m):
            lim[t, k] = math.sqrt(gamma * max(S[t, k, k], 0.0)) * (1.0 + _LIMIT_REL) + 1e-300
    return lim


@numba.njit(cache=True)
def _gate(ti, dj, every, Z, Zp, S, S_inv, logdet, ang, gamma):
    """:func:`gate_pairs` (``every`` False) or :func:`gate_all_pairs` (``every`` True: ``ti``, ``dj`` unused)."""
    T, D, m = Zp.shape[0], Z.shape[0], Z.shape[1]
    lim = _limits(S, gamma)
    nu = np.empty(m)
    n = T * D if every else ti.size
    rows = np.empty(n, np.int64)
    cols = np.empty(n, np.int64)
    nis = np.empty(n)
    cost = np.empty(n)
    c = 0
    i, j = 0, -1
    for p in range(n):
        if every:  # row-major, without a division per pair
            j += 1
            if j == D:
                i, j = i + 1, 0
        else:
            i, j = ti[p], dj[p]
        inside = True
        for k in range(m):
            v = Z[j, k] - Zp[i, k]
            if ang[k] and (v < -math.pi or v >= math.pi):
                v = (v + math.pi) % _TWO_PI - math.pi
            if abs(v) > lim[i, k]:
                inside = False
                break
            nu[k] = v
        if not inside:
            continue
        q = 0.0
        for a in range(m):
            s = 0.0
            for b in range(m):
                s += S_inv[i, a, b] * nu[b]
            q += nu[a] * s
        if q <= gamma:
            rows[c], cols[c], nis[c] = i, j, q
            cost[c] = q + logdet[i] + m * _LOG_2PI
            c += 1
    return rows[:c], cols[:c], nis[:c], cost[:c]


def gate_pairs(ti: np.ndarray, dj: np.ndarray, Z: np.ndarray, Zp: np.ndarray, S: np.ndarray, S_inv: np.ndarray,
               logdet: np.ndarray, ang: np.ndarray, gamma: float) -> tuple[np.ndarray, ...]:
    """The gated ones among candidate pairs ``(ti, dj)``: ``(rows, cols, nis, cost)``, cost
    ``nis + log det S + m log 2π``. A pair is first tested component-wise, ``|νₖ| ≤ √(γ Sₖₖ)`` (necessary for
    ``νᵀS⁻¹ν ≤ γ``), then by its NIS. Angle components are wrapped to ``[−π, π)`` as
    ``MeasurementModel.residual`` wraps them, the modulo only when the difference lies outside (inside, the two
    agree to one ulp of π)."""
    return _gate(ti, dj, False, Z, Zp, S, S_inv, logdet, ang, gamma)


_NO_PAIRS = np.zeros(0, np.int64)


def gate_all_pairs(Z: np.ndarray, Zp: np.ndarray, S: np.ndarray, S_inv: np.ndarray, logdet: np.ndarray,
                   ang: np.ndarray, gamma: float) -> tuple[np.ndarray, ...]:
    """:func:`gate_pairs` over every (track, detection) pair, row-major."""
    return _gate(_NO_PAIRS, _NO_PAIRS, True, Z, Zp, S, S_inv, logdet, ang, gamma)


@numba.njit(cache=True)
def _root(parent, a):
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


@numba.njit(cache=True)
def pair_clusters(rows, cols, n_t):
    """Connected components of the bipartite gating graph (union-find): the pairs sorted by component,
    ``(order, starts)`` with the pairs of component c at ``order[starts[c]:starts[c + 1]]``, components in order of
    their first pair."""
    n_p = rows.size
    n_d = 0
    for p in range(n_p):
        n_d = max(n_d, cols[p] + 1)
    parent = np.arange(n_t + n_d)
    for p in range(n_p):
        a, b = _root(parent, rows[p]), _root(parent, n_t + cols[p])
        if a != b:
            parent[b] = a
    label = np.full(n_t + n_d, -1, np.int64)
    lab = np.empty(n_p, np.int64)
    n_c = 0
    for p in range(n_p):
        r = _root(parent, rows[p])
        if label[r] < 0:
            label[r] = n_c
            n_c += 1
        lab[p] = label[r]
    counts = np.zeros(n_c + 1, np.int64)
    for p in range(n_p):
        counts[lab[p] + 1] += 1
    starts = np.cumsum(counts)
    fill = starts[:-1].copy()
    order = np.empty(n_p, np.int64)
    for p in range(n_p):
        order[fill[lab[p]]] = p
        fill[lab[p]] += 1
    return order, starts


@numba.njit(cache=True)
def _local(rows, cols, values, fill, order, s, e, lt, ld, tracks, dets):
    """The dense ``(k, n)`` matrix of one component's pair ``values`` (``fill`` elsewhere), its tracks and detections
    (``tracks[:k]``, ``dets[:n]``, in order of first pair) and the pair index of each entry (−1 elsewhere). ``lt``,
    ``ld`` are all −1 on entry and on return."""
    k, n = 0, 0
    for q in range(s, e):
        p = order[q]
        if lt[rows[p]] < 0:
            lt[rows[p]] = k
            tracks[k] = rows[p]
            k += 1
        if ld[cols[p]] < 0:
            ld[cols[p]] = n
            dets[n] = cols[p]
            n += 1
    M = np.full((k, n), fill)
    at = np.full((k, n), -1, np.int64)
    for q in range(s, e):
        p = order[q]
        M[lt[rows[p]], ld[cols[p]]] = values[p]
        at[lt[rows[p]], ld[cols[p]]] = p
    for a in range(k):
        lt[tracks[a]] = -1
    for b in range(n):
        ld[dets[b]] = -1
    return M, at, k, n


@numba.njit(cache=True)
def _least_cost_event(C, miss, max_events):
    """Exhaustive search of the least-cost assignment of a small component: ``C`` ``(k, n)`` pair costs (``inf``
    outside the gate), ``miss`` ``(k,)``. Returns the chosen detection per track (−1: none), or None past
    ``max_events`` complete assignments."""
    k, n = C.shape
    used = np.zeros(n, np.bool_)
    opt = np.full(k, -2, np.int64)  # −1 = miss, j = detection j; −2 = not started
    acc = np.zeros(k + 1)
    best = np.full(k, -1, np.int64)
    best_cost = np.inf
    count = 0
    i = 0
    while i >= 0:
        o = opt[i]
        if o >= 0:
            used[o] = False
        o += 1
        while o < n and (o >= 0 and (used[o] or not C[i, o] < np.inf)):
            o += 1
        if o >= n:
            opt[i] = -2
            i -= 1
            continue
        opt[i] = o
        if o >= 0:
            used[o] = True
            acc[i + 1] = acc[i] + C[i, o]
        else:
            acc[i + 1] = acc[i] + miss[i]
        if i == k - 1:
            count += 1
            if count > max_events:
                return None
            if acc[k] < best_cost:
                best_cost = acc[k]
                best[:] = opt
        else:
            i += 1
    return best


@numba.njit(cache=True)
def gnn_clusters(rows, cols, cost, miss, order, starts, n_t, n_d, max_events):
    """Least-cost assignment of each component with at most ``max_events`` complete assignments, by exhaustive
    search (a component of one track or one detection directly). Returns ``(chosen pair indices, components left to
    the general solver)``."""
    lt = np.full(n_t, -1, np.int64)
    ld = np.full(n_d, -1, np.int64)
    tracks = np.empty(n_t, np.int64)
    dets = np.empty(n_d, np.int64)
    take = []
    hard = []
    for c in range(starts.size - 1):
        s, e = starts[c], starts[c + 1]
        if e - s == 1:
            p = order[s]
            if cost[p] < miss[rows[p]]:
                take.append(p)
            continue
        C, at, k, n = _local(rows, cols, cost, np.inf, order, s, e, lt, ld, tracks, dets)
        if k == 1 or n == 1:  # one track: its cheapest detection; one detection: its largest saving
            best, gain = -1, 0.0
            for a in range(k):
                for b in range(n):
                    if at[a, b] >= 0 and miss[tracks[a]] - C[a, b] > gain:
                        best, gain = at[a, b], miss[tracks[a]] - C[a, b]
            if best >= 0:
                take.append(best)
            continue
        choice = _least_cost_event(C, miss[tracks[:k]], max_events)
        if choice is None:
            hard.append(c)
            continue
        for a in range(k):
            if choice[a] >= 0:
                take.append(at[a, choice[a]])
    return np.array(take, np.int64), np.array(hard, np.int64)


@numba.njit(cache=True)
def cluster_matrix(rows, cols, cost, order, s, e, n_t, n_d):
    """:func:`_local` of one component for the general solver: ``(cost matrix, pair index per entry, tracks)``."""
    lt = np.full(n_t, -1, np.int64)
    ld = np.full(n_d, -1, np.int64)
    tracks = np.empty(n_t, np.int64)
    C, at, k, n = _local(rows, cols, cost, np.inf, order, s, e, lt, ld, tracks, np.empty(n_d, np.int64))
    return C, at, tracks[:k]


@numba.njit(cache=True)
def enumerate_events(W, max_events, beta):
    """Exhaustive feasible joint events of one cluster (:mod:`.jpda`); ``W`` ``(k, n + 1)`` option weights (column 0
    the miss, 0 = not allowed). Adds the event weights into ``beta`` and returns their sum, or −1 past
    ``max_events`` events."""
    k, n1 = W.shape
    used = np.zeros(n1, np.bool_)
    opt = np.full(k, -1, np.int64)
    w = np.ones(k + 1)
    total, count = 0.0, 0
    i = 0
    while i >= 0:
        o = opt[i]
        if o > 0:
            used[o] = False
        o += 1
        while o < n1 and (W[i, o] == 0.0 or (o > 0 and used[o])):
            o += 1
        if o >= n1:
            opt[i] = -1
            i -= 1
            continue
        opt[i] = o
        if o > 0:
            used[o] = True
        w[i + 1] = w[i] * W[i, o]
        if i == k - 1:
            count += 1
            if count > max_events:
                return -1.0
            total += w[k]
            for t in range(k):
                beta[t, opt[t]] += w[k]
        else:
            i += 1
    return total


@numba.njit(cache=True)
def jpda_clusters(rows, cols, log_ratio, log_miss, order, starts, n_t, n_d, max_events):
    """JPDA marginals of every component by :func:`enumerate_events`: β ``(n_t, n_d + 1)`` (rows of tracks without a
    gated detection are ``[1, 0, …]``) and the components that exceeded ``max_events`` (their rows left as is)."""
    beta = np.zeros((n_t, n_d + 1))
    beta[:, 0] = 1.0
    lt = np.full(n_t, -1, np.int64)
    ld = np.full(n_d, -1, np.int64)
    tracks = np.empty(n_t, np.int64)
    dets = np.empty(n_d, np.int64)
    failed = []
    for c in range(starts.size - 1):
        s, e = starts[c], starts[c + 1]
        Lr, at, k, n = _local(rows, cols, log_ratio, -np.inf, order, s, e, lt, ld, tracks, dets)
        L = np.empty((k, n + 1))
        L[:, 0] = log_miss
        L[:, 1:] = Lr
        W = np.zeros((k, n + 1))
        for a in range(k):
            mx = -np.inf
            for b in range(n + 1):
                mx = max(mx, L[a, b])
            for b in range(n + 1):
                W[a, b] = math.exp(L[a, b] - mx) if L[a, b] > -np.inf else 0.0
        b_loc = np.zeros((k, n + 1))
        total = enumerate_events(W, max_events, b_loc)
        if total > 0.0:
            for a in range(k):
                beta[tracks[a], 0] = b_loc[a, 0] / total
                for b in range(n):
                    beta[tracks[a], dets[b] + 1] = b_loc[a, b + 1] / total
        else:
            failed.append(c)
    return beta, np.array(failed, np.int64)
