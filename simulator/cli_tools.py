"""``skytrack validate WORLD`` and ``skytrack inspect WORLD``: check a world and read its map, without physics.

``validate`` loads the world (with ``--set`` overrides) through the loader's checks and builds its road network and
buildings (where a route naming no road is caught), then prints one line: ``OK <name>: ...``. Exit codes: 0 valid;
2 invalid, with the :class:`worlds.errors.WorldError` message (file, key path, value, what was expected).

``inspect`` prints what one needs to write a world on that map: the extent of the roads and buildings, every road
with its length, speed limit and lanes, every junction with its position and the roads leaving it, the buildings,
and the designated target's route (``--json`` for the same as one JSON object). Neither starts PyBullet.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict, dataclass
from typing import Any

from worlds.errors import WorldError

__all__ = ["MapSummary", "add_tools_parsers", "map_summary", "package_version"]


def package_version() -> str:
    """The installed ``skytrack`` distribution's version (``unknown`` when it is not installed, e.g. a bare
    checkout on ``sys.path``)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("skytrack")
    except PackageNotFoundError:
        return "unknown"


@dataclass(frozen=True)
class MapSummary:
    """A world's map and cast, as ``inspect`` prints it (lengths m, speeds m/s)."""

    name: str
    description: str
    extent: tuple[float, float, float, float] | None
    ground_size: tuple[float, float]
    roads: list[dict[str, Any]]
    junctions: list[dict[str, Any]]
    buildings: int
    building_height: tuple[float, float] | None
    uavs: list[str]
    ground_vehicles: dict[str, int]
    target_routes: list[dict[str, Any]]


def _load(world: str, overrides: list[str]) -> tuple[Any, Any]:
    """(loaded world, its geometry); raises WorldError."""
    import simulator.registry  # noqa: F401  (registers the components' own rules with the loader's checks)
    from simulator.seeding import RunSeeds
    from worlds.build import build_geometry
    from worlds.loader import load_world

    loaded = load_world(world, overrides)
    geometry = build_geometry(loaded.world, loaded.path, RunSeeds(loaded.world.sim.seed).generator("world/town"))
    return loaded, geometry


def map_summary(loaded: Any, geometry: Any) -> MapSummary:
    """The :class:`MapSummary` of a loaded world and its built geometry (:func:`worlds.build.build_geometry`)."""
    import numpy as np

    world, net = loaded.world, geometry.network
    pts = [b.footprint for b in geometry.buildings]
    roads, junctions = [], []
    if net is not None:
        pts += [r.vertices for r in net.roads.values()]
        roads = [{"id": r.id, "length_m": round(r.length, 1), "speed_limit_mps": round(r.speed_limit, 2),
                  "lanes": int(r.lanes), "from": r.start_node, "to": r.end_node} for r in net.roads.values()]
        junctions = [{"id": n, "x": round(float(p[0]), 1), "y": round(float(p[1]), 1), "out": net.out_roads(n)}
                     for n, p in net.nodes.items()]
    extent = None
    if pts:
        xy = np.concatenate(pts)
        extent = tuple(round(float(v), 1) for v in (xy[:, 0].min(), xy[:, 0].max(), xy[:, 1].min(), xy[:, 1].max()))
    heights = [b.height for b in geometry.buildings]
    by_id = {g.id: g for g in world.ground_vehicles}
    routes = []
    for tid in world.target_ids():
        g = by_id.get(tid)
        if g is None:
            continue
        r = g.route
        entry: dict[str, Any] = {"vehicle": tid, "start_s": r.start_s, "lane": r.lane}
        if r.roads is not None:
            entry["roads"] = list(r.roads)
            if net is not None:
                entry["length_m"] = round(sum(net.roads[k].length for k in r.roads if k in net.roads), 1)
        else:
            entry["random_walk_from"] = r.random_walk_from
        routes.append(entry)
    roles: dict[str, int] = {}
    for g in world.ground_vehicles:
        roles[g.role] = roles.get(g.role, 0) + 1
    return MapSummary(name=world.name, description=world.description, extent=extent,
                      ground_size=tuple(float(v) for v in world.terrain.size), roads=roads, junctions=junctions,
                      buildings=len(heights),
                      building_height=(round(min(heights), 1), round(max(heights), 1)) if heights else None,
                      uavs=[u.id for u in world.uavs], ground_vehicles=roles, target_routes=routes)


