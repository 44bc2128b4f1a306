"""Road-constrained single-target tracker: :class:`SingleTargetTracker` with a :class:`RoadNetworkFilter` as its filter.

Initiation (two-point), χ² gating, association, coasting and loss are the base tracker's parts; the filter factory
(:class:`RoadFilters`) wraps a confirmed track's unconstrained filter in a :class:`RoadNetworkFilter`, which keeps it
as the off-map fallback and runs the road hypotheses alongside, and the gate measures against that fallback
(:func:`unconstrained`). ``step(t, detections)`` returns the same :class:`TargetEstimate` as the other estimators.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from autonomy.estimation.base import Filter
from autonomy.estimation.road.config import RoadFilterConfig
from autonomy.estimation.road.network_filter import RoadNetworkFilter
from autonomy.estimation.road.roadmap import RoadMap
from autonomy.estimation.tracker import ConfiguredFilters, SingleTargetTracker, TrackerConfig, make_motion_model
from autonomy.estimation.tracking.initiator import FilterFactory
from worlds.roads.network import RoadNetwork

__all__ = ["RoadConstrainedTracker", "RoadFilters", "RoadTrackerConfig", "unconstrained"]


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


class RoadFilters:
    """A new track's filter wrapped in a :class:`RoadNetworkFilter`: the unconstrained filter of ``base`` stays the
    off-map fallback and the road hypotheses run alongside.

    Parameters
    ----------
    base : FilterFactory
        Builds the unconstrained filter from ``(x0, P0, t0)``.
    roadmap : RoadMap
        The road map of the hypotheses.
    config : RoadFilterConfig
        Constrained variant, constraint noises, junction and off-map settings.
    """

    def __init__(self, base: FilterFactory, roadmap: RoadMap, config: RoadFilterConfig) -> None:
        self.base = base
        self.roadmap = roadmap
        self.config = config

    def __call__(self, x0: np.ndarray, P0: np.ndarray, t0: float) -> RoadNetworkFilter:
        """The road-network filter around the unconstrained one started from ``(x0, P0)`` at ``t0`` (s)."""
        return RoadNetworkFilter(self.base(x0, P0, t0), self.roadmap, self.config)


def unconstrained(f: Filter) -> Filter:
    """The filter to gate against: a road-network filter's unconstrained fallback (a detection is validated if it
    is plausible for the target at all, so a car leaving the road is not gated out by the constrained estimate,
    tight across the road), any other filter itself."""
    return f.unconstrained if isinstance(f, RoadNetworkFilter) else f


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
        model = make_motion_model(config.tracker)
        roadmap = RoadMap(network, config.road.constraint, vertex_spacing=config.road.vertex_spacing,
                          line_curvature=config.road.line_curvature)
        super().__init__(config.tracker, model=model,
                         filters=RoadFilters(ConfiguredFilters(config.tracker, model), roadmap, config.road),
                         gating_filter=unconstrained)
        self.road_config = config
        self.roadmap = roadmap

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
