"""Joint probabilistic data association (JPDA) of one scan, and the PDA update it feeds.

For a sensor group of a scan gated against many tracks (:class:`~.scan_gate.ScanGating`), a **feasible joint event**
gives each track at most one of its gated detections and each detection at most one track. With detection
probability ``P_D``, gate probability ``P_G`` and clutter density ``λ`` (false detections per unit of measurement
space), its weight is

``w(e) = Π_{(i, j) ∈ e} P_D N(νᵢⱼ; 0, Sᵢⱼ) / λ · Π_{i missed in e} (1 − P_D P_G)``

(Bar-Shalom, Daum and Huang 2009, the parametric JPDA), and the marginal association probabilities are
``βᵢⱼ = Σ_{e ∋ (i, j)} w(e) / Σ_e w(e)``, ``βᵢ₀ = Σ_{e: i missed} w(e) / Σ_e w(e)``. Events of different connected
components ("clusters") of the gating graph are independent, so each cluster is enumerated alone, exhaustively, by a
depth-first search over its tracks (each extended by a miss or by any gated detection not yet taken), in compiled
code (:func:`~.assignment_kernels.enumerate_events`). Each track's options are scaled by one common factor first (the
largest of them), which leaves every β unchanged and keeps the products in range.

When a cluster would have more than ``max_cluster_events`` events the enumeration stops and the cluster's weights
come from Fitzgerald's cheap JPDA (Fitzgerald 1985): with ``Lᵢⱼ`` the likelihood ratios above, ``Tᵢ = Σⱼ Lᵢⱼ`` and
``Cⱼ = Σᵢ Lᵢⱼ``, ``βᵢⱼ ∝ Lᵢⱼ / (Tᵢ + Cⱼ − Lᵢⱼ + B)`` and ``βᵢ₀ ∝ (1 − P_D P_G) / (Tᵢ + B)`` with ``B = 1 − P_D P_G``,
each row normalised to 1. It equals the exact marginals for a track alone in its cluster and discounts a detection
that other tracks compete for; :attr:`JointProbabilisticAssociator.approximated` counts the clusters it served.

:func:`pda_update` applies a track's row of β to its filter (the PDA moment-matched update).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence

import numpy as np

from autonomy.estimation.base import Filter
from autonomy.estimation.measurements import MeasurementLike

from . import assignment_kernels as kernels
from .assignment import ScanAssignment, sensor_groups, single_group, unused_and_gated_out
from .class_affinity import ClassAffinity
from .gate import ChiSquareGate, PredictedNis
from .scan_gate import GatedCosts, ScanGating
from .track import Track

__all__ = ["JointProbabilisticAssociator", "pda_update", "cluster_marginals"]


class JointProbabilisticAssociator:
    """JPDA marginal association probabilities of a sensor group's detections (module docstring).

    Parameters
    ----------
    gate : ChiSquareGate
        The validation gate (its probability is ``P_G``).
    distance : PredictedNis
        The pairwise NIS the batched gating reproduces.
    detection_probability : float
        ``P_D`` in (0, 1].
    clutter_density : float
        ``λ`` > 0, false detections per unit volume of the measurement space (e.g. per m·rad for a radar
        ``[r, az]``).
    max_cluster_events : int
        Largest number of joint events enumerated in one cluster (>= 1); beyond it the cheap-JPDA approximation.
    kdtree_min_pairs : int
        From how many pairs radar and position detections are pre-gated with a k-d tree
        (:class:`~.scan_gate.ScanGating`).
    affinity : ClassAffinity or None
        Classification-aided association (:mod:`.class_affinity`): a gated pair's log-likelihood ratio gains the
        ``log λ`` of its detection's class readings against the track's. None: kinematics alone.

    Attributes
    ----------
    approximated : int
        Clusters whose weights came from the approximation.
    """

    def __init__(self, gate: ChiSquareGate, distance: PredictedNis, detection_probability: float,
                 clutter_density: float, max_cluster_events: int = 10_000, kdtree_min_pairs: int = 40_000,
                 affinity: ClassAffinity | None = None) -> None:
        if not 0.0 < detection_probability <= 1.0:
            raise ValueError(f"JointProbabilisticAssociator.detection_probability must be in (0, 1], got "
                             f"{detection_probability!r}")
        if not (np.isfinite(clutter_density) and clutter_density > 0):
            raise ValueError(f"JointProbabilisticAssociator.clutter_density must be finite and > 0, got "
                             f"{clutter_density!r}")
        if int(max_cluster_events) != max_cluster_events or max_cluster_events < 1:
            raise ValueError(f"JointProbabilisticAssociator.max_cluster_events must be an integer >= 1, got "
                             f"{max_cluster_events!r}")
        self.gate = gate
        self.gating = ScanGating(gate, distance, kdtree_min_pairs)
        self.detection_probability = float(detection_probability)
        self.clutter_density = float(clutter_density)
        self.max_cluster_events = int(max_cluster_events)
        self.affinity = affinity
        self.approximated = 0

    def assign(self, tracks: Sequence[Track], scan: Sequence[MeasurementLike]) -> ScanAssignment:
        """β of ``scan`` (the detections of one sensor and one time) against ``tracks``."""
        dets = single_group(scan)
        costs = self.gating(tracks, dets)
        extra = None
        if self.affinity is not None and costs.rows.size:
            extra = self.affinity.log_ratios(tracks, dets, costs.rows, costs.cols)
        return self.assign_costs(dets, costs, extra)

    def assign_groups(self, tracks: Sequence[Track], scan: Sequence[MeasurementLike]) -> list[ScanAssignment]:
        """One :meth:`assign` per sensor group of ``scan``, in order of first appearance."""
        return [self.assign(tracks, g) for g in sensor_groups(scan)]

    def assign_costs(self, dets: tuple[MeasurementLike, ...], costs: GatedCosts,
                     extra: np.ndarray | None = None) -> ScanAssignment:
        """β from already gated costs of ``dets`` (``extra``: a log-likelihood ratio added to each gated pair's,
        e.g. the class readings' ``log λ``, :mod:`.class_affinity`)."""
        n_t, n_d = costs.shape
        beta = np.zeros((n_t, n_d + 1))
        beta[:, 0] = 1.0
        log_miss = np.log1p(-self.detection_probability * self.gate.probability) if (
            self.detection_probability * self.gate.probability < 1.0) else -np.inf
        rows, cols = costs.rows, costs.cols
        log_ratio = -0.5 * costs.cost[rows, cols] + math.log(self.detection_probability / self.clutter_density)
        if extra is not None:
            log_ratio = log_ratio + extra
        order, starts = kernels.pair_clusters(rows, cols, n_t)
        beta, failed = kernels.jpda_clusters(rows, cols, log_ratio, log_miss, order, starts, n_t, n_d,
                                             self.max_cluster_events)
        for c in failed:
            sel = order[starts[c]:starts[c + 1]]
            ti, dj = np.unique(rows[sel]), np.unique(cols[sel])
            L = np.full((ti.size, dj.size), -np.inf)
            L[np.searchsorted(ti, rows[sel]), np.searchsorted(dj, cols[sel])] = log_ratio[sel]
            beta[np.ix_(ti, np.r_[0, dj + 1])] = _cheap_jpda(L, log_miss)
        self.approximated += len(failed)
        assigned = np.zeros(n_d, dtype=bool)
        assigned[costs.cols] = True
        unused, gated_out = unused_and_gated_out(costs, assigned)
        pairs = tuple(zip(costs.rows.tolist(), costs.cols.tolist(), strict=True))
        return ScanAssignment(detections=dets, pairs=pairs, weights=beta, unused=unused, gated_out=gated_out,
                              costs=costs)


def cluster_marginals(log_L: np.ndarray, log_miss: float, max_events: int) -> tuple[np.ndarray, bool]:
    """Marginal association probabilities of one cluster.

    Parameters
    ----------
    log_L : ndarray
        ``(k, n)`` log likelihood ratios ``log(P_D N(ν; 0, S)/λ)``, ``-inf`` outside the gate.
    log_miss : float
        ``log(1 − P_D P_G)`` (``-inf`` when a track is always detected inside its gate).
    max_events : int
        Enumeration limit (module docstring).

    Returns
    -------
    beta : ndarray
        ``(k, n + 1)``; column 0 the miss.
    exact : bool
        False when the cheap-JPDA approximation was used.
    """
    k, n = log_L.shape
    # scaling all of a track's options by one factor leaves β unchanged: each event holds one option per track
    opts = np.concatenate([np.full((k, 1), log_miss), np.asarray(log_L, dtype=float)], axis=1)
    shift = np.max(opts, axis=1, keepdims=True)
    shift[~np.isfinite(shift)] = 0.0
    W = np.exp(opts - shift)  # (k, n + 1), column 0 the miss, 0 outside the gate
    beta = np.zeros((k, n + 1))
    total = kernels.enumerate_events(W, max_events, beta)
    if not total > 0.0:
        return _cheap_jpda(log_L, log_miss), False
    return beta / total, True


def _cheap_jpda(log_L: np.ndarray, log_miss: float) -> np.ndarray:
    """Fitzgerald's cheap JPDA (module docstring) from the log likelihood ratios and ``log(1 − P_D P_G)``."""
    L = np.exp(log_L)
    B = float(np.exp(log_miss))
    T = L.sum(axis=1, keepdims=True)
    C = L.sum(axis=0, keepdims=True)
    out = np.empty((L.shape[0], L.shape[1] + 1))
    out[:, 1:] = L / (T + C - L + B)
    out[:, :1] = B / (T + B)
    return out / out.sum(axis=1, keepdims=True)


def pda_update(filter: Filter, detections: Sequence[MeasurementLike], betas: Sequence[float] | np.ndarray) -> None:
    """Probabilistic data association update of ``filter`` with the detections of one time and their β.

    ``betas[0]`` is the probability that none of ``detections`` is the track's, ``betas[j + 1]`` that
    ``detections[j]`` is. The filter is predicted to the detections' time (``x₀, P₀``); a deep copy of it is
    updated with each detection of ``βⱼ > 0`` (``xⱼ, Pⱼ``: any filter, any measurement model); the mixture is
    moment-matched, ``x = Σⱼ βⱼ xⱼ``, ``P = Σⱼ βⱼ (Pⱼ + (xⱼ − x)(xⱼ − x)ᵀ)`` (j from 0), and written back with
    :meth:`Filter.set_state`. With one β equal to 1 the filter is updated with that detection alone (or only
    predicted), exactly as a plain update. A filter that holds a mixture (IMM, a road-network filter) is collapsed by
    ``set_state`` onto the moment-matched Gaussian, keeping its mode weights of before the update. A filter whose
    ``set_state`` raises ``NotImplementedError`` is updated with the detection of the largest β instead.
    """
    dets = tuple(detections)
    b = np.asarray(betas, dtype=float).reshape(-1)
    if b.size != len(dets) + 1:
        raise ValueError(f"betas must have len(detections) + 1 = {len(dets) + 1} entries, got {b.size}")
    if np.any(b < 0) or not np.isclose(b.sum(), 1.0, rtol=0.0, atol=1e-9):
        raise ValueError(f"betas must be >= 0 and sum to 1, got {b!r}")
    if not dets:
        return
    t = float(dets[0].t_meas)
    if any(float(d.t_meas) != t for d in dets):
        raise ValueError("pda_update needs detections of one time t_meas")
    filter.predict(t)
    best = int(np.argmax(b))
    if b[best] == 1.0:
        if best > 0:
            filter.update(dets[best - 1])
        return
    xs, Ps, ws = [np.array(filter.x, dtype=float)], [np.array(filter.P, dtype=float)], [b[0]]
    for j, d in enumerate(dets):
        if b[j + 1] > 0.0:
            f = copy.deepcopy(filter)
            f.update(d)
            xs.append(np.array(f.x, dtype=float))
            Ps.append(np.array(f.P, dtype=float))
            ws.append(b[j + 1])
    X, Pst, w = np.array(xs), np.array(Ps), np.array(ws)
    x = w @ X
    D = X - x
    P = np.einsum("k,kij->ij", w, Pst) + (D * w[:, None]).T @ D
    try:
        filter.set_state(x, 0.5 * (P + P.T), t)
    except NotImplementedError:
        if best > 0:
            filter.update(dets[best - 1])
