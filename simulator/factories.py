"""World-file entries → configured components: sensors, estimators, guidance laws, fleet options, the car fleet.

World files give angles in degrees (``*_deg``) and leave out what should take a component's own default; here the
degrees become radians and only the given fields reach the component's config dataclass, whose ``__post_init__``
validates them.
"""

from __future__ import annotations

import math
from typing import Any

from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig
from autonomy.guidance.waypoints import WaypointConfig, WaypointGuidance
from simulator.plugins import load_plugin
from worlds.schema import (BearingSpec, BoxSpec, CameraSpec, CommsSection, FormationSpec, FovSpec, ImmSpec,
                           InfoPlanSpec, RadarSpec, SearchSpec, UavSpec, World)

__all__ = [
    "build_car_fleet",
    "build_estimator",
    "build_channel",
    "build_guidance",
    "build_sensor",
    "channel_config",
    "fleet_options",
]

_COMMON = {"id", "type", "fov"}


def _given(spec: Any, skip: set[str] = _COMMON) -> dict[str, Any]:
    """Fields set in the world file (None = use the component default), degrees converted to radians."""
    out: dict[str, Any] = {}
    for name, value in spec.model_dump(exclude_none=True).items():
        if name in skip:
            continue
        if name.endswith("_deg"):
            out[name[:-4]] = math.radians(value)
        else:
            out[name] = value
    return out


def _fov(spec: FovSpec | None) -> Any:
    from autonomy.sensing.fov import FieldOfRegard

    if spec is None:
        return FieldOfRegard()
    return FieldOfRegard(frame=spec.frame, azimuth_limits=tuple(math.radians(a) for a in spec.azimuth_limits_deg),
                         elevation_limits=tuple(math.radians(a) for a in spec.elevation_limits_deg))


def build_sensor(spec: Any, name: str, buildings: Any = ()) -> Any:
    """A sensor model from its world-file entry (``buildings`` are the box sensor's shadow casters)."""
    if isinstance(spec, RadarSpec):
        from autonomy.sensing.radar import Radar, RadarConfig

        return Radar(RadarConfig(**_given(spec), fov=_fov(spec.fov)), sensor_id=name)
    if isinstance(spec, CameraSpec):
        from autonomy.sensing.camera import Camera, CameraConfig

        return Camera(CameraConfig(**_given(spec)), sensor_id=name)
    if isinstance(spec, BearingSpec):
        from autonomy.sensing.bearing import BearingConfig, BearingSensor

        return BearingSensor(BearingConfig(**_given(spec), fov=_fov(spec.fov)), sensor_id=name)
    if isinstance(spec, BoxSpec):
        from autonomy.sensing.box_sensor import BoxSensor, BoxSensorConfig

        return BoxSensor(BoxSensorConfig(**_given(spec)), buildings=buildings, sensor_id=name)
    raise TypeError(f"unknown sensor spec {type(spec).__name__}")


ROAD_FALLBACK_FILTER = {"maekf": "ekf", "ecukf": "ukf"}
"""Unconstrained filter a road-constrained tracker starts tracks with and falls back to off the map."""


