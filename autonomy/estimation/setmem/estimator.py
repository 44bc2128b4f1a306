"""Set-membership search-and-track estimator of an unknown number of unlabelled targets (Ibenenthal et al.).

Each UAV ``i`` keeps two ground-plane sets (unions of polygons, world frame, metres):

- ``X``, guaranteed to contain every target already detected (it may also hold decoys taken for targets);
- ``Xbar``, guaranteed to contain every target not yet detected.

Initially ``X = {}`` and ``Xbar = X_s``, the free search area (the area minus the building footprints). Every
step of length ``T`` runs three stages, with ``v_max`` the targets' speed bound and ``F`` the observed region
(footprint minus building shadows):

Prediction (paper eqs. 8-9)
    ``X <- (X (+) B(v_max T)) n X_s`` and ``Xbar <- (Xbar (+) B(v_max T)) n X_s``, the dilation being an outer
    approximation (:func:`~autonomy.estimation.setmem.polygons.dilate`).
Correction (eqs. 10-14)
    With the measurement boxes ``Y = U_j [y_j - w, y_j + w]`` (``w`` the error bound per axis), intersected with
    ``F`` (a detected target lies in ``F``):
    ``X <- (X n Y) U (Xbar n Y) U (X \\ F)`` and ``Xbar <- Xbar \\ F``.
    A decoy seen from outside its visibility cone gives no measurement, so the part of ``X`` it explained and that
    lies in ``F`` is erased.
Fusion (eqs. 15-16)
    With the post-correction sets of the neighbours ``l`` in line of sight, ``N_i = neighbours U {i}``:
    ``X_i <- (U_l X_l) \\ U_l Xt_l`` with ``Xt_l = X_s \\ (X_l U Xbar_l)`` proven free of targets, computed as
    ``(U_l X_l) n (n_l (X_l U Xbar_l))``; and ``Xbar_i <- n_l Xbar_l``.

Guarantee: if every target lies in ``X_l U Xbar_l`` of every UAV before the step and moves at most ``v_max T``,
it lies in ``X_i U Xbar_i`` after it. To bound the cost, sets whose vertex count exceeds ``max_vertices`` are
replaced by an outer approximation with fewer vertices (:func:`~autonomy.estimation.setmem.polygons.outer_simplify`),
which keeps the guarantee. Lines and points left by overlays (sets of zero area) are dropped: a target exactly on
such a degenerate piece is a measure-zero event, and containment is checked with a tolerance of ``1e-6`` m.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from autonomy.estimation.measurements import PositionDetectionModel
from autonomy.sensing.measurement import Detection
from worlds.geometry import Building

from . import polygons as pg

__all__ = ["SetEstimate", "SetMembershipConfig", "SetMembershipEstimator", "SetMembershipStats", "free_search_area"]


@dataclass(frozen=True, kw_only=True)
class SetMembershipConfig:
    """Parameters of the set-membership estimator.

    Attributes
    ----------
    max_target_speed : float
        Bound on the targets' ground speed (m/s), > 0; the paper's 5 km/h is 1.389 m/s.
    quad_segs : int
        Segments per quarter circle of the round joins of the dilation, >= 1 (the radius is enlarged so the
        result stays an outer approximation).
    simplify_tol : float
        Douglas-Peucker tolerance of the outer simplification (m), >= 0.
    max_vertices : int
        A set with more vertices than this is outer-simplified, >= 16.
    max_hole_area : float
        Holes of at most this area are filled when simplifying (m^2), >= 0.
    containment_tol : float
        Tolerance of the containment checks (m), >= 0.
    """

    max_target_speed: float = 5.0 / 3.6
    quad_segs: int = 2
    simplify_tol: float = 0.2
    max_vertices: int = 600
    max_hole_area: float = 1.0
    containment_tol: float = 1e-6

    def __post_init__(self) -> None:
        if not (self.max_target_speed > 0):
            raise ValueError(f"SetMembershipConfig.max_target_speed must be > 0 m/s, got {self.max_target_speed}")
        if int(self.quad_segs) != self.quad_segs or self.quad_segs < 1:
            raise ValueError(f"SetMembershipConfig.quad_segs must be an integer >= 1, got {self.quad_segs}")
        if not (self.simplify_tol >= 0):
            raise ValueError(f"SetMembershipConfig.simplify_tol must be >= 0 m, got {self.simplify_tol}")
        if int(self.max_vertices) != self.max_vertices or self.max_vertices < 16:
            raise ValueError(f"SetMembershipConfig.max_vertices must be an integer >= 16, got {self.max_vertices}")
        if not (self.max_hole_area >= 0):
            raise ValueError(f"SetMembershipConfig.max_hole_area must be >= 0 m^2, got {self.max_hole_area}")
        if not (self.containment_tol >= 0):
            raise ValueError(f"SetMembershipConfig.containment_tol must be >= 0 m, got {self.containment_tol}")


@dataclass(frozen=True, kw_only=True)
class SetEstimate:
    """The two sets of one UAV at one time: what the estimator holds and what UAVs exchange.

    Attributes
    ----------
    t : float
        Time of validity (s).
    X : BaseGeometry
        Ground set (m) containing every detected target (and possibly decoys).
    Xbar : BaseGeometry
        Ground set (m) containing every target not yet detected.
    owner : int
        Index of the UAV that computed it.
    """

    t: float
    X: BaseGeometry
    Xbar: BaseGeometry
    owner: int = 0

    def __post_init__(self) -> None:
        if not np.isfinite(self.t):
            raise ValueError(f"SetEstimate.t must be finite, got {self.t}")
        object.__setattr__(self, "X", pg.as_polygonal(self.X))
        object.__setattr__(self, "Xbar", pg.as_polygonal(self.Xbar))

    @property
    def area_X(self) -> float:
        """phi(X) (m^2)."""
        return pg.area(self.X)

    @property
    def area_Xbar(self) -> float:
        """phi(Xbar) (m^2)."""
        return pg.area(self.Xbar)

    @property
    def support(self) -> BaseGeometry:
        """``X U Xbar``: where any target may be (m)."""
        return pg.union_all([self.X, self.Xbar])

    def proven_empty(self, free_area: BaseGeometry) -> BaseGeometry:
        """``Xt = X_s \\ (X U Xbar)``: the part of the free area proven to hold no target (m)."""
        return pg.as_polygonal(shapely.difference(free_area, self.support))

    def contains(self, p_xy: np.ndarray, tol: float = 1e-6) -> np.ndarray:
        """(N,) bool: each ground point (N, 2) m lies in ``X U Xbar`` up to ``tol`` m."""
        return pg.contains_points(self.X, p_xy, tol) | pg.contains_points(self.Xbar, p_xy, tol)

    def in_X(self, p_xy: np.ndarray, tol: float = 1e-6) -> np.ndarray:
        """(N,) bool: each ground point (N, 2) m lies in ``X`` up to ``tol`` m."""
        return pg.contains_points(self.X, p_xy, tol)


def free_search_area(area: BaseGeometry, buildings: Sequence[Building] = ()) -> BaseGeometry:
    """``X_s``: the search area minus the building footprints (m)."""
    if not buildings:
        return pg.as_polygonal(area)
    fps = shapely.union_all([shapely.Polygon(b.footprint) for b in buildings])
    return pg.as_polygonal(shapely.difference(area, fps))


@dataclass(kw_only=True)
class SetMembershipStats:
    """Counters of one estimator (for the recorder and the benchmarks).

    Attributes
    ----------
    simplifications : int
        Number of outer simplifications applied.
    max_vertices_seen : int
        Largest vertex count of a set before simplification.
    """

    simplifications: int = 0
    max_vertices_seen: int = 0


class SetMembershipEstimator:
    """Set-membership estimator of one UAV (module docstring).

    Parameters
    ----------
    config : SetMembershipConfig
        Parameters.
    free_area : BaseGeometry
        ``X_s``, the ground region where targets may be (m); see :func:`free_search_area`.
    t0 : float
        Initial time (s).
    owner : int
        Index of the UAV running this estimator.
    """

    def __init__(self, config: SetMembershipConfig, free_area: BaseGeometry, t0: float = 0.0, owner: int = 0):
        free = pg.as_polygonal(free_area)
        if free.is_empty:
            raise ValueError("SetMembershipEstimator.free_area must have a positive area")
        self.config = config
        self.free_area = free
        self.area0 = pg.area(free)
        self.owner = int(owner)
        self.stats = SetMembershipStats()
        self._est = SetEstimate(t=float(t0), X=pg.EMPTY, Xbar=free, owner=self.owner)
        self._local = self._est

    @property
    def estimate(self) -> SetEstimate:
        """The current sets (after the last stage run)."""
        return self._est

    @property
    def shared(self) -> SetEstimate:
        """The sets after the last correction, before fusion: what this UAV sends to its neighbours."""
        return self._local

    def normalized_areas(self) -> tuple[float, float]:
        """``(phi(X) / phi(X_s), phi(Xbar) / phi(X_s))`` (dimensionless)."""
        return self._est.area_X / self.area0, self._est.area_Xbar / self.area0

    def _bounded(self, geom: BaseGeometry) -> BaseGeometry:
        cfg = self.config
        n = pg.n_vertices(geom)
        self.stats.max_vertices_seen = max(self.stats.max_vertices_seen, n)
        if n <= cfg.max_vertices:
            return geom
        self.stats.simplifications += 1
        return pg.intersection_all([pg.outer_simplify(geom, cfg.simplify_tol, cfg.max_hole_area), self.free_area])

    def predict(self, t: float) -> SetEstimate:
        """Dilate both sets by ``v_max (t - t_est)`` and clip them to the free area (eqs. 8-9)."""
        dt = float(t) - self._est.t
        if dt < 0:
            raise ValueError(f"predict to t={t} s before the estimate time {self._est.t} s")
        if dt == 0:
            return self._est
        r = self.config.max_target_speed * dt
        q = self.config.quad_segs
        X = self._bounded(pg.intersection_all([pg.dilate(self._est.X, r, q), self.free_area]))
        Xbar = self._bounded(pg.intersection_all([pg.dilate(self._est.Xbar, r, q), self.free_area]))
        self._est = SetEstimate(t=float(t), X=X, Xbar=Xbar, owner=self.owner)
        return self._est

    def update(self, observed_region: BaseGeometry, detections: Sequence[Detection]) -> SetEstimate:
        """Correct with the observed region ``F`` and the bounded-error box detections (eqs. 10-14).

        The detections must be of kind ``"box"`` with a ``bound``; they are taken at the estimate time.
        """
        F = pg.as_polygonal(observed_region)
        est = self._est
        if F.is_empty:
            if detections:
                raise ValueError("detections were given with an empty observed region")
            self._local = est
            return est
        if any(not isinstance(d.model, PositionDetectionModel) or d.bound is None for d in detections):
            raise ValueError("SetMembershipEstimator.update needs box detections with a bound")
        z = np.array([d.z[:2] for d in detections]).reshape(-1, 2)
        w = np.array([d.bound[:2] for d in detections]).reshape(-1, 2)
        Y = pg.intersection_all([pg.boxes_union(z, w), F]) if len(z) else pg.EMPTY
        parts = [pg.as_polygonal(shapely.difference(est.X, F))]
        if not Y.is_empty:
            parts += [pg.intersection_all([est.X, Y]), pg.intersection_all([est.Xbar, Y])]
        X = self._bounded(pg.union_all(parts))
        Xbar = self._bounded(pg.as_polygonal(shapely.difference(est.Xbar, F)))
        self._est = SetEstimate(t=est.t, X=X, Xbar=Xbar, owner=self.owner)
        self._local = self._est
        return self._est

    def fuse(self, neighbours: Sequence[SetEstimate]) -> SetEstimate:
        """Fuse with the neighbours' post-correction sets of the same time (eqs. 15-16).

        The sets are combined in the order of their owners, so UAVs fusing the same sets get the same result to the
        last bit (:meth:`adopt` lets one reuse another's).
        """
        if not neighbours:
            return self._est
        own = self._local
        for n in neighbours:
            if abs(n.t - own.t) > 1e-9:
                raise ValueError(f"fusing a set of t={n.t} s with one of t={own.t} s")
        allsets = sorted([own, *neighbours], key=lambda e: e.owner)
        X = pg.union_all([s.X for s in allsets])
        for s in allsets:
            if X.is_empty:
                break
            # X n (X_l U Xbar_l) as a union of two intersections: both are clipped to the (usually small) extent
            # of X inside the overlay, which avoids the union of two large sets
            X = pg.union_all([pg.intersection_all([X, s.X]), pg.intersection_all([X, s.Xbar])])
        Xbar = pg.intersection_all([s.Xbar for s in allsets])
        self._est = SetEstimate(t=own.t, X=self._bounded(X), Xbar=self._bounded(Xbar), owner=self.owner)
        return self._est

    def adopt(self, fused: SetEstimate) -> SetEstimate:
        """Take the result of another UAV's :meth:`fuse` over the same sets as this UAV's own fused estimate (what
        :meth:`fuse` would compute here); the post-correction set this UAV shares is kept."""
        if abs(fused.t - self._local.t) > 1e-9:
            raise ValueError(f"adopting a fused set of t={fused.t} s at t={self._local.t} s")
        self._est = SetEstimate(t=fused.t, X=fused.X, Xbar=fused.Xbar, owner=self.owner)
        return self._est

    def reset(self, estimate: SetEstimate) -> None:
        """Replace the sets (e.g. to start from a shared estimate)."""
        self._est = estimate
        self._local = estimate

