"""From a validated world to its static geometry: the road network, the buildings and the road-surface mesh.

Roads come from exactly one source — explicit ``streets``, a procedural ``town`` or an ``osm`` extract — and buildings
from the ``buildings`` list plus whatever the town or the extract holds. Problems are reported as
:class:`worlds.errors.WorldError` naming the key path, before any physics starts.
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from worlds.errors import WorldError, WorldIssue
from worlds.geometry import Building
from worlds.roads.network import RoadNetwork
from worlds.roads.signals import signalised_junctions
from worlds.schema import World

__all__ = ["WorldGeometry", "build_geometry", "resolve_map_path"]


@dataclass(frozen=True)
class WorldGeometry:
    """Static geometry of a world.

    Attributes
    ----------
    network : RoadNetwork | None
        The road graph (None for worlds without roads).
    buildings : list[Building]
        Every building.
    road_mesh : Any
        ``trimesh.Trimesh`` of the road surface (None without roads).
    signals : tuple[str, ...]
        Junction node ids the map's traffic signals control (:func:`worlds.roads.signals.signalised_junctions`);
        empty when the road source marks no signals (explicit streets, procedural towns).
    """

    network: RoadNetwork | None
    buildings: list[Building]
    road_mesh: Any
    signals: tuple[str, ...] = ()


def resolve_map_path(path: str, world_file: Path) -> Path:
    """A map path as given, else relative to the world file, else under the package's ``assets/maps``."""
    from importlib import resources

    candidates = [Path(path), world_file.parent / path, Path(str(resources.files("assets"))) / "maps" / path]
    for c in candidates:
        if c.is_file():
            return c
    return candidates[1]


def build_geometry(world: World, world_file: Path, rng: np.random.Generator) -> WorldGeometry:
    """Build the road network and buildings of ``world`` (``world_file`` resolves relative map paths)."""
    file = str(world_file)
    roads = world.roads
    mesh = None
    network: RoadNetwork | None = None
    buildings: list[Building] = []
    signals: tuple[str, ...] = ()
    where = "roads"
    try:
        if roads.streets:
            spec = {"nodes": {k: list(v) for k, v in roads.nodes.items()},
                    "streets": [s.model_dump() for s in roads.streets]}
            network = RoadNetwork.from_spec(spec)
            where = "roads.streets"
        elif roads.town is not None:
            from worlds.town import TownConfig, generate_town

            where = "roads.town"
            params = dict(roads.town.model_extra or {})
            names = {f.name for f in dataclasses.fields(TownConfig)}
            unknown = sorted(set(params) - names)
            if unknown:
                raise WorldError(file, [WorldIssue(f"roads.town.{unknown[0]}", params[unknown[0]],
                                                   f"a TownConfig field ({', '.join(sorted(names))})")])
            params = {k: tuple(v) if isinstance(v, list) else v for k, v in params.items()}
            town = generate_town(TownConfig(**params), rng)
            network, buildings = town.network, list(town.buildings)
        elif roads.osm is not None:
            where = "roads.osm.path"
            path = resolve_map_path(roads.osm.path, world_file)
            town, mesh = _import_osm(path, roads.osm.bbox, roads.osm.default_height)
            network, buildings = town.network, list(town.buildings)
            signals = signalised_junctions(network, town.signals)
    except WorldError:
        raise
    except (ValueError, TypeError, OSError) as exc:
        raise WorldError(file, [WorldIssue(where, _value_at(world, where), f"a usable road source ({exc})")]) from None

    for i, b in enumerate(world.buildings):
        buildings.append(Building.cuboid(b.center, b.size, float(np.radians(b.yaw_deg)), name=f"b{i}"))

    issues = [] if network is None else _unknown_ids(world, network)
    issues += _starts_in_buildings(world, buildings[:len(buildings) - len(world.buildings)])
    if issues:
        raise WorldError(file, issues)

    if network is not None and mesh is None:
        from worlds.roads.mesh import road_surface_mesh

        mesh = road_surface_mesh(network)
    return WorldGeometry(network=network, buildings=buildings, road_mesh=mesh, signals=signals)