def build_estimator(uav: UavSpec, index: int, network: Any = None, buildings: Any = ()) -> Any:
    """The UAV's target estimator: the built-in single-target tracker, a road-constrained tracker on ``network``
    (the world's :class:`~worlds.roads.network.RoadNetwork`) for ``maekf``/``ecukf``, the set-membership tracker on
    the search area less the ``buildings``' footprints, or a plugin class built with ``params``."""
    est = uav.autonomy.estimator
    if est.type == "plugin":
        cls = load_plugin(est.plugin, f"uavs[{index}].autonomy.estimator.plugin", ("step",))
        return cls(**est.params)
    if est.type == "set_membership":
        from autonomy.estimation.setmem.estimator import SetMembershipConfig
        from autonomy.estimation.setmem.tracker import SetMembershipTracker

        sm = est.set_membership  # required with this type: worlds.checks
        config = SetMembershipConfig(max_target_speed=sm.max_target_speed, **est.params)
        return SetMembershipTracker(config, search_free_area(sm.area, buildings), owner=index)
    if est.type in ROAD_FALLBACK_FILTER:
        from autonomy.estimation.road.config import RoadFilterConfig
        from autonomy.estimation.road.constraint import RoadConstraintParams
        from autonomy.estimation.road.tracker import RoadConstrainedTracker, RoadTrackerConfig

        if network is None:
            raise ValueError(f"estimator type {est.type!r} needs the world's road network (roads: ...)")
        road = dict(est.road)
        if isinstance(road.get("constraint"), dict):
            road["constraint"] = RoadConstraintParams(**road["constraint"])
        tracker = TrackerConfig(filter=ROAD_FALLBACK_FILTER[est.type], model=est.model, **est.params)
        return RoadConstrainedTracker(RoadTrackerConfig(tracker=tracker, road=RoadFilterConfig(variant=est.type,
                                                                                                **road)), network)
    given: dict[str, Any] = {"filter": est.type, "model": est.model}
    if uav.autonomy.fusion.method == "measurements":  # own and teammates' detections of one time: one update
        given["stack_scans"] = True
    if est.type == "imm":
        imm = est.imm if est.imm is not None else ImmSpec()
        given.update(imm_turn_rate=math.radians(imm.turn_rate_deg_s), imm_q_turn=imm.q_turn, imm_p_stay=imm.p_stay)
    return SingleTargetTracker(TrackerConfig(**{**given, **est.params}))


def search_free_area(area: tuple[float, float, float, float], buildings: Any) -> Any:
    """``X_s`` of paper 004: the search ``area`` (x_min, y_min, x_max, y_max; m) less the building footprints."""
    import shapely

    from autonomy.estimation.setmem.estimator import free_search_area

    return free_search_area(shapely.box(*area), buildings)


def build_guidance(uav: UavSpec, index: int, team_size: int, buildings: Any, comms: CommsSection | None = None,
                   estimator: Any = None) -> Any:
    """The UAV's guidance law from its world-file entry (``comms``: the world's radio, for guidance that plans over
    it; ``estimator``: the UAV's own, which the search law reads)."""
    g = uav.autonomy.guidance
    if g.type == "plugin":
        cls = load_plugin(g.plugin, f"uavs[{index}].autonomy.guidance.plugin", ("command",))
        return cls(**g.params)
    if g.type == "hold":
        return WaypointGuidance(WaypointConfig(waypoints=(tuple(uav.initial.position),), speed=g.speed, **g.params))
    if g.type == "waypoints":
        return WaypointGuidance(WaypointConfig(waypoints=tuple(tuple(w) for w in g.waypoints), speed=g.speed,
                                               **g.params))
    common = dict(standoff_radius=g.standoff_m, nominal_speed=g.speed, altitude=g.altitude, team_size=team_size)
    if g.type == "vector_field":
        from autonomy.guidance.vector_field import VectorFieldConfig, VectorFieldGuidance

        return VectorFieldGuidance(VectorFieldConfig(**common, **g.params), slot=index)
    if g.type == "nmpc":
        from autonomy.guidance.nmpc import NmpcStandoffGuidance
        from autonomy.guidance.nmpc_config import NmpcConfig

        return NmpcStandoffGuidance(NmpcConfig(**common, **g.params), slot=index, buildings=buildings)
    if g.type == "formation":
        return _formation(uav, index, team_size)
    if g.type == "search":
        return _search(uav, buildings, estimator)
    if g.type == "infoplan":
        return _infoplan(uav, index, comms if comms is not None else CommsSection())
    if g.type == "fast_mpc":
        from autonomy.guidance.fast_mpc import FastMpcConfig, FastMpcGuidance

        return FastMpcGuidance(FastMpcConfig(altitude=g.altitude, **g.params))
    raise ValueError(f"unknown guidance type {g.type!r}")


