"""Whole-world checks the per-section schema cannot make: rates that divide the physics rate (the hidden ones too:
the car driver's), periods of whole ticks, UAVs starting inside the terrain, unique ids, references between sections.

Every rate is judged by :func:`worlds.rates.rate_divisor`, the rule the clock and the vehicles' fleets apply too.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable

from worlds.catalog import AIRFRAMES
from worlds.errors import WorldIssue
from worlds.rates import divisors_text, rate_divisor, whole_ticks
from worlds.schema import InfoPlanSpec, World

__all__ = ["check_world", "register_component_check"]

MAX_START_ALTITUDE = 5000.0
"""m: highest start of a UAV; the airframes' rotor and drag data are sea-level figures."""

START_CLEARANCE = 0.5
"""m: the least room between a UAV's start and a building (the survey_quad's collision box reaches 0.33 m from its
centre, the crazyflie's less); closer, the body would start inside the building's collision shape."""

TRACKER_TARGET_HEIGHT = 0.0
"""m: the tracker's default ``target_height`` (``autonomy.estimation.tracker.TrackerConfig``; not imported here, where
worlds are checked without building anything)."""


ComponentCheck = Callable[[World], list[WorldIssue]]
_COMPONENT_CHECKS: list[ComponentCheck] = []


def register_component_check(check: ComponentCheck) -> None:
    """Add a check that :func:`check_world` runs last: the rules of a component's own config that the schema cannot
    state without importing it (a radar's ``pfa < pd_ref`` with the radar's defaults). The package that builds the
    components registers it (``simulator.registry``), so the loader refuses what the build would refuse."""
    if check not in _COMPONENT_CHECKS:
        _COMPONENT_CHECKS.append(check)


def check_world(world: World) -> list[WorldIssue]:
    """Return every cross-field problem of ``world`` (empty when it is consistent)."""
    issues = _world_issues(world)
    if not issues:  # the components' own rules only on a consistent world
        for check in _COMPONENT_CHECKS:
            issues.extend(check(world))
    return issues