def _unknown_ids(world: World, network: RoadNetwork) -> list[WorldIssue]:
    """The road and node ids the world names (routes, traffic flows, traffic signals) that ``network`` lacks."""
    roads: list[tuple[str, str]] = []
    for i, g in enumerate(world.ground_vehicles):
        where = f"ground_vehicles[{i}].route."
        roads += ([(f"{where}roads[{k}]", r) for k, r in enumerate(g.route.roads)] if g.route.roads
                  else [(f"{where}random_walk_from", g.route.random_walk_from)])
    for i, f in enumerate(world.traffic.flows):
        roads += [(f"traffic.flows[{i}].from", f.origin), (f"traffic.flows[{i}].to", f.destination)]
        roads += [(f"traffic.flows[{i}].via[{k}]", r) for k, r in enumerate(f.via)]
    nodes = [(f"traffic.signals[{i}]", n) for i, n in enumerate(world.traffic.signals)]
    road_hint = f"a road id of the network (e.g. {', '.join(list(network.roads)[:6])}; a street 's' gives roads " \
                "'s.f' and 's.r')"
    node_hint = f"a node id of the network (e.g. {', '.join(list(network.nodes)[:6])})"
    return ([WorldIssue(key, rid, road_hint) for key, rid in roads if rid not in network.roads]
            + [WorldIssue(key, nid, node_hint) for key, nid in nodes if nid not in network.nodes])


def _import_osm(path: Path, bbox: Any, default_height: float) -> tuple[Any, Any]:
    """(town, road surface mesh) of an OpenStreetMap file, from the map cache when it holds them
    (:mod:`worlds.map_cache`)."""
    from worlds.map_cache import cached
    from worlds.osm import load_osm
    from worlds.roads.mesh import road_surface_mesh

    def build() -> tuple[Any, Any]:
        town = load_osm(path, bbox=bbox, default_height=default_height)
        town.network.nearest(np.zeros(2))  # builds the network's point index (≈ 0.3 s), so the cache holds it too
        return town, road_surface_mesh(town.network)

    if not path.is_file():
        return build()  # load_osm says what is wrong with the path
    params = repr((None if bbox is None else tuple(bbox), float(default_height)))
    key = [hashlib.sha256(path.read_bytes()).digest(), params]
    return cached("osm", key, build)


def _starts_in_buildings(world: World, generated: list[Building]) -> list[WorldIssue]:
    """A UAV starting inside (or within :data:`~worlds.checks.START_CLEARANCE` of) a building of the town or the map:
    the loader checks the world file's own ``buildings`` (:mod:`worlds.checks`); these exist only once built."""
    if not generated:
        return []
    from shapely import Point, Polygon

    from worlds.checks import START_CLEARANCE

    lo = np.array([b.footprint.min(axis=0) for b in generated]) - START_CLEARANCE
    hi = np.array([b.footprint.max(axis=0) for b in generated]) + START_CLEARANCE
    top = np.array([b.base_z + b.height for b in generated]) + START_CLEARANCE
    issues = []
    for i, uav in enumerate(world.uavs):
        x, y, z = (float(c) for c in uav.initial.position)
        near = np.flatnonzero((lo[:, 0] <= x) & (x <= hi[:, 0]) & (lo[:, 1] <= y) & (y <= hi[:, 1]) & (z <= top))
        for k in near:
            b = generated[int(k)]
            if Polygon(b.footprint).distance(Point(x, y)) <= START_CLEARANCE and z >= b.base_z - START_CLEARANCE:
                issues.append(WorldIssue(f"uavs[{i}].initial.position", [x, y, z],
                                         f"a start outside every building, at least {START_CLEARANCE:g} m from its "
                                         f"walls and roof: the map's building {b.name or k} (height {b.height:g} m) "
                                         f"holds it"))
                break
    return issues


def _value_at(world: World, dotted: str) -> Any:
    node: Any = world
    for part in dotted.split("."):
        node = getattr(node, part, None)
    if hasattr(node, "model_dump"):
        return node.model_dump(exclude_none=True)
    return node
