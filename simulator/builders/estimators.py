"""Estimator builders: a UAV's ``autonomy.estimator`` entry → its target estimator.

Every builder takes an :class:`EstimatorContext` and returns an object the agent steps
(:class:`autonomy.agent.TargetEstimator`). The tracker settings (``params``) reach ``TrackerConfig`` field by field;
the ``imm`` block's settings feed the tracker's ``imm_*`` fields; the fusion method says whether the tracker stacks
the scans of one time (:attr:`worlds.variants.FusionVariant.stacked_scans`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from simulator.builders.common import config_from, in_radians
from simulator.plugins import load_plugin
from worlds.schema import ImmSpec, UavSpec
from worlds.variants import FusionVariant

__all__ = ["ROAD_FALLBACK_FILTER", "EstimatorContext", "build_plugin_estimator", "build_road_tracker",
           "build_set_membership", "build_tracker", "search_free_area"]

ROAD_FALLBACK_FILTER = {"maekf": "ekf", "ecukf": "ukf"}
"""Unconstrained filter a road-constrained tracker starts tracks with and falls back to off the map."""


@dataclass(frozen=True, kw_only=True)
class EstimatorContext:
    """What an estimator builder is given.

    Attributes
    ----------
    uav : UavSpec
        The UAV's world-file entry.
    index : int
        Its index in ``uavs``.
    fusion : FusionVariant
        The UAV's fusion method (whether its tracker stacks scans).
    network : Any
        The world's :class:`~worlds.roads.network.RoadNetwork`, or None without roads.
    buildings : Any
        The world's buildings (footprints for the set-membership estimator).
    """

    uav: UavSpec
    index: int
    fusion: FusionVariant
    network: Any = None
    buildings: Any = ()


def imm_fields(imm: ImmSpec | None) -> dict[str, Any]:
    """The tracker's ``imm_*`` fields of an ``imm`` block (None: the block's defaults), turn rate in rad/s."""
    spec = imm if imm is not None else ImmSpec()
    return {f"imm_{name}": value for name, value in in_radians(spec.model_dump()).items()}


def build_tracker(ctx: EstimatorContext) -> Any:
    """The built-in single-target tracker with the ``ekf``, ``ukf``, ``ckf``, ``scif`` or ``imm`` filter."""
    from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig

    est = ctx.uav.autonomy.estimator
    given: dict[str, Any] = {"filter": est.type, "model": est.model}
    if ctx.fusion.stacked_scans:  # own and teammates' detections of one time: one update
        given["stack_scans"] = True
    if est.type == "imm":
        given.update(imm_fields(est.imm))
    return SingleTargetTracker(config_from(TrackerConfig, est.settings.given(), **given))


def build_road_tracker(ctx: EstimatorContext) -> Any:
    """Paper 002's road-constrained tracker (``maekf``, ``ecukf``) on the world's road network."""
    from autonomy.estimation.road.config import RoadFilterConfig
    from autonomy.estimation.road.tracker import RoadConstrainedTracker, RoadTrackerConfig
    from autonomy.estimation.tracker import TrackerConfig

    est = ctx.uav.autonomy.estimator
    if ctx.network is None:
        raise ValueError(f"estimator type {est.type!r} needs the world's road network (roads: ...)")
    tracker = config_from(TrackerConfig, est.settings.given(), filter=ROAD_FALLBACK_FILTER[est.type],
                          model=est.model)
    road = config_from(RoadFilterConfig, est.road_settings.given(), variant=est.type)
    return RoadConstrainedTracker(RoadTrackerConfig(tracker=tracker, road=road), ctx.network)


def search_free_area(area: tuple[float, float, float, float], buildings: Any) -> Any:
    """``X_s`` of paper 004: the search ``area`` (x_min, y_min, x_max, y_max; m) less the building footprints."""
    import shapely

    from autonomy.estimation.setmem.estimator import free_search_area

    return free_search_area(shapely.box(*area), buildings)


def build_set_membership(ctx: EstimatorContext) -> Any:
    """Paper 004's set-membership tracker on the search area less the buildings' footprints."""
    from autonomy.estimation.setmem.estimator import SetMembershipConfig
    from autonomy.estimation.setmem.tracker import SetMembershipTracker

    est = ctx.uav.autonomy.estimator
    sm = est.set_membership  # required with this type: worlds.checks
    config = config_from(SetMembershipConfig, est.settings.given(), max_target_speed=sm.max_target_speed)
    return SetMembershipTracker(config, search_free_area(sm.area, ctx.buildings), owner=ctx.index)


def build_plugin_estimator(ctx: EstimatorContext) -> Any:
    """A user class (``plugin: package.module:Class``) built with ``params`` as keyword arguments."""
    est = ctx.uav.autonomy.estimator
    cls = load_plugin(est.plugin, f"uavs[{ctx.index}].autonomy.estimator.plugin", ("step",))
    return cls(**est.params)
