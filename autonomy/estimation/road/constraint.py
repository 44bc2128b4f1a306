"""The road constraint as a pseudo-measurement, and the active-segment cursor along a path of segments (paper 002).

Constraint on the active segment (distance form, not the squared circle form, so a lateral error counts the same on
lines and arcs of any radius):

.. math:: h(x) = \\begin{bmatrix} \\ell(p) \\\\ v \\cdot \\bar n \\end{bmatrix}, \\qquad
          z = \\begin{bmatrix} \\ell_0 \\\\ 0 \\end{bmatrix}, \\qquad
          R = \\mathrm{diag}(\\sigma_\\ell^2, \\sigma_{v_n}^2)

with :math:`\\ell(p)` the signed left offset of the position from the (extended) segment, :math:`\\bar n` the left unit
normal at the foot point of the estimate being corrected and :math:`\\ell_0` the lane offset the car is assumed to drive
at. Line: :math:`\\ell = -\\sin\\theta_0 (x - x_0) + \\cos\\theta_0 (y - y_0)`; arc with centre :math:`c`,
:math:`u = p - c`, :math:`r = |u|`: :math:`\\ell = \\mathrm{sgn}(\\kappa)(1/|\\kappa| - r)`, :math:`n =
-\\mathrm{sgn}(\\kappa)\\, u / r`; :math:`\\partial \\ell / \\partial p = n^T`,
:math:`\\partial (v\\cdot \\bar n)/\\partial v = \\bar n^T`.

Why a soft constraint: cars keep to a lane, not to the centre-line, and the lane is unknown on multi-lane roads. The
offset :math:`\\ell_0` defaults to the middle of the road's own carriageway and :math:`\\sigma_\\ell` to the standard
deviation of a position spread uniformly across it plus lane-keeping wobble and approximation error,
:math:`\\sigma_\\ell^2 = w^2/12 + \\sigma_{keep}^2` (:class:`RoadConstraintParams`), so a car in any lane is
consistent with the constraint and the filter does not pull it onto a line it does not drive on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np

from autonomy.estimation.measurements import MeasurementModel, state_indices
from autonomy.estimation.road.segments import Segment
from worlds.roads.road import Road

__all__ = ["RoadConstraintParams", "RoadConstraintModel", "SegmentCursor", "lane_prior"]


@dataclass(frozen=True, kw_only=True)
class RoadConstraintParams:
    """Pseudo-measurement settings of the road constraint.

    Attributes
    ----------
    sigma_lateral : float or None
        Standard deviation of the lateral pseudo-measurement (m), > 0; None: from the carriageway width (see
        :func:`lane_prior`).
    sigma_keep : float
        Lane-keeping wobble plus road-approximation error added to the width term when ``sigma_lateral`` is None (m),
        >= 0.
    sigma_normal_speed : float
        Standard deviation of the velocity component normal to the road (m/s), > 0; lane changes move at ~1 m/s. The
        variance actually used adds ``(v_t κ)² σ_s²``, the normal speed the true velocity shows at the estimate's foot
        point when that is ``σ_s`` off along a bend of curvature ``κ``.
    velocity_update : {"auto", "partial", "joint", "off"}
        How the velocity-along-tangent row is applied. ``"joint"``: with the lateral row (the paper's augmented
        measurement; for the projecting ECUKF, velocities projected onto the tangent). ``"partial"``: after it, as an
        update of the velocity components only (every other gain zero, Joseph-form covariance). ``"off"``: not applied.
        ``"auto"``: ``"joint"`` for the projecting ECUKF, ``"off"`` for the pseudo-measurement filters. Measured in
        Monte Carlo on bends with stop-and-go traffic (follow_road_heading on): the pseudo-measurement speed row, in
        either form, raised the position error (it acts on the along-road state through the cross-covariances), while
        projecting the sigma-point velocities did not and lowered the velocity error; on straight roads the row changes
        nothing, the lateral row already pinning the normal speed.
    lateral_offset : float or None
        Assumed left offset of the car from the centre-line (m); None: middle of the road's own carriageway.
    switch_gate : float or None
        Paper's segment-switching gate ε: move on when ``dᵀ P_pos⁻¹ d < ε`` with ``d`` = segment end − position
        (dimensionless, > 0); None disables it (the along-track rule always applies). With segments shorter than the
        position uncertainty this gate fires several segments early, hence off by default.
    follow_road_heading : bool
        Turn the predicted velocity and acceleration with the road heading between the foot points before and after
        each prediction (an addition to the paper: a straight-line motion model otherwise lags every bend and
        loses speed at each corner, since the normal-speed constraint removes the component across the new heading).
    """

    sigma_lateral: float | None = None
    sigma_keep: float = 0.5
    sigma_normal_speed: float = 1.0
    velocity_update: Literal["auto", "partial", "joint", "off"] = "auto"
    lateral_offset: float | None = None
    switch_gate: float | None = None
    follow_road_heading: bool = True

    def __post_init__(self) -> None:
        if self.sigma_lateral is not None and not (self.sigma_lateral > 0):
            raise ValueError(f"RoadConstraintParams.sigma_lateral must be > 0 m or None, got {self.sigma_lateral!r}")
        if not (self.sigma_keep >= 0):
            raise ValueError(f"RoadConstraintParams.sigma_keep must be >= 0 m, got {self.sigma_keep!r}")
        if not (self.sigma_normal_speed > 0):
            raise ValueError(f"RoadConstraintParams.sigma_normal_speed must be > 0 m/s, "
                             f"got {self.sigma_normal_speed!r}")
        if self.velocity_update not in ("auto", "partial", "joint", "off"):
            raise ValueError(f"RoadConstraintParams.velocity_update must be auto|partial|joint|off, "
                             f"got {self.velocity_update!r}")
        if self.lateral_offset is not None and not np.isfinite(self.lateral_offset):
            raise ValueError(f"RoadConstraintParams.lateral_offset must be finite or None, got {self.lateral_offset!r}")
        if self.switch_gate is not None and not (self.switch_gate > 0):
            raise ValueError(f"RoadConstraintParams.switch_gate must be > 0 or None, got {self.switch_gate!r}")


def lane_prior(road: Road, params: RoadConstraintParams) -> tuple[float, float]:
    """(offset ℓ0, σ_ℓ) in m for ``road``: the middle of its carriageway and ``√(w²/12 + σ_keep²)`` (``w`` its
    width) unless overridden."""
    right, left = road.edge_offsets
    offset = 0.5 * (right + left) if params.lateral_offset is None else params.lateral_offset
    if params.sigma_lateral is not None:
        return offset, params.sigma_lateral
    return offset, math.sqrt((left - right) ** 2 / 12.0 + params.sigma_keep**2)


class RoadConstraintModel(MeasurementModel):
    """``h(x) = ℓ(p)`` or ``[ℓ(p), v·n̄]`` on one segment (rows: lateral offset m, normal speed m/s).

    ``n̄`` is the left normal at the foot point of ``p_ref`` (the estimate being corrected), held fixed during the
    update, so the speed row is linear in the velocity and has no position part (a normal varying with ``p`` ties the
    along-road position to the velocity heading, by ``∂(v·n)/∂p ∝ |v|/r`` on tight arcs).

    Parameters
    ----------
    layout : tuple of str
        State layout (needs x, y; vx, vy for the speed row).
    segment : Segment
        The active segment.
    p_ref : ndarray
        Reference position (2,) for ``n̄`` (m).
    velocity : bool
        Include the speed row.
    """

    def __init__(self, layout: tuple[str, ...], segment: Segment, p_ref: np.ndarray, velocity: bool = False) -> None:
        self.n_state = len(layout)
        pos, vel = state_indices(layout)
        self.ip = list(pos[:2])
        self.iv = None if vel is None or not velocity else list(vel[:2])
        self.segment = segment
        self.n_ref = np.asarray(segment.local(np.asarray(p_ref, dtype=float))[2], dtype=float)
        self.m = 1 if self.iv is None else 2
        self.angle_mask = np.zeros(self.m, dtype=bool)

    def h(self, X: np.ndarray) -> np.ndarray:
        _, lat, _ = self.segment.local(X[self.ip])
        if self.iv is None:
            return np.array([lat])
        v = X[self.iv]
        return np.array([lat, v[0] * self.n_ref[0] + v[1] * self.n_ref[1]])

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        _, _, n = self.segment.local(x[self.ip])
        H = np.zeros((self.m, self.n_state))
        H[0, self.ip] = n
        if self.iv is not None:
            H[1, self.iv] = self.n_ref
        return H


class SegmentCursor:
    """The active segment of a path of segments, moved along the path's order as the estimate advances.

    Rules, applied to the position ``p`` (and position covariance) before each constrained update:

    1. along-track: while the foot point lies beyond the active segment's end, move to the next one; while it lies
       before its start, move back (never before the first, nor back across a junction onto the previous road);
    2. the paper's gate (optional, :class:`RoadConstraintParams` ``switch_gate``): if ``dᵀ P_pos⁻¹ d < ε`` with
       ``d`` = end of the active segment − ``p``, move to the next one.

    Parameters
    ----------
    segments : sequence of Segment
        The path in driving order (it may span several roads).
    index : int
        Initial active segment.
    """

    def __init__(self, segments: Sequence[Segment], index: int = 0) -> None:
        if not segments:
            raise ValueError("SegmentCursor: segments must not be empty")
        self.segments = tuple(segments)
        if not 0 <= index < len(self.segments):
            raise ValueError(f"SegmentCursor: index must be in [0, {len(self.segments) - 1}], got {index}")
        self.index = int(index)
        self._s_end = np.cumsum([g.length for g in self.segments])
        ids: list[str] = []
        for g in self.segments:
            if not ids or ids[-1] != g.road_id:
                ids.append(g.road_id)
        self._road_ids = tuple(ids)

    @property
    def active(self) -> Segment:
        """The active segment."""
        return self.segments[self.index]

    @property
    def road_id(self) -> str:
        """Road of the active segment."""
        return self.active.road_id

    def follow(self, p: np.ndarray, P_pos: np.ndarray | None = None, gate: float | None = None) -> Segment:
        """Move the cursor for position ``p`` (2,) (m), covariance ``P_pos`` (2, 2) (m²); returns the active segment."""
        last = len(self.segments) - 1
        for _ in range(len(self.segments)):
            sigma = float(self.active.local(p)[0])
            if sigma > self.active.length and self.index < last:
                self.index += 1
            elif sigma < 0.0 and self.index > 0 and self.segments[self.index - 1].road_id == self.road_id \
                    and float(self.segments[self.index - 1].local(p)[0]) < self.segments[self.index - 1].length:
                self.index -= 1
            else:
                break
        if gate is not None and P_pos is not None and self.index < last:
            d = self.active.p1 - p
            if float(d @ np.linalg.solve(P_pos, d)) < gate:
                self.index += 1
        return self.active

    def next_road_start(self) -> int | None:
        """Index of the first segment of the road after the active one on the path, or None on the last road."""
        road = self.road_id
        for i in range(self.index + 1, len(self.segments)):
            if self.segments[i].road_id != road:
                return i
        return None

    def remaining(self, p: np.ndarray) -> float:
        """Arc length (m) from the foot point of ``p`` on the active segment to the end of the path."""
        sigma = float(self.active.local(p)[0])
        return float(self._s_end[-1] - self._s_end[self.index] + self.active.length - sigma)

    def road_ids(self) -> tuple[str, ...]:
        """The roads of the path in order (each once)."""
        return self._road_ids