def _world_issues(world: World) -> list[WorldIssue]:
    issues: list[WorldIssue] = []
    hz = world.sim.physics_hz

    def rate(path: str, value: float, note: str = "") -> None:
        if rate_divisor(value, hz) is None:
            issues.append(WorldIssue(path, value, f"a rate in Hz that divides sim.physics_hz={hz} into whole ticks "
                                                  f"(e.g. {divisors_text(hz)}){note}"))

    rate("sim.record_hz", world.sim.record_hz)
    if round(world.sim.flush_every_s * hz) < 1:
        issues.append(WorldIssue("sim.flush_every_s", world.sim.flush_every_s,
                                 f"at least one physics tick, {1 / hz:.6g} s at sim.physics_hz={hz}: the record is "
                                 "flushed every round(flush_every_s * physics_hz) ticks"))
    for i, g in enumerate(world.ground_vehicles):
        given = "rate_hz" in g.driver.model_fields_set
        rate(f"ground_vehicles[{i}].driver.rate_hz", g.driver.rate_hz,
             "" if given else f"; the driver's default is {g.driver.rate_hz} Hz: give ground_vehicles[{i}].driver."
                              "rate_hz one that divides the physics rate")
    if world.traffic.cars:
        rate("traffic.rate_hz", world.traffic.rate_hz)
    if world.comms.latency_s is not None and whole_ticks(world.comms.latency_s, hz) is None:
        issues.append(WorldIssue("comms.latency_s", world.comms.latency_s,
                                 f"a whole number of physics ticks (multiples of {1 / hz:.6g} s at "
                                 f"sim.physics_hz={hz})"))
    # render.fps needs no divisor check: the video is replayed from the record, interpolated to each frame's time
    if world.uavs and world.render.uav >= len(world.uavs):
        n = len(world.uavs)
        issues.append(WorldIssue("render.uav", world.render.uav,
                                 f"the index of one of the world's {n} UAVs (0 .. {n - 1})"))
    issues.extend(_start_issues(world))
    for i, uav in enumerate(world.uavs):
        rate(f"uavs[{i}].outer_loop_hz", uav.outer_loop_hz)
        if uav.outer_loop_hz != world.uavs[0].outer_loop_hz:
            issues.append(WorldIssue(f"uavs[{i}].outer_loop_hz", uav.outer_loop_hz,
                                     f"{world.uavs[0].outer_loop_hz}, the outer_loop_hz of uavs[0]: the UAVs' "
                                     "outer loops run in one fleet at one rate"))
        rate(f"uavs[{i}].autonomy.rate_hz", uav.autonomy.rate_hz)
        for j, sensor in enumerate(uav.sensors):
            rate(f"uavs[{i}].sensors[{j}].rate_hz", sensor.rate_hz)

    for section, ids in (("uavs", [u.id for u in world.uavs]),
                         ("ground_vehicles", [g.id for g in world.ground_vehicles]),
                         ("decoys", [d.id for d in world.decoys])):
        for name, count in Counter(ids).items():
            if count > 1:
                issues.append(WorldIssue(f"{section}[{ids.index(name)}].id", name, "ids unique within their section"))

    vehicle_ids = {g.id for g in world.ground_vehicles}
    for k, target in enumerate(world.targets or []):
        if target.id not in vehicle_ids:
            issues.append(WorldIssue(f"targets[{k}].id", target.id,
                                     f"the id of a ground vehicle ({sorted(vehicle_ids) or 'none defined'})"))

    has_roads = bool(world.roads.streets or world.roads.osm or world.roads.town)
    for i, uav in enumerate(world.uavs):
        est = uav.autonomy.estimator
        if est.type in ("maekf", "ecukf") and not has_roads:
            issues.append(WorldIssue(f"uavs[{i}].autonomy.estimator.type", est.type,
                                     "an estimator without a road map (ekf, ukf, ...): this world has no roads"))
        if est.road and est.type not in ("maekf", "ecukf"):
            issues.append(WorldIssue(f"uavs[{i}].autonomy.estimator.road", est.road,
                                     "no 'road' settings unless the type is maekf or ecukf"))
    for i, g in enumerate(world.ground_vehicles):
        if not has_roads:
            issues.append(WorldIssue(f"ground_vehicles[{i}].route", g.route.model_dump(exclude_none=True),
                                     "a road network in 'roads' for the vehicle to drive on"))
    issues.extend(_road_issues(world))
    issues.extend(_hcmci_issues(world))
    issues.extend(_formation_imm_issues(world))
    issues.extend(_search_issues(world))
    issues.extend(_relay_issues(world))
    uav_ids = {u.id for u in world.uavs} | {"base"}
    for i, o in enumerate(world.comms.outages):
        if o.end_s <= o.start_s:
            issues.append(WorldIssue(f"comms.outages[{i}].end_s", o.end_s, f"a time after start_s={o.start_s}"))
        for k, node in enumerate(o.link):
            if node not in uav_ids:
                issues.append(WorldIssue(f"comms.outages[{i}].link[{k}]", node,
                                         f"a UAV id or 'base' ({sorted(uav_ids)})"))
    link_nodes = uav_ids if world.comms.base_station is not None else uav_ids - {"base"}
    for i, pair in enumerate(world.comms.links or []):
        for k, node in enumerate(pair):
            if node not in link_nodes:
                issues.append(WorldIssue(f"comms.links[{i}][{k}]", node,
                                         f"a UAV id{' or base' if 'base' in link_nodes else ''} "
                                         f"({sorted(link_nodes)})"))
        if pair[0] == pair[1]:
            issues.append(WorldIssue(f"comms.links[{i}]", list(pair), "two different UAV ids"))
    return issues


def _start_issues(world: World) -> list[WorldIssue]:
    """Each UAV starts as a known airframe above the ground, no higher than :data:`MAX_START_ALTITUDE` (the schema
    keeps x and y within 50 km of the origin). ``terrain.size`` is the visual extent of the ground: its collision
    plane is infinite, and shipped worlds fly beyond the visual edge, so it bounds no start."""
    issues: list[WorldIssue] = []
    for i, uav in enumerate(world.uavs):
        if uav.airframe not in AIRFRAMES:
            issues.append(WorldIssue(f"uavs[{i}].airframe", uav.airframe,
                                     f"one of the airframes of vehicles/airframes ({', '.join(AIRFRAMES)})"))
        z = uav.initial.position[2]
        if not 0.0 < z <= MAX_START_ALTITUDE:
            issues.append(WorldIssue(f"uavs[{i}].initial.position", list(uav.initial.position),
                                     f"a start above the ground: 0 < z <= {MAX_START_ALTITUDE:g} m"))
            continue
        k = _building_at(world, uav.initial.position)
        if k is not None:
            b = world.buildings[k]
            issues.append(WorldIssue(f"uavs[{i}].initial.position", list(uav.initial.position),
                                     f"a start outside every building, at least {START_CLEARANCE:g} m from its walls "
                                     f"and roof: buildings[{k}] (center {list(b.center)}, size {list(b.size)}, "
                                     f"yaw_deg {b.yaw_deg:g}) holds it"))
    return issues