def _formation(uav: UavSpec, index: int, team_size: int) -> Any:
    """FIM-optimal formation guidance of UAV ``index`` in a team of ``team_size`` (:class:`FormationSpec`)."""
    from autonomy.guidance.formation.guidance import FormationConfig, FormationGuidance
    from autonomy.guidance.formation.jacobi import JacobiGains

    g = uav.autonomy.guidance
    form = g.formation if g.formation is not None else FormationSpec()
    sigma_deg = form.sigma_bearing_deg
    if sigma_deg is None:
        sigma_deg = next(s.sigma_azimuth_deg for s in uav.sensors if isinstance(s, BearingSpec))  # worlds.checks
    cfg = FormationConfig(team_size=team_size, sigma_bearing=math.radians(sigma_deg),
                          ranges=None if form.ranges is None else tuple(form.ranges),
                          gains=JacobiGains(**form.gains.model_dump()), dt=1.0 / uav.autonomy.rate_hz,
                          max_speed=g.speed, backward_weight=form.backward_weight, n_rotations=form.n_rotations,
                          altitude=g.altitude, altitude_gain=form.altitude_gain, geometry=form.geometry,
                          trail_fan=math.radians(form.trail_fan_deg), **g.params)
    return FormationGuidance(cfg, agent_id=index)


def _search(uav: UavSpec, buildings: Any, estimator: Any) -> Any:
    """Paper 004's search MPC over the UAV's own set-membership ``estimator`` (a
    :class:`~autonomy.estimation.setmem.tracker.SetMembershipTracker`), seeing through the UAV's box sensor."""
    import numpy as np

    from autonomy.estimation.setmem.tracker import SetMembershipTracker
    from autonomy.guidance.search.guidance import SetMembershipSearchGuidance
    from autonomy.guidance.search.planner import SearchConfig, SearchPlanner
    from autonomy.guidance.search.regions import PrismViewRegion
    from autonomy.sensing.box_sensor import BoxSensorConfig

    if not isinstance(estimator, SetMembershipTracker):
        raise ValueError("guidance type 'search' plans on the UAV's own set_membership estimator, got "
                         f"{type(estimator).__name__}")
    from vehicles.quadrotor.airframes import load_airframe

    g = uav.autonomy.guidance
    spec = g.search if g.search is not None else SearchSpec()
    given = _given(spec, {"velocity_lag_s"})
    box = next(s for s in uav.sensors if isinstance(s, BoxSpec))  # worlds.checks
    sensor = BoxSensorConfig(**_given(box, _COMMON | {"rate_hz", "latency_s"}))
    config = SearchConfig(speed=g.speed, altitude=g.altitude, dt=1.0 / uav.autonomy.rate_hz,
                          max_target_speed=estimator.estimator.config.max_target_speed, **given)
    reach = np.sqrt(2.0) * (g.altitude - sensor.ground_z) * np.tan(sensor.opening_angle / 2)
    planner = SearchPlanner(config, PrismViewRegion(sensor, buildings), estimator.estimator.free_area, buildings,
                            footprint_radius=float(reach))
    return SetMembershipSearchGuidance(planner, estimator.estimator, lag_s=spec.velocity_lag_s,
                                       max_speed=load_airframe(uav.airframe).max_speed)


