"""World-file sections → configured components: the radio channel, fleet options, the car fleet.

The sensors, estimators and guidance laws are built through the registry of builders (:mod:`simulator.registry`).
"""

from __future__ import annotations

import math
from typing import Any

from worlds.schema import CommsSection, World

__all__ = [
    "build_car_fleet",
    "build_channel",
    "channel_config",
    "fleet_options",
    "sumo_net_config",
]

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


def build_car_fleet(world: World, network: Any, client: int, physics_hz: int, rng: Any,
                    signals: tuple[str, ...] = ()) -> Any:
    """The ground vehicles, their drivers, routes and dynamics (physics multibody or kinematic box), and SUMO's
    slots when the world's traffic engine is SUMO (the last ``traffic.cars`` entries, added by
    :func:`worlds.traffic.with_traffic`), with traffic lights at the junctions ``signals`` by the section's ``tls``
    (:func:`sumo_net_config`)."""
    from vehicles.car.driver_config import DriverConfig
    from vehicles.car.fleet import CarFleet
    from vehicles.car.params import load_car
    from vehicles.car.route import Route

    listed = world.ground_vehicles
    sources = []
    if world.traffic.engine == "sumo" and world.traffic.cars:
        listed = listed[:-world.traffic.cars]
        sources.append(_sumo(world, network, client, physics_hz, rng.spawn(1)[0], signals))
    params, drivers, routes = [], [], []
    for g in listed:
        params.append(load_car(g.type))
        drivers.append(DriverConfig(**g.driver.model_dump()))  # the schema's model, field by field
        where = dict(start_s=g.route.start_s, lane=g.route.lane)
        if g.route.roads is not None:
            routes.append(Route(roads=tuple(g.route.roads), **where))
        else:
            routes.append(Route(random_walk=True, start_road=g.route.random_walk_from, **where))
    try:
        return CarFleet(client, params, drivers, routes, network, physics_hz, rng,
                        dynamics=[g.dynamics for g in listed], sources=sources)
    except BaseException:
        for src in sources:
            src.close()
        raise


def _sumo(world: World, network: Any, client: int, physics_hz: int, rng: Any, signals: tuple[str, ...]) -> Any:
    """SUMO co-simulation of the world's traffic section, its network cached under the skytrack cache."""
    from vehicles.sumo import make_sumo_traffic
    from vehicles.sumo.demand import DemandConfig, Flow
    from worlds.map_cache import cache_root

    spec = world.traffic
    flows = tuple(Flow(origin=f.origin, destination=f.destination, per_hour=f.per_hour, begin_s=f.begin_s,
                       end_s=math.inf if f.end_s is None else f.end_s, via=tuple(f.via)) for f in spec.flows)
    return make_sumo_traffic(network, n_vehicles=spec.sumo_trips, n_slots=spec.cars, rate_hz=spec.rate_hz,
                             physics_hz=physics_hz, client_id=client, rng=rng, work_dir=cache_root() / "sumo",
                             car=spec.types[0], net=sumo_net_config(spec.tls, (*signals, *(
                                 s for s in spec.signals if s not in signals))),
                             demand=DemandConfig(flows=flows))


def sumo_net_config(tls: str, signals: tuple[str, ...]) -> Any:
    """The SUMO network options of a traffic section's ``tls`` with the junctions the map's signals control:
    ``map`` lights those only, ``guess`` those and netconvert's guess elsewhere, ``none`` none, ``auto`` is ``map``
    when there are any and ``guess`` otherwise."""
    from vehicles.sumo.network import NetConfig

    if tls == "auto":
        tls = "map" if signals else "guess"
    if tls not in ("map", "guess", "none"):
        raise ValueError(f"traffic.tls must be 'auto', 'map', 'guess' or 'none', got {tls!r}")
    return NetConfig(tls="guess" if tls == "guess" else "none", signals=() if tls == "none" else tuple(signals))