def _load_or_report(command: str, args: argparse.Namespace) -> tuple[Any, Any] | None:
    """:func:`_load` of the command's world and ``--set`` lines, or None after printing the world error as
    ``skytrack COMMAND: …`` on stderr."""
    try:
        return _load(args.world, args.set or [])
    except WorldError as exc:
        print(f"skytrack {command}: {exc}", file=sys.stderr)
        return None


def _validate(args: argparse.Namespace) -> int:
    if (got := _load_or_report("validate", args)) is None:
        return 2
    loaded, geometry = got
    w = loaded.world
    net = geometry.network
    cars = ", ".join(f"{n} {role}" for role, n in map_summary(loaded, geometry).ground_vehicles.items()) or "none"
    roads = f"{len(net.roads)} roads" if net is not None else "no roads"
    print(f"OK {w.name}: {len(w.uavs)} UAVs, ground vehicles: {cars}, {roads}, {len(geometry.buildings)} buildings, "
          f"{w.sim.duration_s:g} s at {w.sim.physics_hz} Hz ({loaded.path})")
    return 0


def _inspect(args: argparse.Namespace) -> int:
    if (got := _load_or_report("inspect", args)) is None:
        return 2
    s = map_summary(*got)
    if args.json:
        print(json.dumps(asdict(s), indent=2))
        return 0
    for line in _text(s):
        print(line)
    return 0


def _text(s: MapSummary) -> list[str]:
    lines = [f"world: {s.name}"]
    if s.description:
        lines.append(f"description: {s.description}")
    if s.extent is not None:
        x0, x1, y0, y1 = s.extent
        lines.append(f"extent: x {x0:g} .. {x1:g} m, y {y0:g} .. {y1:g} m (roads and buildings)")
    lines.append(f"ground: {s.ground_size[0]:g} x {s.ground_size[1]:g} m")
    lines.append(f"roads: {len(s.roads)}" + ("" if s.roads else " (none)"))
    if s.roads:
        w = max(len(r["id"]) for r in s.roads)
        lines.append(f"  {'id':<{w}}  {'length m':>9}  {'limit m/s':>9}  {'km/h':>5}  lanes  from -> to")
        for r in s.roads:
            lines.append(f"  {r['id']:<{w}}  {r['length_m']:>9.1f}  {r['speed_limit_mps']:>9.2f}  "
                         f"{3.6 * r['speed_limit_mps']:>5.0f}  {r['lanes']:>5}  {r['from']} -> {r['to']}")
    lines.append(f"junctions: {len(s.junctions)}")
    for j in s.junctions:
        lines.append(f"  {j['id']}  ({j['x']:g}, {j['y']:g})  out: {', '.join(j['out']) or '-'}")
    heights = "" if s.building_height is None else f" (heights {s.building_height[0]:g} .. {s.building_height[1]:g} m)"
    lines.append(f"buildings: {s.buildings}{heights}")
    lines.append(f"uavs: {', '.join(s.uavs) or 'none'}")
    lines.append("ground vehicles: " + (", ".join(f"{n} {role}" for role, n in s.ground_vehicles.items()) or "none"))
    if not s.target_routes:
        lines.append("target route: none (no designated target)")
    for r in s.target_routes:
        where = f"start_s {r['start_s']:g} m, lane {r['lane']}"
        if "roads" in r:
            length = f", {r['length_m']:g} m" if "length_m" in r else ""
            lines.append(f"target route ({r['vehicle']}): {' -> '.join(r['roads'])} ({where}{length})")
        else:
            lines.append(f"target route ({r['vehicle']}): random walk from {r['random_walk_from']} ({where})")
    return lines


def add_tools_parsers(subparsers: argparse._SubParsersAction) -> None:
    """Register the ``validate`` and ``inspect`` subcommands on a ``skytrack`` subparser set."""
    for name, fn, text in (("validate", _validate, "load and check a world (no physics): one OK line, or the errors"),
                           ("inspect", _inspect, "print a world's map: extent, roads, junctions, buildings, target "
                                                 "route (no physics)")):
        p = subparsers.add_parser(name, help=text)
        p.add_argument("world", help="shipped world name (see 'skytrack worlds') or path to a world YAML file")
        p.add_argument("--set", action="append", metavar="KEY.PATH=VALUE",
                       help="override a world value before checking it (repeatable)")
        if name == "inspect":
            p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
        p.set_defaults(fn=fn)