def _building_at(world: World, position: tuple[float, float, float]) -> int | None:
    """Index of the first of ``world.buildings`` (cuboids) whose shape grown by :data:`START_CLEARANCE` holds
    ``position``, or None. The buildings of a ``town`` or an ``osm`` map are generated when the world is built and
    checked then (``worlds.build``)."""
    x, y, z = position
    for k, b in enumerate(world.buildings):
        length, width, height = b.size
        if z > height + START_CLEARANCE:
            continue
        yaw = math.radians(b.yaw_deg)
        dx, dy = x - b.center[0], y - b.center[1]
        along = dx * math.cos(yaw) + dy * math.sin(yaw)  # in the building's frame (length along yaw)
        across = -dx * math.sin(yaw) + dy * math.cos(yaw)
        if abs(along) <= length / 2 + START_CLEARANCE and abs(across) <= width / 2 + START_CLEARANCE:
            return k
    return None


def _road_issues(world: World) -> list[WorldIssue]:
    """A network given as ``streets`` builds (no street of zero length, no vertex repeated ...) and every route names
    roads of the network (street ``s`` gives roads ``s.f`` and, two-way, ``s.r``; a procedural town's ids follow
    from its grid) and, on streets, starts within its first road. A map extract's routes are checked when its
    geometry is built (:func:`worlds.build.build_geometry`), still before the physics starts."""
    roads = world.roads
    lengths: dict[str, float] = {}
    if roads.streets:
        from worlds.roads.network import RoadNetwork

        spec = {"nodes": {k: list(v) for k, v in roads.nodes.items()},
                "streets": [s.model_dump() for s in roads.streets]}
        try:
            network = RoadNetwork.from_spec(spec)
        except ValueError as exc:
            return [WorldIssue("roads.streets", [s.id for s in roads.streets], f"a usable road network ({exc})")]
        road_ids = list(network.roads)
        lengths = {rid: road.length for rid, road in network.roads.items()}
    elif roads.town is not None:
        from worlds.town import TownConfig, town_road_ids

        params = {k: tuple(v) if isinstance(v, list) else v for k, v in (roads.town.model_extra or {}).items()}
        road_ids = town_road_ids(TownConfig(**params))  # the schema has checked the town's settings
    else:
        return []
    known = set(road_ids)
    issues = []
    for i, g in enumerate(world.ground_vehicles):
        ids = g.route.roads or [g.route.random_walk_from]
        for k, rid in enumerate(ids):
            if rid not in known:
                key = f"ground_vehicles[{i}].route." + (f"roads[{k}]" if g.route.roads else "random_walk_from")
                sample = ", ".join(road_ids[:6])
                issues.append(WorldIssue(key, rid, f"a road id of the network (e.g. {sample}; a street 's' gives "
                                                   "roads 's.f' and 's.r')"))
        first = ids[0]
        if first in lengths and g.route.start_s > lengths[first]:
            issues.append(WorldIssue(f"ground_vehicles[{i}].route.start_s", g.route.start_s,
                                     f"a start on the first road: at most its length, {lengths[first]:.1f} m of "
                                     f"{first!r}"))
    return issues


def _hcmci_issues(world: World) -> list[WorldIssue]:
    """HCMCI fuses information filters (``scif``), and the team runs one consensus: one ``rounds`` and ``b``, and one
    state to average — the same motion model (``cv`` has 4 states, ``singer`` 6) on the same target plane
    (``params.target_height``: the nodes' measurement models must place the one target at one height)."""
    issues: list[WorldIssue] = []
    first = None
    for i, uav in enumerate(world.uavs):
        fusion = uav.autonomy.fusion
        if fusion.method != "hcmci":
            continue
        est = uav.autonomy.estimator
        if est.type != "scif":
            issues.append(WorldIssue(f"uavs[{i}].autonomy.estimator.type", est.type,
                                     "scif: fusion method hcmci fuses square-root information filters"))
        height = est.params.get("target_height", TRACKER_TARGET_HEIGHT)
        if first is None:
            first = (i, fusion.rounds, fusion.b, est.model, height)
            continue
        k = first[0]
        if (fusion.rounds, fusion.b) != first[1:3]:
            issues.append(WorldIssue(f"uavs[{i}].autonomy.fusion", {"rounds": fusion.rounds, "b": fusion.b},
                                     f"the rounds and b of uavs[{k}] (rounds={first[1]}, b={first[2]!r}): "
                                     "the hcmci team runs one consensus"))
        if est.model != first[3]:
            issues.append(WorldIssue(f"uavs[{i}].autonomy.estimator.model", est.model,
                                     f"{first[3]!r}, the estimator model of uavs[{k}]: the hcmci team averages one "
                                     "state layout (cv: 4 states, singer: 6)"))
        if height != first[4]:
            issues.append(WorldIssue(f"uavs[{i}].autonomy.estimator.params.target_height", height,
                                     f"{first[4]!r}, the target height of uavs[{k}]: the hcmci team tracks one "
                                     "target on one plane"))
    return issues


