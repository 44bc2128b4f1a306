"""Global nearest-neighbour (GNN) assignment of one scan's detections to many tracks.

The scan's detections are split per sensor (one sensor group: one ``sensor_id``, one ``t_meas``); each group is gated
against every track at once (:class:`~.scan_gate.ScanGating`) and assigned by one optimal assignment: each track takes
at most one detection of the group, each detection goes to at most one track, a pair outside the gate is never
assigned, and the total cost ``Σ −2 log N(νᵢⱼ; 0, Sᵢⱼ)`` of the pairs plus the cost of the tracks left without a
detection is least. The problem is the rectangular assignment of the gated cost matrix augmented with one "no
detection" column per track (its own miss cost on the diagonal, ``inf`` off it), solved on each connected component
("cluster") of the bipartite gating graph in turn: components share no track and no detection, so their optimal
assignments are independent, and a sparse gate makes each small. A component of one track or one detection is solved
directly, one of at most ``max_enumerated`` feasible assignments by exhaustive search in compiled code, a larger one
by ``scipy.optimize.linear_sum_assignment`` (all three optimal; the first two avoid the solver's call cost on the
many small components).

A track's miss cost is ``miss_cost`` when given, else the largest cost a detection on the boundary of the track's
gate would have (``χ²_m(p) + log det(2πSᵢⱼ)`` over its gated detections): with it a gated detection is never worse
than none for the track alone, which is Blackman and Popoli's choice of the non-assignment cost at the gate.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from autonomy.estimation.measurements import MeasurementLike

from . import assignment_kernels as kernels
from .class_affinity import ClassAffinity
from .gate import ChiSquareGate, PredictedNis
from .scan_gate import GatedCosts, ScanGating
from .track import Track

__all__ = ["GatedCosts", "ScanGating", "ScanAssignment", "GlobalNearestNeighbourAssociator", "gating_clusters",
           "sensor_groups", "solve_component"]


@dataclass(frozen=True, eq=False)
class ScanAssignment:
    """How one sensor group of a scan is shared among the tracks.

    Attributes
    ----------
    detections : tuple
        The group's detections (one sensor, one time); detection indices below index this tuple.
    pairs : tuple of (int, int)
        ``(track index, detection index)`` of the assigned pairs (GNN), or of every gated pair (JPDA, whose
        ``weights`` say how much each counts); sorted by track index.
    weights : ndarray or None
        None for GNN; for JPDA the marginal association probabilities βᵢⱼ, shape ``(n_tracks, n_dets + 1)``, column
        0 the probability that the track's detection is not in the group, column ``j + 1`` that it is detection
        ``j``; each row sums to 1.
    unused : tuple of int
        Detections assigned to no track (GNN), or in no track's gate (JPDA): what the initiator gets.
    gated_out : tuple of int
        Detections in no track's gate.
    costs : GatedCosts
        The gated NIS and cost matrices the assignment was made from.
    """

    detections: tuple[MeasurementLike, ...]
    pairs: tuple[tuple[int, int], ...]
    weights: np.ndarray | None
    unused: tuple[int, ...]
    gated_out: tuple[int, ...]
    costs: GatedCosts

    def detection_of(self, track: int) -> int | None:
        """The detection index assigned to track ``track`` (GNN), or None."""
        for i, j in self.pairs:
            if i == track:
                return j
        return None


def sensor_groups(scan: Sequence[MeasurementLike]) -> list[tuple[MeasurementLike, ...]]:
    """The scan's detections per ``sensor_id``, in order of first appearance."""
    groups: dict[object, list[MeasurementLike]] = {}
    for d in scan:
        groups.setdefault(d.sensor_id, []).append(d)
    return [tuple(g) for g in groups.values()]


def gating_clusters(costs: GatedCosts) -> list[tuple[np.ndarray, np.ndarray]]:
    """Connected components of the bipartite gating graph that hold at least one gated pair: ``(track indices,
    detection indices)`` of each, both sorted, components in order of their first gated pair (row-major)."""
    order, starts = kernels.pair_clusters(costs.rows, costs.cols, costs.shape[0])
    return [(np.unique(costs.rows[order[s:e]]), np.unique(costs.cols[order[s:e]]))
            for s, e in zip(starts[:-1], starts[1:], strict=True)]


def pair_thresholds(gate: ChiSquareGate, costs: GatedCosts) -> np.ndarray:
    """The gate threshold ``χ²_m(p)`` of each gated pair (``m`` its detection's length)."""
    dof = costs.dof[costs.cols]
    if dof.size and np.all(dof == dof[0]):
        return np.full(dof.size, gate.threshold(int(dof[0])))
    return np.array([gate.threshold(int(m)) for m in dof])


def unused_and_gated_out(costs: GatedCosts, assigned: np.ndarray) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """Indices of the detections not in ``assigned`` (bool per detection), and of those in no gate."""
    in_gate = np.zeros(costs.shape[1], dtype=bool)
    in_gate[costs.cols] = True
    return tuple(np.flatnonzero(~assigned).tolist()), tuple(np.flatnonzero(~in_gate).tolist())


