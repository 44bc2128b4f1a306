"""The registry of builders: each world-file tag of a sensor, estimator or guidance law maps to one builder.

The world schema accepts the tags registered in :mod:`worlds.variants` (with their typed settings); here each tag
maps to the function that builds its component. A new guidance law is one module (its settings model, builder and
law) plus one line, ``register_guidance("circle", CircleSettings, build_circle)``, which registers both halves.
The front doors :func:`build_sensor`, :func:`build_estimator` and :func:`build_guidance` look the UAV's tags up.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from pydantic import BaseModel

from autonomy.sensing.measurement import Sensor
from simulator.builders.estimators import (EstimatorContext, build_plugin_estimator, build_road_tracker,
                                           build_set_membership, build_tracker)
from simulator.builders.guidance import (GuidanceContext, build_fast_mpc, build_formation, build_hold,
                                         build_infoplan, build_nmpc, build_plugin_guidance, build_search,
                                         build_vector_field, build_waypoints)
from simulator.builders.sensors import build_bearing, build_box, build_camera, build_radar
from worlds import variants
from worlds.checks import register_component_check
from worlds.errors import WorldIssue
from worlds.schema import CommsSection, UavSpec, World

__all__ = ["ESTIMATOR_BUILDERS", "GUIDANCE_BUILDERS", "SENSOR_BUILDERS", "build_estimator", "build_guidance",
           "build_sensor", "register_estimator", "register_guidance", "sensor_issues"]

SensorBuilder = Callable[[Any, str, Any], Sensor]
EstimatorBuilder = Callable[[EstimatorContext], Any]
GuidanceBuilder = Callable[[GuidanceContext], Any]

SENSOR_BUILDERS: dict[str, SensorBuilder] = {
    "radar": build_radar,
    "camera": build_camera,
    "bearing": build_bearing,
    "box": build_box,
}
"""Sensor builders by the sensor entry's ``type``."""

ESTIMATOR_BUILDERS: dict[str, EstimatorBuilder] = {
    "ekf": build_tracker,
    "ukf": build_tracker,
    "ckf": build_tracker,
    "scif": build_tracker,
    "imm": build_tracker,
    "maekf": build_road_tracker,
    "ecukf": build_road_tracker,
    "set_membership": build_set_membership,
    "plugin": build_plugin_estimator,
}
"""Estimator builders by ``autonomy.estimator.type`` (the tags of :data:`worlds.variants.ESTIMATORS`)."""

GUIDANCE_BUILDERS: dict[str, GuidanceBuilder] = {
    "hold": build_hold,
    "waypoints": build_waypoints,
    "vector_field": build_vector_field,
    "nmpc": build_nmpc,
    "fast_mpc": build_fast_mpc,
    "formation": build_formation,
    "search": build_search,
    "infoplan": build_infoplan,
    "plugin": build_plugin_guidance,
}
"""Guidance builders by ``autonomy.guidance.type`` (the tags of :data:`worlds.variants.GUIDANCES`)."""


def register_guidance(tag: str, settings: type[BaseModel], builder: GuidanceBuilder) -> None:
    """Add a guidance type: the world schema accepts ``type: tag`` with ``params`` checked against ``settings``
    at load, and :func:`build_guidance` builds it with ``builder``."""
    variants.register_guidance(tag, variants.GuidanceVariant(settings=settings))
    GUIDANCE_BUILDERS[tag] = builder


def register_estimator(tag: str, settings: type[BaseModel], builder: EstimatorBuilder) -> None:
    """Add an estimator type (``params`` checked against ``settings`` at load; built with ``builder``)."""
    variants.register_estimator(tag, variants.EstimatorVariant(settings=settings))
    ESTIMATOR_BUILDERS[tag] = builder


def sensor_issues(world: World) -> list[WorldIssue]:
    """Every sensor entry of ``world`` that its sensor model refuses (its config's cross-field rules with the model's
    own defaults), as load-time issues: registered with :func:`worlds.checks.register_component_check`."""
    issues = []
    for i, u in enumerate(world.uavs):
        for j, spec in enumerate(u.sensors):
            try:
                build_sensor(spec, spec.id or f"{u.id}/{spec.type}{j}")
            except (ValueError, TypeError) as exc:
                issues.append(WorldIssue(f"uavs[{i}].sensors[{j}]", spec.model_dump(exclude_none=True),
                                         f"settings the {spec.type} model accepts ({exc})"))
    return issues


register_component_check(sensor_issues)


def build_sensor(spec: Any, name: str, buildings: Any = ()) -> Sensor:
    """A sensor model from its world-file entry (``buildings`` are the box sensor's shadow casters)."""
    builder = SENSOR_BUILDERS.get(getattr(spec, "type", None))
    if builder is None:
        raise TypeError(f"unknown sensor spec {type(spec).__name__}")
    return builder(spec, name, buildings)


def build_estimator(uav: UavSpec, index: int, network: Any = None, buildings: Any = ()) -> Any:
    """The UAV's target estimator: the built-in single-target tracker, a road-constrained tracker on ``network``
    (the world's :class:`~worlds.roads.network.RoadNetwork`) for ``maekf``/``ecukf``, the set-membership tracker on
    the search area less the ``buildings``' footprints, a registered type, or a plugin class built with ``params``."""
    auto = uav.autonomy
    ctx = EstimatorContext(uav=uav, index=index, fusion=auto.fusion.variant, network=network, buildings=buildings)
    return ESTIMATOR_BUILDERS[auto.estimator.type](ctx)


def build_guidance(uav: UavSpec, index: int, team_size: int, buildings: Any, comms: CommsSection | None = None,
                   estimator: Any = None) -> Any:
    """The UAV's guidance law from its world-file entry (``comms``: the world's radio, for guidance that plans over
    it; ``estimator``: the UAV's own, which the search law reads)."""
    ctx = GuidanceContext(uav=uav, index=index, team_size=team_size, buildings=buildings,
                          comms=comms if comms is not None else CommsSection(), estimator=estimator)
    return GUIDANCE_BUILDERS[uav.autonomy.guidance.type](ctx)