SHARED_MEASUREMENT_ESTIMATORS = ("ekf", "ukf", "ckf", "imm")
"""Estimators that stack the teammates' shared detections with their own (the built-in single-target tracker)."""


def _formation_imm_issues(world: World) -> list[WorldIssue]:
    """Paper 003's pieces: the ``imm`` estimator (model ``cv`` with its ``cv_ct`` modes; its ``imm`` settings only with
    it; bearings alone cannot start its track without the teammates' bearings), ``measurements`` fusion (a tracker
    that stacks them), and ``formation`` guidance (a team of every UAV, one range per UAV, a bearing σ to weigh the
    geometry with)."""
    issues: list[WorldIssue] = []
    n = len(world.uavs)
    for i, uav in enumerate(world.uavs):
        where = f"uavs[{i}].autonomy"
        est, fusion, g = uav.autonomy.estimator, uav.autonomy.fusion, uav.autonomy.guidance
        if est.imm is not None and est.type != "imm":
            issues.append(WorldIssue(f"{where}.estimator.imm", est.imm.model_dump(),
                                     f"no 'imm' settings unless the type is imm (type is {est.type!r})"))
        if est.type == "imm" and (est.imm is None or est.imm.modes == "cv_ct") and est.model != "cv":
            issues.append(WorldIssue(f"{where}.estimator.model", est.model,
                                     "'cv': the cv_ct imm's modes (CV and coordinated turns) share the CV state "
                                     "layout (imm: {modes: move_stop} runs on cv or singer)"))
        bearing_only = bool(uav.sensors) and all(s.type in ("bearing", "camera") for s in uav.sensors)
        if est.type == "imm" and bearing_only and fusion.method != "measurements":
            issues.append(WorldIssue(f"{where}.fusion.method", fusion.method,
                                     "'measurements': this UAV's imm sees bearings only, and one bearing line cannot "
                                     "start a track; the teammates' bearings can"))
        if fusion.method == "measurements" and est.type not in SHARED_MEASUREMENT_ESTIMATORS:
            issues.append(WorldIssue(f"{where}.estimator.type", est.type,
                                     f"one of {', '.join(SHARED_MEASUREMENT_ESTIMATORS)}: fusion method measurements "
                                     "needs the built-in tracker, which stacks the shared detections with its own"))
        if g.formation is not None and g.type != "formation":
            issues.append(WorldIssue(f"{where}.guidance.formation", g.formation.model_dump(),
                                     f"no 'formation' settings unless the type is formation (type is {g.type!r})"))
        if g.type != "formation":
            continue
        if n < 2:
            issues.append(WorldIssue(f"{where}.guidance.type", g.type, "formation guidance in a team of >= 2 UAVs "
                                                                       f"(this world has {n})"))
        form = g.formation
        if form is not None and form.ranges is not None and len(form.ranges) != n:
            issues.append(WorldIssue(f"{where}.guidance.formation.ranges", list(form.ranges),
                                     f"one range per UAV of the world ({n} values, m)"))
        if (form is None or form.sigma_bearing_deg is None) and not any(s.type == "bearing" for s in uav.sensors):
            issues.append(WorldIssue(f"{where}.guidance.formation.sigma_bearing_deg", None,
                                     "a bearing noise σ in degrees: this UAV has no bearing sensor to take it from"))
    return issues