def _infoplan(uav: UavSpec, index: int, comms: CommsSection) -> Any:
    """Paper 001's information planner as UAV ``index``'s guidance (:class:`InfoPlanSpec`; the radar, base station
    and radio are the world's: ``worlds.checks`` makes sure they exist)."""
    from autonomy.guidance.infoplan.config import InfoPlannerConfig
    from autonomy.guidance.infoplan.guidance import InfoPlannerGuidance

    g = uav.autonomy.guidance
    plan = g.infoplan if g.infoplan is not None else InfoPlanSpec()
    radar = next(s for s in uav.sensors if isinstance(s, RadarSpec))
    if comms.base_station is None:
        raise ValueError("guidance infoplan needs comms.base_station")
    cfg = InfoPlannerConfig(base_p_W=tuple(comms.base_station[:2]), dt=1.0 / uav.autonomy.rate_hz,
                            horizon=plan.horizon, speed=g.speed, max_heading_rate=math.radians(
                                plan.max_heading_rate_deg_s), n_heading_rates=plan.heading_rates,
                            sigma_range=radar.sigma_range, sigma_bearing=math.radians(radar.sigma_azimuth_deg),
                            target_accel_std=plan.target_accel_std, channel=channel_config(comms),
                            d_safe=plan.d_safe, objective=plan.objective, routing=plan.routing or comms.routing,
                            criterion=plan.criterion, search=plan.search, sweeps=plan.sweeps, altitude=g.altitude,
                            **g.params)
    return InfoPlannerGuidance(cfg, uav_id=index)


def channel_config(comms: CommsSection) -> Any:
    """The :class:`~autonomy.sensing.channel.ChannelConfig` of the ``comms`` section (fields left out take the
    channel's defaults): the radio's link model, also for planners that weigh links by it."""
    from autonomy.sensing.channel import ChannelConfig, LinkOutage

    given = comms.model_dump(exclude_none=True, exclude={"model", "base_station", "routing", "outages", "links"})
    outages = tuple(LinkOutage(node_a=o.link[0], node_b=o.link[1], start_s=o.start_s, end_s=o.end_s)
                    for o in comms.outages)
    links = None if comms.links is None else tuple(tuple(pair) for pair in comms.links)
    return ChannelConfig(**given, outages=outages, links=links)


def build_channel(world: World, physics_hz: int, rng: Any, scene: Any) -> Any:
    """The radio channel of the ``comms`` section, or None for perfect communication."""
    if world.comms.model == "perfect":
        return None
    from autonomy.sensing.channel import Channel

    return Channel(channel_config(world.comms), physics_hz, rng, scene)


def fleet_options(world: World) -> Any:
    """Quadrotor fleet options from the environment section (all UAVs share one outer-loop rate)."""
    from vehicles.quadrotor.fleet import FleetOptions
    from vehicles.quadrotor.wind import WindConfig

    env = world.environment
    wind = None
    if env.wind is not None:
        turb = env.wind.turbulence
        sigma = (0.0, 0.0, 0.0) if turb is None else (turb.sigma, turb.sigma, turb.sigma / 2)
        length = (200.0, 200.0, 50.0) if turb is None else (turb.length_scale,) * 3
        airspeed = max(1.0, math.hypot(*env.wind.mean_W[:2]))
        wind = WindConfig(mean_W=tuple(env.wind.mean_W), sigma=sigma, length_scale=length, airspeed=airspeed)
    # one outer-loop rate for the fleet: worlds.checks refuses a world whose UAVs differ
    return FleetOptions(wind=wind, downwash=env.downwash, ground_effect=env.ground_effect,
                        outer_loop_hz=world.uavs[0].outer_loop_hz if world.uavs else FleetOptions().outer_loop_hz)


def build_car_fleet(world: World, network: Any, client: int, physics_hz: int, rng: Any) -> Any:
    """The ground vehicles, their drivers, routes and dynamics (physics multibody or kinematic box)."""
    from vehicles.car.driver_config import DriverConfig
    from vehicles.car.fleet import CarFleet
    from vehicles.car.params import load_car
    from vehicles.car.route import Route

    params, drivers, routes = [], [], []
    for g in world.ground_vehicles:
        params.append(load_car(g.type))
        drivers.append(DriverConfig(**g.driver.model_dump()))  # the schema's model, field by field
        where = dict(start_s=g.route.start_s, lane=g.route.lane)
        if g.route.roads is not None:
            routes.append(Route(roads=tuple(g.route.roads), **where))
        else:
            routes.append(Route(random_walk=True, start_road=g.route.random_walk_from, **where))
    return CarFleet(client, params, drivers, routes, network, physics_hz, rng,
                    dynamics=[g.dynamics for g in world.ground_vehicles])