def single_group(scan: Sequence[MeasurementLike]) -> tuple[MeasurementLike, ...]:
    """``scan`` as one sensor group, or a ValueError naming its sensors."""
    dets = tuple(scan)
    ids = {d.sensor_id for d in dets}
    if len(ids) > 1:
        raise ValueError(f"assign takes the detections of one sensor, got sensors {sorted(map(str, ids))}; "
                         "use assign_groups for a scan of several")
    return dets


class GlobalNearestNeighbourAssociator:
    """Optimal one-to-one assignment of a sensor group's detections to tracks inside the gate (module docstring).

    Parameters
    ----------
    gate : ChiSquareGate
        The validation gate.
    distance : PredictedNis
        The pairwise NIS (motion model, target height, gating filter) the batched gating reproduces.
    miss_cost : float or None
        Cost of a track left without a detection, in the units of ``−2 log N`` (dimensionless); None: each track's
        gate-boundary cost (module docstring).
    max_enumerated : int
        A component with at most this many feasible assignments is solved by exhaustive search in compiled code
        (>= 1); a larger one by ``linear_sum_assignment`` (both optimal; the search avoids the solver's call cost on
        the many small components of a sparse gate).
    kdtree_min_pairs : int
        From how many pairs radar and position detections are pre-gated with a k-d tree (:class:`ScanGating`).
    affinity : ClassAffinity or None
        Classification-aided association (:mod:`.class_affinity`): a gated pair's cost loses ``2 log λ`` of its
        detection's class readings against the track's (after the miss costs are set from the kinematic costs, so an
        adverse reading can leave a track without a detection). None: kinematics alone.
    """

    def __init__(self, gate: ChiSquareGate, distance: PredictedNis, miss_cost: float | None = None,
                 max_enumerated: int = 500, kdtree_min_pairs: int = 40_000,
                 affinity: ClassAffinity | None = None) -> None:
        if int(max_enumerated) != max_enumerated or max_enumerated < 1:
            raise ValueError(f"GlobalNearestNeighbourAssociator.max_enumerated must be an integer >= 1, got "
                             f"{max_enumerated!r}")
        self.max_enumerated = int(max_enumerated)
        if miss_cost is not None and not np.isfinite(miss_cost):
            raise ValueError(f"GlobalNearestNeighbourAssociator.miss_cost must be finite or None, got {miss_cost!r}")
        self.gate = gate
        self.gating = ScanGating(gate, distance, kdtree_min_pairs)
        self.miss_cost = miss_cost
        self.affinity = affinity

    def assign(self, tracks: Sequence[Track], scan: Sequence[MeasurementLike]) -> ScanAssignment:
        """The assignment of ``scan`` (the detections of one sensor and one time) to ``tracks``."""
        dets = single_group(scan)
        costs = self.gating(tracks, dets)
        rows, cols = costs.rows, costs.cols
        c = costs.cost[rows, cols]
        if self.miss_cost is None:  # each track's gate-boundary cost
            miss = np.full(costs.shape[0], -np.inf)
            np.maximum.at(miss, rows, c - costs.nis[rows, cols] + pair_thresholds(self.gate, costs))
        else:
            miss = np.full(costs.shape[0], float(self.miss_cost))
        if self.affinity is not None and rows.size:
            log_ratio = self.affinity.log_ratios(tracks, dets, rows, cols)
            if log_ratio is not None:
                c = c - 2.0 * log_ratio
        n_t, n_d = costs.shape
        order, starts = kernels.pair_clusters(rows, cols, n_t)
        take, hard = kernels.gnn_clusters(rows, cols, c, miss, order, starts, n_t, n_d, self.max_enumerated)
        chosen = [take]
        for h in hard:
            chosen.append(solve_component(*kernels.cluster_matrix(rows, cols, c, order, starts[h], starts[h + 1], n_t,
                                                                  n_d), miss))
        picked = np.sort(np.concatenate(chosen))  # pair indices are row-major
        pairs = tuple(zip(rows[picked].tolist(), cols[picked].tolist(), strict=True))
        assigned = np.zeros(len(dets), dtype=bool)
        assigned[cols[picked]] = True
        unused, gated_out = unused_and_gated_out(costs, assigned)
        return ScanAssignment(detections=dets, pairs=pairs, weights=None, unused=unused,
                              gated_out=gated_out, costs=costs)

    def assign_groups(self, tracks: Sequence[Track], scan: Sequence[MeasurementLike]) -> list[ScanAssignment]:
        """One :meth:`assign` per sensor group of ``scan``, in order of first appearance."""
        return [self.assign(tracks, g) for g in sensor_groups(scan)]


def solve_component(C: np.ndarray, at: np.ndarray, tracks: np.ndarray, miss: np.ndarray) -> np.ndarray:
    """Pair indices of the optimal assignment of one component: its cost matrix ``C`` (``inf`` outside the gate,
    ``at`` the pair index of each entry, ``tracks`` the track of each row) beside one "no detection" column per
    track (module docstring)."""
    k, n = C.shape
    big = np.full((k, n + k), np.inf)
    big[:, :n] = C
    big[np.arange(k), n + np.arange(k)] = miss[tracks]
    r, c = linear_sum_assignment(big)
    take = c < n
    return at[r[take], c[take]]
