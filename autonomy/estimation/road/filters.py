"""Road-constrained filters of paper 002: measurement-augmented EKF (MAEKF) and equality-constrained UKF (ECUKF).

Both predict with the unconstrained motion model (then, with ``follow_road_heading``, turn velocity and acceleration
with the road) and apply the road constraint (:mod:`autonomy.estimation.road.constraint`) once per measurement time
stamp, with the first measurement of that time (further sensors at the same time update normally):

- **MAEKF**: one EKF update with the augmented measurement ``z_a = [z, ℓ0]``, ``h_a = [h, ℓ(p)]``,
  ``R_a = diag(R, σ_ℓ²)`` (paper eqs. 12–19), the constraint linearised at the prediction; with
  ``velocity_update="joint"`` the speed row ``v·n̄ = 0`` (noise ``σ_vn²``) is stacked too.
- **ECUKF**: the unconstrained UKF update with ``z``, then a second stage on sigma points of that posterior:
  ``"pseudo"`` passes every sigma point through the nonlinear constraint and makes a sigma-point update with the
  pseudo-measurement; ``"project"`` (default) moves every sigma point onto the constraint (position along its
  foot-point normal to the offset ``ℓ0``; velocity to its along-road part with ``"joint"``), recomputes mean and
  covariance, and adds ``σ_ℓ² n nᵀ`` (``σ_vn² n̄ n̄ᵀ``) back so the covariance stays positive definite.

With ``velocity_update="partial"`` the speed row follows as a velocity-only update: gain
``K_v = P_vv n̄ / S`` on the velocity components and zero elsewhere, ``S = n̄ᵀ P_vv n̄ + σ_vn²``, Joseph-form
covariance (a consistent suboptimal update). The constrained estimate is carried to the next step.

``update`` returns the innovation of the sensor measurement alone (``ν``, ``S`` of the sensor rows), so constrained
hypotheses can be weighted by the likelihood of the real measurement.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

import numpy as np

from autonomy.estimation.base import TIME_TOLERANCE, GaussianFilter, Innovation
from autonomy.estimation.ekf import EKF
from autonomy.estimation.measurements import (
    MeasurementLike,
    MeasurementModel,
    StackedModel,
    measurement_model,
    state_indices,
    wrap_angle,
)
from autonomy.estimation.models import MotionModel
from autonomy.estimation.road.constraint import RoadConstraintModel, RoadConstraintParams, SegmentCursor
from autonomy.estimation.sigma_point import UKF, UKFParams

__all__ = ["RoadConstrainedFilter", "MAEKF", "ECUKF", "make_road_filter"]


class RoadConstrainedFilter(GaussianFilter):
    """Shared part of the road-constrained filters: the segment cursor, lane priors and once-per-time bookkeeping.

    Parameters
    ----------
    model, x0, P0, t0, target_height
        As :class:`GaussianFilter`.
    cursor : SegmentCursor
        The path of segments the target is assumed to follow and the active one.
    lanes : mapping str -> (float, float)
        Per road id on the path: assumed lateral offset ``ℓ0`` (m) and its standard deviation ``σ_ℓ`` (m).
    params : RoadConstraintParams
        Normal-speed noise and segment-switching gate.
    """

    def _setup_road(self, cursor: SegmentCursor, lanes: Mapping[str, tuple[float, float]],
                    params: RoadConstraintParams) -> None:
        roads = {g.road_id for g in cursor.segments}
        missing = {rid for rid in roads if rid not in lanes}
        if missing:
            raise ValueError(f"lanes must give (offset, sigma) for every road on the path, missing {sorted(missing)}")
        self.cursor = cursor
        self.lanes = {rid: lanes[rid] for rid in roads}  # the path's roads (a cursor's path is fixed): what it reads
        self.params = params
        self._ip, vel = state_indices(self.layout)
        self._ip = list(self._ip[:2])
        self._iv = None if vel is None else list(vel[:2])
        self._constrained_t = -np.inf
        mode = params.velocity_update
        if mode == "auto":
            mode = "joint" if getattr(self, "stage2", "pseudo") == "project" else "off"
        self.velocity_mode = mode if self._iv is not None else "off"
        self.last_lateral = 0.0  # m; lateral innovation of the last constraint (before it was applied)
        self._iva = [list(self._iv)] if self._iv is not None else []
        if "ax" in self.layout and "ay" in self.layout:
            self._iva.append([self.layout.index("ax"), self.layout.index("ay")])

    def _road_heading(self) -> float:
        """Road heading (rad) at the foot point of the current position on the path (the cursor follows it)."""
        p = self.x[self._ip]
        return self.cursor.follow(p).heading_at(p)

    def _predict(self, dt: float) -> None:
        """Model prediction, then (``follow_road_heading``) velocity and acceleration turned with the road.

        ``Δθ`` is the change of road heading between the foot points of the estimate before and after the prediction
        (``v T κ`` on an arc, the corner angle across a junction); ``x_v ← G x_v``, ``P ← G P Gᵀ`` with ``G`` the
        rotation by ``Δθ`` on the (vx, vy) and (ax, ay) pairs.
        """
        if not self.params.follow_road_heading or not self._iva:
            super()._predict(dt)
            return
        th0 = self._road_heading()
        super()._predict(dt)
        self.turn(float(wrap_angle(self._road_heading() - th0)))

    def turn(self, dth: float) -> None:
        """Turn velocity and acceleration by ``dth`` (rad) and the position spread with them (mean position kept).

        ``x_v ← G x_v``, ``P ← G P Gᵀ`` with ``G`` the rotation by ``dth`` on the (vx, vy), (ax, ay) and, for the
        covariance only, (x, y) pairs.
        """
        if dth == 0.0 or not self._iva:
            return
        c, s = np.cos(dth), np.sin(dth)
        G = np.eye(len(self.layout))
        for i, j in self._iva:
            G[i, i], G[i, j], G[j, i], G[j, j] = c, -s, s, c
        x = G @ self.x
        i, j = self._ip
        G[i, i], G[i, j], G[j, i], G[j, j] = c, -s, s, c  # the position spread turns with the road too
        self.set_state(x, G @ self.P @ G.T)

    def _pseudo(self, velocity: bool) -> tuple[RoadConstraintModel, np.ndarray, np.ndarray]:
        """Move the cursor for the current estimate; the constraint model, pseudo-measurement and its noise."""
        p = self.x[self._ip]
        P_pos = self.P[np.ix_(self._ip, self._ip)]
        seg = self.cursor.follow(p, P_pos, self.params.switch_gate)
        offset, sigma = self.lanes[seg.road_id]
        cm = RoadConstraintModel(self.layout, seg, p, velocity=velocity and self._iv is not None)
        # second-order term of the linearised lateral offset: along a circle of curvature κ the offset changes by
        # κ δs²/2 for an along-road error δs ~ N(0, σ_s²), of variance κ² σ_s⁴ / 2 (m²); it keeps a tight corner
        # from collapsing the along-road variance when σ_s is not small against the radius
        t = np.array([cm.n_ref[1], -cm.n_ref[0]])
        sigma_s2 = float(t @ P_pos @ t)
        kappa = seg.kappa if 0.0 <= seg.local(p)[0] <= seg.length else 0.0
        var_lat = sigma**2 + 0.5 * kappa**2 * sigma_s2**2
        if cm.m == 1:
            return cm, np.array([offset]), np.array([[var_lat]])
        return cm, np.array([offset, 0.0]), np.diag([var_lat, self._normal_speed_var(cm)])

    def _normal_speed_var(self, cm: RoadConstraintModel) -> float:
        """``σ_vn² + (v_t κ)² σ_s²`` (m²/s²): the normal is taken at the estimate's foot point, ``σ_s`` off the car's
        along the road, where the true velocity shows a normal component ``≈ v_t κ δs`` on an arc."""
        seg, n = cm.segment, cm.n_ref
        t = np.array([n[1], -n[0]])
        p = self.x[self._ip]
        sigma_s2 = float(t @ self.P[np.ix_(self._ip, self._ip)] @ t)
        v_t = float(self.x[self._iv] @ t)
        kappa = seg.kappa if 0.0 <= seg.local(p)[0] <= seg.length else 0.0
        return self.params.sigma_normal_speed**2 + (v_t * kappa) ** 2 * sigma_s2

    def _velocity_update(self) -> None:
        """Velocity-only update with ``v·n̄ = 0`` (see the module docstring)."""
        if self._iv is None:
            return
        p = self.x[self._ip]
        seg = self.cursor.active
        cm = RoadConstraintModel(self.layout, seg, p, velocity=True)
        n = cm.n_ref
        var = self._normal_speed_var(cm)
        x, P = self.x, self.P
        iv = self._iv
        PHt = P[:, iv] @ n
        S = float(n @ PHt[iv]) + var
        K = np.zeros(len(x))
        K[iv] = PHt[iv] / S
        H = np.zeros(len(x))
        H[iv] = n
        IKH = np.eye(len(x)) - np.outer(K, H)
        P = IKH @ P @ IKH.T + var * np.outer(K, K)
        self.set_state(x - K * float(x[iv] @ n), 0.5 * (P + P.T))

    def update(self, measurement: MeasurementLike, model: MeasurementModel | None = None) -> Innovation:
        self.predict(measurement.t_meas)
        mm = model if model is not None else measurement_model(measurement, self.layout, self.target_height)
        z = np.asarray(measurement.z, dtype=float)
        R = np.asarray(measurement.R, dtype=float)
        if abs(self.t - self._constrained_t) <= TIME_TOLERANCE:
            return self.update_with(mm, z, R)
        self._constrained_t = self.t
        inn = self._constrained_update(mm, z, R)
        if self.velocity_mode == "partial":
            self._velocity_update()
        return inn

    def constrain(self) -> None:
        """Apply the road constraint alone at the current time (e.g. right after initialisation)."""
        cm, zc, Rc = self._pseudo(self.velocity_mode == "joint")
        self._apply_constraint(cm, zc, Rc)
        if self.velocity_mode == "partial":
            self._velocity_update()
        self._constrained_t = self.t

    def _apply_constraint(self, cm: RoadConstraintModel, zc: np.ndarray, Rc: np.ndarray) -> None:
        self.last_lateral = float(zc[0] - cm.h(self.x)[0])
        self.update_with(cm, zc, Rc)

    def _constrained_update(self, mm: MeasurementModel, z: np.ndarray, R: np.ndarray) -> Innovation:
        inn = self.update_with(mm, z, R)
        cm, zc, Rc = self._pseudo(self.velocity_mode == "joint")
        self._apply_constraint(cm, zc, Rc)
        return inn


class MAEKF(RoadConstrainedFilter, EKF):
    """Measurement-augmented EKF: the sensor rows and the road rows in one EKF update (see the module docstring)."""

    def __init__(self, model: MotionModel, x0: np.ndarray, P0: np.ndarray, t0: float = 0.0,
                 target_height: float = 0.0, *, cursor: SegmentCursor, lanes: Mapping[str, tuple[float, float]],
                 params: RoadConstraintParams | None = None) -> None:
        super().__init__(model, x0, P0, t0, target_height)
        self._setup_road(cursor, lanes, params if params is not None else RoadConstraintParams())

    def _constrained_update(self, mm: MeasurementModel, z: np.ndarray, R: np.ndarray) -> Innovation:
        cm, zc, Rc = self._pseudo(self.velocity_mode == "joint")
        m = z.size
        self.last_lateral = float(zc[0] - cm.h(self.x)[0])
        Ra = np.zeros((m + zc.size, m + zc.size))
        Ra[:m, :m] = R
        Ra[m:, m:] = Rc
        inn = self.update_with(StackedModel([mm, cm]), np.concatenate([z, zc]), Ra)
        return Innovation(inn.nu[:m], inn.S[:m, :m])


class ECUKF(RoadConstrainedFilter, UKF):
    """Equality-constrained UKF: unconstrained sigma-point update, then a sigma-point constraint stage.

    ``stage2`` is ``"pseudo"`` (sigma-point pseudo-measurement update) or ``"project"`` (sigma points projected onto
    the constraint); see the module docstring.
    """

    def __init__(self, model: MotionModel, x0: np.ndarray, P0: np.ndarray, t0: float = 0.0,
                 target_height: float = 0.0, *, cursor: SegmentCursor, lanes: Mapping[str, tuple[float, float]],
                 params: RoadConstraintParams | None = None, ukf_params: UKFParams | None = None,
                 stage2: Literal["pseudo", "project"] = "project") -> None:
        if stage2 not in ("pseudo", "project"):
            raise ValueError(f"stage2 must be 'pseudo' or 'project', got {stage2!r}")
        super().__init__(model, x0, P0, t0, target_height, params=ukf_params)
        self.stage2 = stage2
        self._setup_road(cursor, lanes, params if params is not None else RoadConstraintParams())

    def _apply_constraint(self, cm: RoadConstraintModel, zc: np.ndarray, Rc: np.ndarray) -> None:
        if self.stage2 == "pseudo":
            super()._apply_constraint(cm, zc, Rc)
            return
        self.last_lateral = float(zc[0] - cm.h(self.x)[0])
        X = self._points()
        seg = cm.segment
        _, lat, n = seg.local(X[self._ip])
        X[self._ip] -= (lat - zc[0]) * n
        if cm.m == 2:
            nr = cm.n_ref
            X[self._iv] -= (X[self._iv[0]] * nr[0] + X[self._iv[1]] * nr[1]) * nr[:, None]
        x = X @ self._Wm
        D = X - x[:, None]
        P = (D * self._Wc) @ D.T
        _, _, n_bar = seg.local(x[self._ip])
        P[np.ix_(self._ip, self._ip)] += Rc[0, 0] * np.outer(n_bar, n_bar)
        if cm.m == 2:
            P[np.ix_(self._iv, self._iv)] += Rc[1, 1] * np.outer(cm.n_ref, cm.n_ref)
        self._x = x
        self._P = 0.5 * (P + P.T)


def make_road_filter(variant: Literal["maekf", "ecukf"], model: MotionModel, x0: np.ndarray, P0: np.ndarray,
                     t0: float, *, cursor: SegmentCursor, lanes: Mapping[str, tuple[float, float]],
                     params: RoadConstraintParams, target_height: float = 0.0,
                     stage2: Literal["pseudo", "project"] = "project") -> RoadConstrainedFilter:
    """A road-constrained filter of the given ``variant`` (``"maekf"`` or ``"ecukf"``)."""
    if variant == "maekf":
        return MAEKF(model, x0, P0, t0, target_height, cursor=cursor, lanes=lanes, params=params)
    if variant == "ecukf":
        return ECUKF(model, x0, P0, t0, target_height, cursor=cursor, lanes=lanes, params=params, stage2=stage2)
    raise ValueError(f"variant must be 'maekf' or 'ecukf', got {variant!r}")