def _search_issues(world: World) -> list[WorldIssue]:
    """Paper 004's pieces: the ``set_membership`` estimator (its ``set_membership`` block; a ``box`` sensor scanning at
    the agent's rate, so that each step corrects with one scan and the team fuses sets of one time; one search area,
    speed bound and rate for the whole team; a speed bound no street lets a car exceed), ``sets`` fusion and
    ``search`` guidance (both on that estimator)."""
    issues: list[WorldIssue] = []
    first = None
    for i, uav in enumerate(world.uavs):
        where = f"uavs[{i}].autonomy"
        est, fusion, g = uav.autonomy.estimator, uav.autonomy.fusion, uav.autonomy.guidance
        sets = est.type == "set_membership"
        if est.set_membership is not None and not sets:
            issues.append(WorldIssue(f"{where}.estimator.set_membership", est.set_membership.model_dump(),
                                     f"no 'set_membership' settings unless the type is set_membership (type is "
                                     f"{est.type!r})"))
        if g.search is not None and g.type != "search":
            issues.append(WorldIssue(f"{where}.guidance.search", g.search.model_dump(),
                                     f"no 'search' settings unless the type is search (type is {g.type!r})"))
        if not sets:
            for key, value, alternative in ((f"{where}.fusion.method", fusion.method, "sets"),
                                            (f"{where}.guidance.type", g.type, "search")):
                if value == alternative:
                    issues.append(WorldIssue(key, value, f"another choice, or estimator type set_membership: "
                                                         f"{value!r} works on that estimator's sets (the estimator "
                                                         f"type is {est.type!r})"))
            continue
        if fusion.method not in ("none", "sets"):
            issues.append(WorldIssue(f"{where}.fusion.method", fusion.method,
                                     "'sets' or 'none': the set_membership estimator shares sets, not a point "
                                     "estimate"))
        if est.set_membership is None:
            issues.append(WorldIssue(f"{where}.estimator.set_membership", None,
                                     "the search area and the targets' speed bound: {area: [x_min, y_min, x_max, "
                                     "y_max], max_target_speed: ...}"))
            continue
        boxes = [j for j, s in enumerate(uav.sensors) if s.type == "box"]
        if not boxes:
            issues.append(WorldIssue(f"uavs[{i}].sensors", [s.type for s in uav.sensors],
                                     "a box sensor: the set_membership estimator corrects with its observed "
                                     "regions and bounded-error detections"))
        for j in boxes:
            if uav.sensors[j].rate_hz != uav.autonomy.rate_hz:
                issues.append(WorldIssue(f"uavs[{i}].sensors[{j}].rate_hz", uav.sensors[j].rate_hz,
                                         f"the agent's rate_hz ({uav.autonomy.rate_hz:g}): the set_membership "
                                         "estimator corrects with one scan per step"))
        sm = est.set_membership
        key = (sm.area, sm.max_target_speed, uav.autonomy.rate_hz)
        if first is None:
            first = (i, key)
        elif key != first[1]:
            k = first[0]
            issues.append(WorldIssue(f"{where}.estimator.set_membership",
                                     {"area": list(sm.area), "max_target_speed": sm.max_target_speed,
                                      "rate_hz": uav.autonomy.rate_hz},
                                     f"the area, max_target_speed and agent rate_hz of uavs[{k}]: the team fuses "
                                     "sets of one area, one speed bound and one time"))
        if world.ground_vehicles and world.roads.streets:
            fastest = max(range(len(world.roads.streets)), key=lambda m: world.roads.streets[m].speed_limit)
            limit = world.roads.streets[fastest].speed_limit
            if sm.max_target_speed < limit:
                issues.append(WorldIssue(f"{where}.estimator.set_membership.max_target_speed", sm.max_target_speed,
                                         f"at least the fastest street's speed limit ({limit:g} m/s, "
                                         f"roads.streets[{fastest}]): the sets hold the targets only if none "
                                         "moves faster than the bound"))
    return issues


MOTION_PARAMS = ("q", "singer_alpha", "singer_sigma_a")
"""Tracker parameters of the motion model (``TrackerConfig``): the base station predicts with the UAVs' model."""


