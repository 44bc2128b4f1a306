"""Batched χ² gating of one scan: the NIS and the cost of every (track, detection) pair at once.

For a scan of one sensor and one time ``t_meas``, :class:`ScanGating` returns the matrices of the NIS ``νᵀS⁻¹ν``
(``inf`` outside the χ² gate of :class:`~.gate.ChiSquareGate`) and of the cost ``−2 log N(ν; 0, S)
= νᵀS⁻¹ν + log det(2πS)`` that :class:`~.gate.PredictedNis` gives pair by pair, with the same prediction (its motion
model, its ``gating_filter``) and the same linearisation. The work is shared:

1. **each track is predicted once** to ``t_meas``; with a linear motion model (CV, Singer, … :
   ``propagate = F(dt)·x``, ``Q`` a function of ``dt`` alone) all tracks of one ``dt`` are predicted in one batched
   product ``F X``, ``F P Fᵀ + Q``;
2. detections that share their model, sensor position and velocity, and ``R`` (a radar's scan) form a **batch**:
   ``h(x̂ᵢ)``, ``Hᵢ`` and ``Sᵢ = Hᵢ Pᵢ Hᵢᵀ + R`` are evaluated once per track (in compiled loops for the radar
   ``[r, az(, el)]`` and position models, :mod:`.assignment_kernels`; by the bound model's ``h`` and ``jacobian``,
   once per track, for any other), and the NIS of each pair is then one quadratic form (angle components wrapped as
   the model's ``residual`` wraps them). A detection that shares nothing (a stacked measurement, its own sensor
   position) is a batch of one: the exact per-pair computation;
3. **spatial pre-gating**: for radar and position batches (their models fix a ground position,
   :meth:`~autonomy.estimation.measurements.DetectionModel.ground_fix`), only the pairs whose ground fix lies within
   a radius of a point of the track are evaluated, found with a ``cKDTree`` on the fixes. The radius is an exact
   bound, never an approximation: inside the gate, each innovation component obeys ``|νₖ| ≤ √(γ Sₖₖ)`` (the largest
   value of ``eₖᵀν`` on the ellipsoid ``νᵀS⁻¹ν ≤ γ``), and the ground marginal ``ν_xy`` of a position obeys
   ``‖ν_xy‖² ≤ γ λ_max(S_xy) ≤ γ (λ_max(P_xy) + λ_max(R_xy))`` (a marginal's quadratic form never exceeds the whole's).

   - position ``[x, y(, z)]``: the fix is ``z_xy`` and ``ν_xy = z_xy − x̂_xy``, so the radius about ``x̂_xy`` is
     ``√(γ λ_max(S_xy))``;
   - radar ``[r, az, …]``: ``|Δr| ≤ a = √(γ S_rr)``, ``|Δaz| ≤ b = √(γ S_az,az)``. With ``ρ(r) = √(r² − Δh²)`` the
     ground range of a slant range on the fix plane and ``q`` the ground point of ``(ρ(r̂), âz)``, a fix at
     ``(ρ, az)`` lies at ``d² = (ρ − ρ_q)² + 4 ρ ρ_q sin²(Δaz/2)`` from ``q``, so inside the gate
     ``d² ≤ max(ρ(r̂+a) − ρ_q, ρ_q − ρ(r̂−a))² + 4 ρ(r̂+a) ρ_q sin²(min(b, π)/2)`` — the nonlinear map from
     ``(r, az)`` to the ground is bounded exactly, where the first-order radius ``√(γ(λ_max(P_xy) + λ_max(P_fix)))``
     can miss a gated pair far from the linear regime (a near-nadir range, a wide gate).

   The radius is widened by a relative 1e-7 and 1 µm against round-off. The tree pays off from some ten thousand
   pairs (``kdtree_min_pairs``); below, every pair goes to the compiled loop, which rejects it on the first
   component beyond ``√(γ Sₖₖ)`` — the same exact bound, in measurement space — before its quadratic form.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from autonomy.estimation.base import Filter
from autonomy.estimation.measurements import MeasurementLike, MeasurementModel, PositionModel, RadarModel, state_indices
from autonomy.estimation.models import LinearMotionModel

from . import assignment_kernels as kernels
from .gate import ChiSquareGate, PredictedNis
from .track import Track

__all__ = ["GatedCosts", "ScanGating"]

_RADIUS_REL = 1e-7  # relative widening of a pre-gating radius against round-off
_RADIUS_ABS = 1e-6  # m


@dataclass(frozen=True, eq=False)
class GatedCosts:
    """Gated distances of one scan's detections to a list of tracks.

    Attributes
    ----------
    nis : ndarray
        ``(n_tracks, n_dets)`` NIS ``νᵀS⁻¹ν`` of each pair, ``inf`` outside the gate (and for pairs pre-gating
        proved to lie outside it).
    cost : ndarray
        ``(n_tracks, n_dets)`` ``−2 log N(ν; 0, S) = νᵀS⁻¹ν + log det(2πS)``, ``inf`` outside the gate.
    dof : ndarray
        ``(n_dets,)`` length of each detection's ``z`` (the gate's degrees of freedom).
    rows, cols : ndarray
        Track and detection indices of the gated pairs (``nis[rows, cols]`` finite), row-major order.
    evaluated : int
        Pairs whose NIS was computed (the others were excluded by spatial pre-gating).
    """

    nis: np.ndarray
    cost: np.ndarray
    dof: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    evaluated: int

    @property
    def shape(self) -> tuple[int, int]:
        """``(n_tracks, n_dets)``."""
        return self.nis.shape  # type: ignore[return-value]


@dataclass(frozen=True, eq=False)
class _Predicted:
    """Tracks predicted to the scan time: states ``(T, n)``, covariances ``(T, n, n)``."""

    X: np.ndarray
    P: np.ndarray


class ScanGating:
    """Batched gating of one scan against many tracks (module docstring).

    Parameters
    ----------
    gate : ChiSquareGate
        The validation gate.
    distance : PredictedNis
        The pairwise NIS whose prediction (motion model, gating filter) and target height are reproduced.
    kdtree_min_pairs : int
        Number of (track, detection) pairs of a batch from which radar and position batches are pre-gated
        spatially with a k-d tree (>= 0); below it every pair is tested in compiled code, first component by
        component (``|νₖ| ≤ √(γ Sₖₖ)``, the bound the radius is built from), which is cheaper than building trees
        for a few thousand pairs. Either way the result is the same.
    """

    def __init__(self, gate: ChiSquareGate, distance: PredictedNis, kdtree_min_pairs: int = 40_000) -> None:
        if int(kdtree_min_pairs) != kdtree_min_pairs or kdtree_min_pairs < 0:
            raise ValueError(f"ScanGating.kdtree_min_pairs must be an integer >= 0, got {kdtree_min_pairs!r}")
        self.gate = gate
        self.distance = distance
        self.kdtree_min_pairs = int(kdtree_min_pairs)
        self._pos = np.array(state_indices(distance.layout)[0], dtype=np.int64)

    def __call__(self, tracks: Sequence[Track], detections: Sequence[MeasurementLike]) -> GatedCosts:
        """The gated NIS and cost matrices of ``detections`` (one time ``t_meas``) against ``tracks``."""
        n_t, n_d = len(tracks), len(detections)
        nis = np.full((n_t, n_d), np.inf)
        cost = np.full((n_t, n_d), np.inf)
        dof = np.zeros(n_d, dtype=int)
        evaluated = 0
        found: list[tuple[np.ndarray, np.ndarray]] = []
        if n_d:
            t_meas = float(detections[0].t_meas)
            if any(d.t_meas != t_meas for d in detections):
                raise ValueError("ScanGating needs the detections of one time t_meas")
            pred = self.predict([self.distance.gating_filter(tr.filter) for tr in tracks], t_meas) if n_t else None
            for idx in _batches(detections):
                dets = [detections[j] for j in idx]
                dof[idx] = np.size(dets[0].z)
                if pred is not None:
                    evaluated += self._gate_batch(pred, dets, np.asarray(idx), nis, cost, found)
        if not found:
            rows = cols = np.zeros(0, dtype=np.int64)
        elif len(found) == 1 and found[0][2]:
            rows, cols = found[0][:2]
        else:
            rows, cols = np.concatenate([f[0] for f in found]), np.concatenate([f[1] for f in found])
            order = np.lexsort((cols, rows))
            rows, cols = rows[order], cols[order]
        return GatedCosts(nis=nis, cost=cost, dof=dof, rows=rows, cols=cols, evaluated=evaluated)

    # --- prediction ---------------------------------------------------------------------------------------------
    def predict(self, filters: Sequence[Filter], t: float) -> _Predicted:
        """The filters' estimates predicted to ``t`` (s) as :class:`~.gate.PredictedNis` predicts them."""
        model = self.distance.motion
        n = len(self.distance.layout)
        X = np.empty((len(filters), n))
        P = np.empty((len(filters), n, n))
        if isinstance(model, LinearMotionModel):
            X[:] = [f.x for f in filters]
            P[:] = [f.P for f in filters]
            dts = t - np.array([f.t for f in filters])
            if dts.size and np.all(dts == dts[0]):
                groups = [(float(dts[0]), slice(None))]
            else:
                values, inverse = np.unique(dts, return_inverse=True)
                groups = [(float(v), np.flatnonzero(inverse == k)) for k, v in enumerate(values)]
            for dt, sel in groups:
                F, Q = model.matrices(dt)
                X[sel], P[sel] = kernels.predict_linear(X[sel], P[sel], F, Q)
        else:
            for i, f in enumerate(filters):
                dt = t - f.t
                F = model.jacobian(f.x, dt)
                X[i] = model.propagate(f.x, dt)
                P[i] = F @ f.P @ F.T + model.process_noise(dt, f.x)
        return _Predicted(X, P)

    # --- one batch of detections sharing h, H and R per track -----------------------------------------------------
    def _gate_batch(self, pred: _Predicted, dets: list[MeasurementLike], idx: np.ndarray, nis: np.ndarray,
                    cost: np.ndarray, found: list) -> int:
        """Fill ``nis`` and ``cost`` at the batch's gated pairs; append ``(rows, cols, row-major)`` to ``found``; return
        the number of pairs evaluated."""
        d0 = dets[0]
        h = d0.model.bind(d0, self.distance.layout, self.distance.target_height)
        R = np.ascontiguousarray(d0.R, dtype=float)
        m = R.shape[0]
        gamma = self.gate.threshold(m)
        Z = np.array([d.z for d in dets], dtype=float).reshape(len(dets), m)
        if isinstance(h, RadarModel) and h.m in (2, 3):
            Zp, S = kernels.radar_terms(pred.X, pred.P, self._pos, h.m, np.asarray(h.p_s, dtype=float), R,
                                        h.target_height)
        elif isinstance(h, PositionModel):
            Zp, S = kernels.position_terms(pred.X, pred.P, np.asarray(h.idx, dtype=np.int64), R)
        else:  # any other model: h and H once per track, as PredictedNis evaluates them
            Zp = np.array([h.h(x) for x in pred.X]).reshape(len(pred.X), m)
            H = np.array([h.jacobian(x) for x in pred.X])
            S = np.ascontiguousarray(H @ pred.P @ H.transpose(0, 2, 1) + R)
        S_inv, logdet = kernels.inv_logdet(S)
        ang = np.asarray(h.angle_mask, dtype=np.bool_)
        pairs = None
        if len(Zp) * len(dets) >= self.kdtree_min_pairs:
            pairs = self._candidates(h, d0, Z, Zp, S, pred.X, gamma)
        if pairs is None:
            rows, cols, q, c = kernels.gate_all_pairs(Z, Zp, S, S_inv, logdet, ang, gamma)
            evaluated = len(Zp) * len(dets)
        else:
            rows, cols, q, c = kernels.gate_pairs(pairs[0], pairs[1], Z, Zp, S, S_inv, logdet, ang, gamma)
            evaluated = int(pairs[0].size)
        cols = idx[cols]
        nis[rows, cols] = q
        cost[rows, cols] = c
        found.append((rows, cols, pairs is None and bool(np.all(np.diff(idx) == 1))))
        return evaluated

    def _candidates(self, h: MeasurementModel, d0: MeasurementLike, Z: np.ndarray, Zp: np.ndarray, S: np.ndarray,
                    X: np.ndarray, gamma: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The (track, detection) pairs within the pre-gating radius, or None when the batch's model has no bound."""
        if not d0.model.fixes_position:
            return None
        if isinstance(h, RadarModel):
            centres, radii, fixes = _radar_bound(h, d0, Z, Zp, S, gamma, self.distance.target_height)
        elif isinstance(h, PositionModel):
            centres = X[:, self._pos[:2]]
            a, b, c = S[:, 0, 0], S[:, 0, 1], S[:, 1, 1]
            lam = 0.5 * (a + c) + np.sqrt(0.25 * (a - c) ** 2 + b * b)  # λ_max of the 2×2 S_xy
            radii = np.sqrt(gamma * lam)
            fixes = Z[:, :2]
        else:
            return None
        radii = radii * (1.0 + _RADIUS_REL) + _RADIUS_ABS
        near = cKDTree(centres).sparse_distance_matrix(cKDTree(fixes), float(np.max(radii)), output_type="ndarray")
        keep = near["v"] <= radii[near["i"]]
        return near["i"][keep].astype(np.int64), near["j"][keep].astype(np.int64)


def _batches(dets: Sequence[MeasurementLike]) -> list[list[int]]:
    """Indices of the detections that share model, sensor position and velocity, and ``R``."""
    d0 = dets[0]
    if not any(hasattr(d, "parts") for d in dets) and all(d.model is d0.model for d in dets) and all(
            getattr(d, "v_sensor_W", None) is None for d in dets):  # one sensor's scan: compare in bulk
        p = np.array([d.p_sensor_W for d in dets], dtype=float)
        R = np.array([d.R for d in dets], dtype=float)
        if np.all(p == p[0]) and np.all(R == R[0]):
            return [list(range(len(dets)))]
    out: dict[object, list[int]] = {}
    for j, d in enumerate(dets):
        if hasattr(d, "parts"):  # a stacked measurement: its model is built per call
            out[("own", j)] = [j]
            continue
        v = getattr(d, "v_sensor_W", None)
        key = (id(d.model), _bytes(d.p_sensor_W), None if v is None else _bytes(v), _bytes(d.R))
        out.setdefault(key, []).append(j)
    return list(out.values())


def _bytes(a: np.ndarray) -> bytes:
    return (a if type(a) is np.ndarray and a.dtype == np.float64 else np.asarray(a, dtype=float)).tobytes()


def _radar_bound(h: RadarModel, d0: MeasurementLike, Z: np.ndarray, Zp: np.ndarray, S: np.ndarray, gamma: float,
                 target_height: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres, radii and ground fixes of a radar batch (module docstring, item 3)."""
    p_s = np.asarray(d0.p_sensor_W, dtype=float)
    dz2 = (target_height - p_s[2]) ** 2

    def ground(r: np.ndarray) -> np.ndarray:
        rho2 = r * r - dz2
        return np.sqrt(np.where(rho2 > 0, rho2, 0.0))

    rho_z = ground(Z[:, 0])
    fixes = p_s[:2] + rho_z[:, None] * np.stack([np.cos(Z[:, 1]), np.sin(Z[:, 1])], axis=1)
    r_hat, az_hat = Zp[:, 0], Zp[:, 1]
    a = np.sqrt(gamma * S[:, 0, 0])
    b = np.minimum(np.sqrt(gamma * S[:, 1, 1]), np.pi)
    rho_q = ground(r_hat)
    rho_hi = ground(r_hat + a)
    rho_lo = np.where(r_hat - a > 0, ground(np.maximum(r_hat - a, 0.0)), 0.0)
    d_rho = np.maximum(rho_hi - rho_q, rho_q - rho_lo)
    radii = np.sqrt(d_rho * d_rho + 4.0 * rho_hi * rho_q * np.sin(0.5 * b) ** 2)
    centres = p_s[:2] + rho_q[:, None] * np.stack([np.cos(az_hat), np.sin(az_hat)], axis=1)
    return centres, radii, fixes
