"""Building a run: :func:`prepare` (geometry and each UAV's autonomy, before the physics starts) and
:func:`build_assembly` (the PyBullet scene, the fleets, the radio, the team protocols, the record)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import pybullet as p
from pydantic import BaseModel

from autonomy.agent import Agent, TargetEstimator
from autonomy.estimation.setmem.tracker import SetMembershipTracker
from autonomy.fusion.base_station import InformationReporter
from autonomy.fusion.hcmci_team import HcmciConfig
from autonomy.fusion.track_fusion import TrackFusion, TrackFusionConfig
from autonomy.sensing.camera import CAR_RGBA
from autonomy.team.base import TeamProtocol
from autonomy.team.base_station import BaseStationTeam
from autonomy.team.hcmci import HcmciConsensusTeam, is_information_tracker
from autonomy.team.independent import IndependentTeam, MeasurementSharingTeam, TrackFusionTeam
from autonomy.team.set_fusion import SetFusionTeam
from simulator.clock import Clock
from simulator.comms import Comms
from simulator.decoys import StaticDecoys, build_decoys
from autonomy.estimation.tracking.gated import TargetGatedEstimator
from autonomy.estimation.tracking.multi import MultiTargetTracker
from simulator.builders.multi_target import multi_target
from simulator.registry import build_estimator, build_guidance, build_sensor
from simulator.record import RunRecorder
from simulator.recording import PybulletContacts, Recording
from simulator.scene import Scene, SceneConfig
from simulator.scene_query import PybulletSceneQuery
from simulator.search_team import SearchTeamRun
from worlds.traffic import TrafficPlacementError, with_traffic
from simulator.seeding import RunSeeds
from simulator.slots import AgentSlot, SensorSlot
from simulator.tick import Assembly
from simulator.truth import Truth, car_attributes
from worlds.build import WorldGeometry, build_geometry
from worlds.errors import WorldError, WorldIssue
from worlds.loader import LoadedWorld
from worlds.schema import World

if TYPE_CHECKING:
    from simulator.engine import RunOptions

__all__ = ["Prepared", "build_assembly", "build_teams", "prepare", "team_comms"]


@dataclass
class Prepared:
    """Everything built before the physics starts: geometry and the autonomy of each UAV (fails fast on bad input)."""

    loaded: LoadedWorld
    clock: Clock
    geometry: WorldGeometry
    sensors: list[SensorSlot]
    agents: list[AgentSlot]
    hcmci: HcmciConfig | None = None


def prepare(loaded: LoadedWorld, clock: Clock, seeds: RunSeeds, options: RunOptions) -> Prepared:
    """Build geometry, sensors, estimators and guidance; raises :class:`WorldError` naming the entry on a bad one."""
    from vehicles.quadrotor.airframes import load_airframe

    geometry = build_geometry(loaded.world, loaded.path, seeds.generator("world/town"))
    loaded = _add_traffic(loaded, geometry, seeds)
    world = loaded.world
    issues = []
    for i, u in enumerate(world.uavs):
        try:
            load_airframe(u.airframe)
        except (KeyError, ValueError) as exc:
            issues.append(WorldIssue(f"uavs[{i}].airframe", u.airframe, f"a known airframe ({exc})"))
    if issues:
        raise WorldError(str(loaded.path), issues)
    sensors, agents, hcmci = [], [], None
    for i, u in enumerate(world.uavs):
        for j, spec in enumerate(u.sensors):
            name = spec.id or f"{u.id}/{spec.type}{j}"
            where = f"uavs[{i}].sensors[{j}]"
            sensor = _checked(loaded, where, spec, lambda: build_sensor(spec, name, geometry.buildings))
            sensors.append(SensorSlot(uav=i, sensor=sensor, name=name, divisor=clock.divisor(spec.rate_hz, where),
                                      rng=seeds.generator(f"sensor/{u.id}/{j}")))
        if options.estimator_factory is not None:
            estimator = options.estimator_factory(i, u)
        else:
            estimator = _checked(loaded, f"uavs[{i}].autonomy.estimator", u.autonomy.estimator,
                                 lambda: build_estimator(u, i, geometry.network, geometry.buildings))
        estimator = _checked(loaded, f"uavs[{i}].autonomy.estimator.tracking", u.autonomy.estimator.tracking,
                             lambda: multi_target(estimator, world, u, geometry.network))
        if options.guidance_factory is not None:
            guidance = options.guidance_factory(i, u)
        else:
            guidance = _checked(loaded, f"uavs[{i}].autonomy.guidance", u.autonomy.guidance,
                                lambda: build_guidance(u, i, len(world.uavs), geometry.buildings, world.comms,
                                                       estimator))
        fusion, f = None, u.autonomy.fusion
        if f.method == "hcmci":
            _check_information_tracker(loaded, i, estimator, f.method)
            hcmci = HcmciConfig(rounds=f.rounds, gain=f.b)  # one config for all: worlds.checks
        elif f.method == "base_station":
            _check_information_tracker(loaded, i, estimator, f.method)
            estimator = InformationReporter(estimator)
        elif f.method not in ("none", "measurements", "sets"):
            fusion = TrackFusion(TrackFusionConfig(method=f.method, max_age_s=f.max_age_s, q=f.q,
                                                   switch_margin=f.switch_margin))
        agents.append(AgentSlot(uav=i, agent=Agent(u.id, estimator, guidance, fusion=fusion),
                                divisor=clock.divisor(u.autonomy.rate_hz, f"uavs[{i}].autonomy.rate_hz")))
    return Prepared(loaded=loaded, clock=clock, geometry=geometry, sensors=sensors, agents=agents, hcmci=hcmci)


def _add_traffic(loaded: LoadedWorld, geometry: WorldGeometry, seeds: RunSeeds) -> LoadedWorld:
    """The world with its generated background traffic (``traffic.cars``) among its ground vehicles."""
    spec = loaded.world.traffic
    if spec.cars == 0:
        return loaded
    if geometry.network is None:
        raise WorldError(str(loaded.path), [WorldIssue("traffic.cars", spec.cars, "0 in a world without roads "
                                                       "(give roads: streets, osm or town)")])
    if spec.engine == "sumo":
        from vehicles.sumo import INSTALL_HINT, sumo_available

        if not sumo_available():
            raise WorldError(str(loaded.path), [WorldIssue("traffic.engine", spec.engine, "an installed engine: "
                                                           f"SUMO is not installed ({INSTALL_HINT})")])
    try:
        world = with_traffic(loaded.world, geometry.network, seeds.generator("world/traffic"))
    except TrafficPlacementError as exc:
        raise WorldError(str(loaded.path), [WorldIssue("traffic.cars", spec.cars, f"a number of cars that fits "
                                                       f"({exc})")]) from None
    return replace(loaded, world=world)


def build_teams(methods: list[str], agents: list[AgentSlot], hcmci: HcmciConfig | None) -> list[TeamProtocol]:
    """The team protocols of a world from each UAV's fusion method (``methods[k]`` for ``agents[k]``), in the order
    they step: HCMCI consensus, set fusion (every set-membership tracker), then the protocols without team-level
    work (independent, track fusion, measurement sharing, base-station reporting)."""
    groups: dict[str, list[AgentSlot]] = {}
    for a, method in zip(agents, methods, strict=True):
        if isinstance(a.agent.estimator, SetMembershipTracker):
            key = "sets"
        elif method in ("convex", "covariance_intersection"):
            key = "track_fusion"
        elif method in ("hcmci", "measurements", "base_station"):
            key = method
        else:  # none (and sets on another estimator, which worlds.checks refuses)
            key = "none"
        groups.setdefault(key, []).append(a)
    teams: list[TeamProtocol] = []
    if "hcmci" in groups:
        teams.append(HcmciConsensusTeam([a.uav for a in groups["hcmci"]], hcmci or HcmciConfig()))
    if "sets" in groups:
        teams.append(SetFusionTeam({a.uav: a.agent.estimator for a in groups["sets"]},
                                   fusing={a.uav for a, m in zip(agents, methods, strict=True) if m == "sets"}))
    simple: dict[str, Callable[[list[int]], TeamProtocol]] = {
        "none": IndependentTeam, "track_fusion": TrackFusionTeam, "measurements": MeasurementSharingTeam}
    for key, make in simple.items():
        if key in groups:
            teams.append(make([a.uav for a in groups[key]]))
    if "base_station" in groups:
        teams.append(BaseStationTeam({a.uav: a.agent.estimator for a in groups["base_station"]}))
    return teams


def team_comms(teams: list[TeamProtocol], agents: list[AgentSlot], **parts: Any) -> Comms:
    """The run's :class:`~simulator.comms.Comms` (``parts``: its other arguments) for ``teams``: the members of the
    protocols that take detections receive them, and estimates are shared when a protocol shares them."""
    takers = {u for team in teams if team.takes_detections for u in team.members}
    return Comms(receivers={a.uav: a.agent for a in agents if a.uav in takers},
                 share_estimates=any(team.shares_estimates and team.members for team in teams), **parts)


def _check_information_tracker(loaded: LoadedWorld, i: int, estimator: TargetEstimator, method: str) -> None:
    """HCMCI and base-station fusion need the built-in tracker with the information filter (also when an estimator was
    passed in code)."""
    if method == "hcmci" and isinstance(estimator, MultiTargetTracker) and estimator.config.filter == "scif":
        return  # HCMCI on each node's target track, between nodes whose target tracks are one car
    if isinstance(estimator, MultiTargetTracker | TargetGatedEstimator):
        raise WorldError(str(loaded.path), [WorldIssue(
            f"uavs[{i}].autonomy.estimator.tracking.mode", "multi",
            f"single: fusion method {method} fuses one track's information"
            + (" (the built-in tracker with the scif filter runs HCMCI among traffic)" if method == "hcmci" else "")
            + "; a world with traffic tracks every car by default")])
    if not is_information_tracker(estimator):
        raise WorldError(str(loaded.path), [WorldIssue(
            f"uavs[{i}].autonomy.estimator", type(estimator).__name__,
            f"the built-in tracker with the scif filter: fusion method {method} fuses its information")])


def _checked(loaded: LoadedWorld, where: str, spec: Any, build: Callable[[], Any]) -> Any:
    try:
        return build()
    except WorldError:
        raise
    except (ValueError, TypeError, KeyError, ImportError) as exc:
        value = spec.model_dump(exclude_defaults=True) if isinstance(spec, BaseModel) else spec
        raise WorldError(str(loaded.path), [WorldIssue(where, value, f"a valid configuration ({exc})")]) from None


def build_assembly(prep: Prepared, seeds: RunSeeds, recorder: RunRecorder) -> Assembly:
    """Start PyBullet and build the scene and the fleets of a prepared world."""
    from simulator.base_station import BaseStationLink, build_base_station
    from simulator.factories import build_car_fleet, build_channel, fleet_options
    from vehicles.quadrotor.airframes import load_airframe
    from vehicles.quadrotor.fleet import QuadrotorFleet

    world, clock, geometry = prep.loaded.world, prep.clock, prep.geometry
    scene = Scene.create(SceneConfig(physics_hz=clock.physics_hz, gravity=world.environment.gravity,
                                     ground_size=tuple(world.terrain.size)))
    scene.add_buildings(geometry.buildings)
    if geometry.road_mesh is not None:
        scene.add_road_surface(geometry.road_mesh)

    quads = None
    if world.uavs:
        airframes = [load_airframe(u.airframe) for u in world.uavs]
        p0 = np.array([u.initial.position for u in world.uavs], dtype=float)
        yaw0 = np.radians([u.initial.yaw_deg for u in world.uavs])
        quads = QuadrotorFleet(scene.client, airframes, p0, yaw0, clock.physics_hz, fleet_options(world),
                               seeds.generator("vehicles/quadrotors"))
    cars, car_kinds = None, ()
    if world.ground_vehicles:
        cars = build_car_fleet(world, geometry.network, scene.client, clock.physics_hz,
                               seeds.generator("vehicles/cars"), geometry.signals)
        car_kinds = tuple("decoy" if g.role == "decoy" else "car" for g in world.ground_vehicles)
        for body in cars.body_ids:  # paint the bodies in the colour the camera detector looks for
            p.changeVisualShape(int(body), -1, rgbaColor=CAR_RGBA, physicsClientId=scene.client)

    car_ids = [g.id for g in world.ground_vehicles]
    uav_ids = [u.id for u in world.uavs]
    target_ids = world.target_ids()
    decoys = build_decoys(world.decoys, scene, CAR_RGBA)
    query = PybulletSceneQuery(scene.client, scene.occluders)
    outages = [(o.link[0], o.link[1], clock.ticks(o.start_s), clock.ticks(o.end_s)) for o in world.comms.outages]
    channel = build_channel(world, clock.physics_hz, seeds.generator("comms/channel"), query)
    truth = Truth(quads, cars, car_kinds, decoys, car_attributes([g.type for g in world.ground_vehicles],
                                                                 [g.colour for g in world.ground_vehicles]))
    _hand_off(world, prep.agents, cars, car_ids, seeds)
    teams = build_teams([u.autonomy.fusion.method for u in world.uavs], prep.agents, prep.hcmci)
    comms = team_comms(teams, prep.agents, uav_ids=uav_ids, quads=quads, channel=channel, comms=world.comms,
                       outages=outages, scene_query=query)
    for team in teams:  # the engine-side parts of the protocols: the base station, the search record
        if isinstance(team, BaseStationTeam):
            station = build_base_station(world, prep.agents, channel, recorder)
            team.base = None if station is None else BaseStationLink(station, comms.positions)
        elif isinstance(team, SetFusionTeam):
            team.observer = _search_record(team, truth, recorder, car_ids, target_ids, car_kinds, decoys)
    contacts = None if quads is None else PybulletContacts(scene, quads, cars, uav_ids, car_ids)
    if cars is not None and quads is not None:  # the kinematic cars' boxes near a UAV follow them every step
        cars.near_points = lambda: quads.live_state.p_W
    return Assembly(clock=clock, scene=scene, truth=truth, comms=comms,
                    recording=Recording(recorder, uav_ids, car_ids, contacts), teams=teams, scene_query=query,
                    uav_ids=uav_ids, car_ids=car_ids,
                    target_index=car_ids.index(target_ids[0]) if target_ids else None,
                    sensors=prep.sensors, agents=prep.agents, buildings=geometry.buildings, network=geometry.network,
                    world_spec=world, outages=outages, record_div=clock.divisor(world.sim.record_hz, "sim.record_hz"))


def _hand_off(world: World, agents: list[AgentSlot], cars: Any, car_ids: list[str], seeds: RunSeeds) -> None:
    """The cue that designates the (first) target to the team: its true start position plus a normal error of the
    target's ``cue.sigma_m`` per axis, one draw for the whole team, told to every estimator that takes a cue."""
    takers = [a for a in agents if callable(getattr(a.agent.estimator, "cue", None))]
    targets = world.designated()
    if not takers or not targets or cars is None or targets[0].id not in car_ids:
        return
    sigma = targets[0].cue.sigma_m
    p0 = np.asarray(cars.state.p_W[car_ids.index(targets[0].id)], dtype=float)[:2]
    cued = p0 + seeds.generator("targets/cue").normal(0.0, sigma, 2)
    for a in takers:
        a.agent.estimator.cue(0.0, cued, sigma)


def _search_record(team: SetFusionTeam, truth: Truth, recorder: RunRecorder, car_ids: list[str],
                   target_ids: list[str], car_kinds: tuple[str, ...], decoys: StaticDecoys | None) -> SearchTeamRun:
    """The record of the search team, judged on the target rows of the truth (the tracked vehicles) and its decoy
    rows (vehicles of role decoy, then the static decoys)."""
    n = len(car_ids)
    return SearchTeamRun(team=team, truth=truth, recorder=recorder,
                         target_rows=[car_ids.index(t) for t in target_ids],
                         decoy_rows=[k for k in range(n) if car_kinds[k] == "decoy"]
                         + list(range(n, n + (len(decoys) if decoys is not None else 0))))
