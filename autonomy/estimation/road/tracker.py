"""Road-constrained single-target tracker: :class:`SingleTargetTracker` with a :class:`RoadNetworkFilter` as its filter.

Initiation (two-point), χ² gating, association, coasting and loss are the base tracker's; once a track is confirmed its
unconstrained filter is wrapped in a :class:`RoadNetworkFilter`, which keeps it as the off-map fallback and runs the
road hypotheses alongside. ``step(t, detections)`` returns the same :class:`TargetEstimate` as the other estimators.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from autonomy.estimation.road.config import RoadFilterConfig
from autonomy.estimation.road.network_filter import RoadNetworkFilter
from autonomy.estimation.road.roadmap import RoadMap
from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig
from worlds.roads.network import RoadNetwork

__all__ = ["RoadTrackerConfig", "RoadConstrainedTracker"]


def _paper_tracker() -> TrackerConfig:
    """Paper 002's Singer target model (α = 0.6 1/s, σa = 0.66 m/s²) with an EKF fallback."""
    return TrackerConfig(filter="ekf", model="singer", singer_alpha=0.6, singer_sigma_a=0.66)


@dataclass(frozen=True, kw_only=True)
class RoadTrackerConfig:
    """Road-constrained tracker settings.

    Attributes
    ----------
    tracker : TrackerConfig
        Initiation, gating, loss and the motion model (shared by the fallback and the constrained filters); the
        unconstrained fallback filter is ``tracker.filter``.
    road : RoadFilterConfig
        Constrained variant (``"maekf"`` | ``"ecukf"``), constraint noises, junction and off-map settings.
    """

    tracker: TrackerConfig = field(default_factory=_paper_tracker)
    road: RoadFilterConfig = field(default_factory=RoadFilterConfig)

    def __post_init__(self) -> None:
        if not isinstance(self.tracker, TrackerConfig):
            raise ValueError(f"RoadTrackerConfig.tracker must be a TrackerConfig, got {type(self.tracker).__name__}")
        if not isinstance(self.road, RoadFilterConfig):
            raise ValueError(f"RoadTrackerConfig.road must be a RoadFilterConfig, got {type(self.road).__name__}")


class RoadConstrainedTracker(SingleTargetTracker):
    """Single-target tracker whose estimate follows the road network (see the module docstring).

    Parameters
    ----------
    config : RoadTrackerConfig
        Settings.
    network : RoadNetwork
        The known road map.
    """

    def __init__(self, config: RoadTrackerConfig, network: RoadNetwork) -> None:
        super().__init__(config.tracker)
        self.road_config = config
        self.roadmap = RoadMap(network, config.road.constraint, vertex_spacing=config.road.vertex_spacing,
                               line_curvature=config.road.line_curvature)

    def _initiate(self, dets: Sequence[object]) -> bool:
        ok = super()._initiate(dets)
        if ok:
            self.filter = RoadNetworkFilter(self.filter, self.roadmap, self.road_config.road)
        return ok

    def _nis(self, det: object) -> float:
        """Gate against the unconstrained filter: a detection is validated if it is plausible for the target at all,
        so a car leaving the road is not gated out by the (tight across the road) constrained estimate."""
        f = self.filter
        if not isinstance(f, RoadNetworkFilter):
            return super()._nis(det)
        self.filter = f.unconstrained
        try:
            return super()._nis(det)
        finally:
            self.filter = f

    @property
    def on_road(self) -> bool:
        """True while the track is constrained to the road network."""
        return isinstance(self.filter, RoadNetworkFilter) and self.filter.attached

    @property
    def road_id(self) -> str | None:
        """Road of the dominant hypothesis, or None off the map / without a track."""
        if not isinstance(self.filter, RoadNetworkFilter) or self.filter.dominant is None:
            return None
        return self.filter.dominant.road_id

    def road_held(self) -> str:
        """Road the target is held on (:attr:`road_id` while :attr:`on_road`), "" otherwise."""
        return (self.road_id or "") if self.on_road else ""

    def hypotheses(self) -> list[tuple[str, float]]:
        """(road id of the active segment, normalised weight) of each live hypothesis."""
        if not isinstance(self.filter, RoadNetworkFilter):
            return []
        return [(h.road_id, float(w)) for h, w in zip(self.filter.hypotheses, self.filter.weights, strict=True)]
