"""Settings of the road-constrained network filter (:class:`autonomy.estimation.road.network_filter.RoadNetworkFilter`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from autonomy.estimation.road.constraint import RoadConstraintParams

__all__ = ["RoadFilterConfig"]


@dataclass(frozen=True, kw_only=True)
class RoadFilterConfig:
    """Settings of the road-constrained network filter.

    Attributes
    ----------
    variant : {"maekf", "ecukf"}
        Constrained filter of each hypothesis.
    ecukf_stage2 : {"pseudo", "project"}
        ECUKF constraint stage (see :mod:`autonomy.estimation.road.filters`).
    constraint : RoadConstraintParams
        Pseudo-measurement noises and lane offset.
    vertex_spacing : float or None
        Resampling of the road centre-lines before the biarc fit (m); None: the roads' own vertices.
    line_curvature : float
        Biarc pieces flatter than this become lines (1/m), >= 0.
    spawn_distance : float
        Spawn successor hypotheses this far (m) before the end of a road, > 0.
    prune_threshold : float
        Drop hypotheses whose normalised weight falls below this, in (0, 1).
    merge_threshold : float
        Keep only the dominant hypothesis once its weight reaches this, in (0, 1]; 1 keeps every hypothesis above
        ``prune_threshold``.
        Why the defaults (1e-6 and 1, not 1e-3 and 0.995): a car that waits at a junction and then turns stands on
        the straight-on child's line while it waits, so that child gathers the weight; when the turn shows, the child
        of the branch taken must still be alive to take it back. With 1e-3 / 0.995 it often was not, and the track
        followed the wrong branch until it left the map: replaying nine recorded ``road_standoff`` runs (ECUKF,
        Table I's Singer model), mid-block estimates on a wrong branch lagged the car by 40 m, and the fused error was
        11.6 m against the EKF's 11.3 m; with 1e-6 / 1 (and the ``switch_probability`` gate) it was 10.3 m.
    switch_probability : float
        χ²(1) probability of the gate the unconstrained position must leave the current road's carriageway by before
        a hypothesis near a junction crosses to its next road ahead of its own estimate, in (0, 1).
    max_hypotheses : int
        Upper bound on simultaneous hypotheses, >= 1.
    off_road_probability : float
        χ²(1) probability of the leave-the-map gate, in (0, 1).
    off_road_scans : int
        Consecutive updates outside the gate before leaving the map, >= 1.
    attach_probability : float
        χ²(1) probability of the attach gate, in (0, 1); below ``off_road_probability`` for hysteresis.
    attach_scans : int
        Consecutive updates inside the attach gate before (re-)attaching, >= 1.
    direction_weighting : bool
        Let each hypothesis' weight carry ``Φ(v_t / σ_vt)`` of its current estimate, the probability that its car
        drives with its directed road (roads are one-way; a two-way street is two twins): per measurement time the
        weight is multiplied by the new value over the one it carries. Without it a hypothesis on the twin, or on the
        branch opposite the one taken (whose line, extended back through the junction, covers the taken one), differs
        from the right one only by the lane offset and is hardly told apart. Only weight ratios matter, so a stopped
        car (Φ = ½ for every hypothesis) changes nothing.
        Why the ratio, not the factor at every measurement time: the velocity estimate is the same evidence from one
        scan to the next, and multiplying by ``Φ`` at every scan counted it again each time: while a car waited at a
        junction, the noise in the children's velocities made their weight ratios a random walk, and one child
        became certain with no evidence. Replaying 20 ``road_standoff`` cars seen by the paper's radars from 500 m
        (ECUKF), hypotheses that held ≥ 0.95 of the weight among several, with the car moving, were on its route 65 %
        of the time (86 % with the ratio), and the fused error was 14.6 m (13.0 m with the ratio; EKF 16.4 m).
    wrong_way_z : float or None
        A hypothesis whose along-road speed is below ``−wrong_way_z`` standard deviations moves to the road's twin
        (dimensionless, > 0); None disables it.
    """

    variant: Literal["maekf", "ecukf"] = "maekf"
    ecukf_stage2: Literal["pseudo", "project"] = "project"
    constraint: RoadConstraintParams = field(default_factory=RoadConstraintParams)
    vertex_spacing: float | None = 10.0
    line_curvature: float = 1e-4
    spawn_distance: float = 30.0
    prune_threshold: float = 1e-6
    merge_threshold: float = 1.0
    switch_probability: float = 0.99
    max_hypotheses: int = 8
    off_road_probability: float = 0.999
    off_road_scans: int = 2
    attach_probability: float = 0.99
    attach_scans: int = 2
    direction_weighting: bool = True
    wrong_way_z: float | None = 3.0

    def __post_init__(self) -> None:
        if self.variant not in ("maekf", "ecukf"):
            raise ValueError(f"RoadFilterConfig.variant must be 'maekf' or 'ecukf', got {self.variant!r}")
        if self.ecukf_stage2 not in ("pseudo", "project"):
            raise ValueError(f"RoadFilterConfig.ecukf_stage2 must be 'pseudo' or 'project', got {self.ecukf_stage2!r}")
        if self.vertex_spacing is not None and not (self.vertex_spacing > 0):
            raise ValueError(f"RoadFilterConfig.vertex_spacing must be > 0 m or None, got {self.vertex_spacing!r}")
        if not (self.line_curvature >= 0):
            raise ValueError(f"RoadFilterConfig.line_curvature must be >= 0 1/m, got {self.line_curvature!r}")
        if not (self.spawn_distance > 0):
            raise ValueError(f"RoadFilterConfig.spawn_distance must be > 0 m, got {self.spawn_distance!r}")
        for name in ("prune_threshold", "off_road_probability", "attach_probability", "switch_probability"):
            if not 0 < getattr(self, name) < 1:
                raise ValueError(f"RoadFilterConfig.{name} must be in (0, 1), got {getattr(self, name)!r}")
        if not 0 < self.merge_threshold <= 1:
            raise ValueError(f"RoadFilterConfig.merge_threshold must be in (0, 1], got {self.merge_threshold!r}")
        for name in ("max_hypotheses", "off_road_scans", "attach_scans"):
            if not (isinstance(getattr(self, name), int) and getattr(self, name) >= 1):
                raise ValueError(f"RoadFilterConfig.{name} must be an integer >= 1, got {getattr(self, name)!r}")
        if self.wrong_way_z is not None and not (self.wrong_way_z > 0):
            raise ValueError(f"RoadFilterConfig.wrong_way_z must be > 0 or None, got {self.wrong_way_z!r}")
        if self.attach_probability > self.off_road_probability:
            raise ValueError(f"RoadFilterConfig.attach_probability ({self.attach_probability}) must not exceed "
                             f"off_road_probability ({self.off_road_probability})")
