"""Guidance builders: a UAV's ``autonomy.guidance`` entry → its guidance law.

Every builder takes a :class:`GuidanceContext` and returns a law with ``command(...)``
(:class:`autonomy.guidance.base.Guidance`). The section's ``params`` reach the law's configuration field by field
(:func:`~simulator.builders.common.config_from`); the settings blocks (``formation``, ``search``, ``infoplan``) feed
the fields of their own names, degrees in radians. The mission keys every law is given (``speed``, ``altitude``,
``standoff_m``) feed the law's field of that meaning, named in :data:`MISSION_FIELDS`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from simulator.builders.common import SENSOR_COMMON, config_from, given
from simulator.factories import channel_config
from simulator.plugins import load_plugin
from worlds.schema import (BearingSpec, BoxSpec, CommsSection, FormationSpec, InfoPlanSpec, RadarSpec, SearchSpec,
                           UavSpec)

__all__ = ["MISSION_FIELDS", "GuidanceContext", "build_fast_mpc", "build_formation", "build_hold", "build_infoplan",
           "build_nmpc", "build_plugin_guidance", "build_search", "build_vector_field", "build_waypoints",
           "mission"]

MISSION_FIELDS: dict[str, dict[str, str]] = {
    "hold": {"speed": "speed"},
    "waypoints": {"speed": "speed"},
    "vector_field": {"standoff_m": "standoff_radius", "speed": "nominal_speed", "altitude": "altitude"},
    "nmpc": {"standoff_m": "standoff_radius", "speed": "nominal_speed", "altitude": "altitude"},
    "fast_mpc": {"altitude": "altitude"},
    "formation": {"speed": "max_speed", "altitude": "altitude"},
    "search": {"speed": "speed", "altitude": "altitude"},
    "infoplan": {"speed": "speed", "altitude": "altitude"},
}
"""For each built-in type, the configuration field each mission key of the guidance section feeds (the keys every
law shares keep one world-file name; the laws name the quantity in their own terms)."""


@dataclass(frozen=True, kw_only=True)
class GuidanceContext:
    """What a guidance builder is given.

    Attributes
    ----------
    uav : UavSpec
        The UAV's world-file entry.
    index : int
        Its index in ``uavs`` (its slot in the team).
    team_size : int
        Number of UAVs in the world.
    buildings : Any
        The world's buildings (keep-out volumes, view shadows).
    comms : CommsSection
        The world's radio, for laws that plan over it.
    estimator : Any
        The UAV's own estimator, for laws that plan on it (search).
    """

    uav: UavSpec
    index: int
    team_size: int
    buildings: Any = ()
    comms: CommsSection = field(default_factory=CommsSection)
    estimator: Any = None


def mission(ctx: GuidanceContext) -> dict[str, Any]:
    """The configuration fields the guidance section's mission keys give the UAV's law (:data:`MISSION_FIELDS`)."""
    g = ctx.uav.autonomy.guidance
    return {field: getattr(g, key) for key, field in MISSION_FIELDS[g.type].items()}


def build_hold(ctx: GuidanceContext) -> Any:
    """Hold the start position."""
    from autonomy.guidance.waypoints import WaypointConfig, WaypointGuidance

    g = ctx.uav.autonomy.guidance
    return WaypointGuidance(config_from(WaypointConfig, g.settings.given(),
                                        waypoints=(tuple(ctx.uav.initial.position),), **mission(ctx)))


def build_waypoints(ctx: GuidanceContext) -> Any:
    """Fly the ``waypoints`` in order."""
    from autonomy.guidance.waypoints import WaypointConfig, WaypointGuidance

    g = ctx.uav.autonomy.guidance
    return WaypointGuidance(config_from(WaypointConfig, g.settings.given(),
                                        waypoints=tuple(tuple(w) for w in g.waypoints), **mission(ctx)))


def build_vector_field(ctx: GuidanceContext) -> Any:
    """Lyapunov vector-field standoff orbit, slot ``index`` of the team."""
    from autonomy.guidance.vector_field import VectorFieldConfig, VectorFieldGuidance

    g = ctx.uav.autonomy.guidance
    cfg = config_from(VectorFieldConfig, g.settings.given(), team_size=ctx.team_size, **mission(ctx))
    return VectorFieldGuidance(cfg, slot=ctx.index)


def build_nmpc(ctx: GuidanceContext) -> Any:
    """NMPC standoff orbit with building keep-outs, slot ``index`` of the team."""
    from autonomy.guidance.nmpc import NmpcStandoffGuidance
    from autonomy.guidance.nmpc_config import NmpcConfig

    g = ctx.uav.autonomy.guidance
    cfg = config_from(NmpcConfig, g.settings.given(), team_size=ctx.team_size, **mission(ctx))
    return NmpcStandoffGuidance(cfg, slot=ctx.index, buildings=ctx.buildings)


def build_fast_mpc(ctx: GuidanceContext) -> Any:
    """Paper 000's fast MPC with separation constraints."""
    from autonomy.guidance.fast_mpc import FastMpcConfig, FastMpcGuidance

    g = ctx.uav.autonomy.guidance
    return FastMpcGuidance(config_from(FastMpcConfig, g.settings.given(), **mission(ctx)))