def _relay_issues(world: World) -> list[WorldIssue]:
    """Paper 001's pieces. Fusion method ``base_station``: the ``scif`` estimator (its scan information is what is
    sent), a base position and a radio to send over, and one motion model for the base to predict with (the fusing
    UAVs' ``model`` and motion parameters). Guidance ``infoplan``: its settings only with it; a radar for the noise;
    the base position; the radio's link model unless the objective ignores the routes (``routing: none``), and routes
    that are the radio's; every UAV of the world in the team with one planner configuration (each UAV plans the whole
    team, so they must agree)."""
    issues: list[WorldIssue] = []
    comms = world.comms

    def add(path: str, value: object, expected: str) -> None:
        if all(i.path != path for i in issues):
            issues.append(WorldIssue(path, value, expected))

    fusing = [i for i, u in enumerate(world.uavs) if u.autonomy.fusion.method == "base_station"]
    for i in fusing:
        est = world.uavs[i].autonomy.estimator
        if comms.base_station is None:
            add("comms.base_station", None, f"the base station's position [x, y, z] (m): uavs[{i}] fuses at the base "
                                            "station (fusion method base_station)")
        if comms.model == "perfect":
            add("comms.model", comms.model, f"a radio model ('rayleigh'): uavs[{i}] sends its scans' information to "
                                            "the base station over the radio's routes (fusion method base_station)")
        if est.type != "scif":
            add(f"uavs[{i}].autonomy.estimator.type", est.type,
                "scif: fusion method base_station sends the information of the scif filter's scans")
        first = world.uavs[fusing[0]].autonomy.estimator
        if est.model != first.model:
            add(f"uavs[{i}].autonomy.estimator.model", est.model,
                f"{first.model!r}, the model of uavs[{fusing[0]}]: the base station predicts with one motion model")
        mine = {k: est.params[k] for k in MOTION_PARAMS if k in est.params}
        theirs = {k: first.params[k] for k in MOTION_PARAMS if k in first.params}
        if mine != theirs:
            add(f"uavs[{i}].autonomy.estimator.params", mine,
                f"the motion parameters of uavs[{fusing[0]}] ({theirs}): the base station predicts with one model")
    planners = [i for i, u in enumerate(world.uavs) if u.autonomy.guidance.type == "infoplan"]
    for i, uav in enumerate(world.uavs):
        g = uav.autonomy.guidance
        if g.infoplan is not None and g.type != "infoplan":
            add(f"uavs[{i}].autonomy.guidance.infoplan", g.infoplan.model_dump(exclude_defaults=True),
                f"no 'infoplan' settings unless the type is infoplan (type is {g.type!r})")
        if planners and g.type != "infoplan":
            add(f"uavs[{i}].autonomy.guidance.type", g.type,
                f"'infoplan': uavs[{planners[0]}] plans the whole team with the information planner, so every UAV of "
                "the world must fly it")
    if not planners:
        return issues
    ref = world.uavs[planners[0]].autonomy
    ref_plan = (ref.guidance.infoplan or InfoPlanSpec()).model_dump()
    for i in planners:
        auto = world.uavs[i].autonomy
        where = f"uavs[{i}].autonomy"
        plan = auto.guidance.infoplan or InfoPlanSpec()
        if not any(s.type == "radar" for s in world.uavs[i].sensors):
            add(f"uavs[{i}].sensors", [s.type for s in world.uavs[i].sensors],
                "a radar: guidance infoplan takes the range and azimuth noise of its information model from it")
        if comms.base_station is None:
            add("comms.base_station", None, f"the base station's position [x, y, z] (m): uavs[{i}]'s guidance "
                                            "infoplan maximises the information delivered to it")
        routing = plan.routing or comms.routing
        if routing != "none" and comms.model == "perfect":
            add("comms.model", comms.model, f"a radio model ('rayleigh'): uavs[{i}]'s guidance infoplan weighs the "
                                            f"information by the route probabilities of its links ({routing})")
        if plan.routing not in (None, "none", comms.routing):
            add(f"{where}.guidance.infoplan.routing", plan.routing,
                f"{comms.routing!r} (the radio's comms.routing), 'none' or null: the planner models the routes the "
                "radio uses")
        if plan.model_dump() != ref_plan:
            add(f"{where}.guidance.infoplan", plan.model_dump(exclude_defaults=True),
                f"the infoplan settings of uavs[{planners[0]}] "
                f"({(ref.guidance.infoplan or InfoPlanSpec()).model_dump(exclude_defaults=True)}): every UAV "
                "plans the whole team, so they must agree")
        if auto.guidance.speed != ref.guidance.speed:
            add(f"{where}.guidance.speed", auto.guidance.speed,
                f"{ref.guidance.speed} m/s, the speed of uavs[{planners[0]}]: the team plan flies one speed")
        if auto.rate_hz != ref.rate_hz:
            add(f"{where}.rate_hz", auto.rate_hz,
                f"{ref.rate_hz} Hz, the rate of uavs[{planners[0]}]: the team plan's step T_s is the agents' period")
    return issues