def build_formation(ctx: GuidanceContext) -> Any:
    """FIM-optimal formation guidance of UAV ``index`` in a team of ``team_size`` (:class:`FormationSpec`)."""
    from autonomy.guidance.formation.guidance import FormationConfig, FormationGuidance
    from autonomy.guidance.formation.jacobi import JacobiGains

    uav = ctx.uav
    g = uav.autonomy.guidance
    form = g.formation if g.formation is not None else FormationSpec()
    block = given(form, {"gains", "ranges"})
    if "sigma_bearing" not in block:  # the UAV's bearing sensor's: worlds.checks
        block["sigma_bearing"] = math.radians(next(s.sigma_azimuth_deg for s in uav.sensors
                                                   if isinstance(s, BearingSpec)))
    cfg = FormationConfig(team_size=ctx.team_size, ranges=None if form.ranges is None else tuple(form.ranges),
                          gains=JacobiGains(**form.gains.model_dump()), dt=1.0 / uav.autonomy.rate_hz,
                          **mission(ctx), **block)
    return FormationGuidance(cfg, agent_id=ctx.index)


def build_search(ctx: GuidanceContext) -> Any:
    """Paper 004's search MPC over the UAV's own set-membership estimator (a
    :class:`~autonomy.estimation.setmem.tracker.SetMembershipTracker`), seeing through the UAV's box sensor."""
    import numpy as np

    from autonomy.estimation.setmem.tracker import SetMembershipTracker
    from autonomy.guidance.search.guidance import SetMembershipSearchGuidance
    from autonomy.guidance.search.planner import SearchConfig, SearchPlanner
    from autonomy.guidance.search.regions import PrismViewRegion
    from autonomy.sensing.box_sensor import BoxSensorConfig
    from vehicles.quadrotor.airframes import load_airframe

    uav, estimator = ctx.uav, ctx.estimator
    if not isinstance(estimator, SetMembershipTracker):
        raise ValueError("guidance type 'search' plans on the UAV's own set_membership estimator, got "
                         f"{type(estimator).__name__}")
    g = uav.autonomy.guidance
    spec = g.search if g.search is not None else SearchSpec()
    box = next(s for s in uav.sensors if isinstance(s, BoxSpec))  # worlds.checks
    sensor = BoxSensorConfig(**given(box, SENSOR_COMMON | {"rate_hz", "latency_s"}))
    config = SearchConfig(dt=1.0 / uav.autonomy.rate_hz, max_target_speed=estimator.estimator.config.max_target_speed,
                          **mission(ctx), **given(spec, {"velocity_lag_s"}))
    reach = np.sqrt(2.0) * (g.altitude - sensor.ground_z) * np.tan(sensor.opening_angle / 2)
    planner = SearchPlanner(config, PrismViewRegion(sensor, ctx.buildings), estimator.estimator.free_area,
                            ctx.buildings, footprint_radius=float(reach))
    return SetMembershipSearchGuidance(planner, estimator.estimator, velocity_lag_s=spec.velocity_lag_s,
                                       max_speed=load_airframe(uav.airframe).max_speed)


def build_infoplan(ctx: GuidanceContext) -> Any:
    """Paper 001's information planner as UAV ``index``'s guidance (:class:`InfoPlanSpec`; the radar, base station
    and radio are the world's: ``worlds.checks`` makes sure they exist). The block's ``heading_rates`` (a count) is
    the config's ``n_heading_rates``: the config's ``heading_rates`` is the grid itself."""
    from autonomy.guidance.infoplan.config import InfoPlannerConfig
    from autonomy.guidance.infoplan.guidance import InfoPlannerGuidance

    uav, comms = ctx.uav, ctx.comms
    g = uav.autonomy.guidance
    plan = g.infoplan if g.infoplan is not None else InfoPlanSpec()
    radar = next(s for s in uav.sensors if isinstance(s, RadarSpec))
    if comms.base_station is None:
        raise ValueError("guidance infoplan needs comms.base_station")
    block = given(plan, {"routing", "heading_rates"})
    cfg = config_from(InfoPlannerConfig, g.settings.given(), base_p_W=tuple(comms.base_station[:2]),
                      dt=1.0 / uav.autonomy.rate_hz, n_heading_rates=plan.heading_rates,
                      sigma_range=radar.sigma_range, sigma_bearing=math.radians(radar.sigma_azimuth_deg),
                      channel=channel_config(comms), routing=plan.routing or comms.routing, **mission(ctx), **block)
    return InfoPlannerGuidance(cfg, uav_id=ctx.index)


def build_plugin_guidance(ctx: GuidanceContext) -> Any:
    """A user class (``plugin: package.module:Class``) built with ``params`` as keyword arguments."""
    g = ctx.uav.autonomy.guidance
    cls = load_plugin(g.plugin, f"uavs[{ctx.index}].autonomy.guidance.plugin", ("command",))
    return cls(**g.params)
