"""A directed road graph: junction nodes joined by :class:`~worlds.roads.road.Road` edges.

Frames: world ENU x-y plane, metres. Travel is right-hand; a two-way street is a pair of twin roads sharing one
centre-line (the dividing line), each with its lanes on its own right.
"""

from __future__ import annotations

import heapq
import itertools
import weakref
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from worlds.roads.projection import RoadTables, project_pairs
from worlds.roads.road import Road

__all__ = ["RoadNetwork", "street_road_ids"]

_NODE_TOL = 1e-3  # m; a road must start / end this close to its junction nodes
_SEARCH_SPACING = 2.0  # m; spacing of the samples indexing all roads for nearest()
_TABLES: weakref.WeakKeyDictionary[RoadNetwork, RoadTables] = weakref.WeakKeyDictionary()  # see _road_tables


def street_road_ids(street_id: str) -> tuple[str, str]:
    """(forward, reverse) road ids of a street built by :meth:`RoadNetwork.from_spec`: ``"<id>.f"``, ``"<id>.r"``."""
    return f"{street_id}.f", f"{street_id}.r"


class RoadNetwork:
    """Roads and the junctions they connect.

    Parameters
    ----------
    roads : iterable of Road
        The directed roads; ids must be unique, twins must name each other and run between the same nodes reversed.
    nodes : mapping str -> (2,) array
        Junction positions (m). Every road must start at its ``start_node`` and end at its ``end_node`` within 1 mm.

    Attributes
    ----------
    roads : dict[str, Road]
        Roads by id, in the order given.
    nodes : dict[str, np.ndarray]
        Junction positions by id (read-only (2,) arrays, m).
    """

    def __init__(self, roads: Iterable[Road], nodes: Mapping[str, Any]) -> None:
        self.nodes: dict[str, np.ndarray] = {}
        for nid, p in nodes.items():
            arr = np.array(p, dtype=float)
            if arr.shape != (2,) or not np.all(np.isfinite(arr)):
                raise ValueError(f"node {nid!r}: position must be 2 finite numbers, got {p!r}")
            arr.setflags(write=False)
            self.nodes[str(nid)] = arr
        self.roads: dict[str, Road] = {}
        for road in roads:
            if road.id in self.roads:
                raise ValueError(f"road id {road.id!r} is used twice")
            self.roads[road.id] = road
        self._out: dict[str, list[str]] = {n: [] for n in self.nodes}
        for road in self.roads.values():
            self._check_road(road)
            self._out[road.start_node].append(road.id)
        self._ids = list(self.roads)
        self._index: tuple[cKDTree, np.ndarray] | None = None
        self._rank = {rid: k for k, rid in enumerate(self._ids)}

    def _check_road(self, road: Road) -> None:
        ends = (("start_node", road.start_node, road.vertices[0]), ("end_node", road.end_node, road.vertices[-1]))
        for end, nid, p in ends:
            if nid not in self.nodes:
                raise ValueError(f"road {road.id!r}: {end} {nid!r} is not a node of the network")
            gap = float(np.hypot(*(self.nodes[nid] - p)))
            if gap > _NODE_TOL:
                raise ValueError(f"road {road.id!r}: its {end} {nid!r} is {gap:.3f} m from the road's end vertex")
        if road.twin is not None:
            twin = self.roads.get(road.twin)
            if twin is None:
                raise ValueError(f"road {road.id!r}: twin {road.twin!r} is not in the network")
            if twin.twin != road.id or twin.start_node != road.end_node or twin.end_node != road.start_node:
                raise ValueError(f"road {road.id!r}: twin {road.twin!r} must name it back and run between the same "
                                 f"nodes in the opposite direction")

    # ------------------------------------------------------------------ construction from plain data
    @classmethod
    def from_spec(cls, spec: Any) -> "RoadNetwork":
        """Build from plain data (a mapping or an object with the same attributes, e.g. the world-file section).

        ``spec`` has ``nodes``: ``{id: [x, y]}`` (m) and ``streets``: a list of ``{id, nodes: [a, b],
        via: [[x, y], ...], lanes, lane_width, speed_limit, two_way}``; ``via`` are the intermediate centre-line
        vertices from ``a`` to ``b`` (default none); ``lanes`` is per direction (default 1), ``lane_width`` in m (3.5),
        ``speed_limit`` in m/s (13.9), ``two_way`` (true). A street ``"s"`` becomes road ``"s.f"`` (a -> b) and, if
        two-way, its twin ``"s.r"`` (b -> a).
        """
        nodes = {str(k): v for k, v in dict(_get(spec, "nodes", {}) or {}).items()}
        streets = list(_get(spec, "streets", []) or [])
        roads: list[Road] = []
        seen: set[str] = set()
        for i, st in enumerate(streets):
            sid = _get(st, "id", None)
            if not sid:
                raise ValueError(f"streets[{i}]: missing id")
            sid = str(sid)
            if sid in seen:
                raise ValueError(f"streets[{i}]: street id {sid!r} is used twice")
            seen.add(sid)
            ends = list(_get(st, "nodes", []) or [])
            if len(ends) != 2:
                raise ValueError(f"street {sid!r}: nodes must be [start, end], got {ends!r}")
            a, b = (str(n) for n in ends)
            for n in (a, b):
                if n not in nodes:
                    raise ValueError(f"street {sid!r}: node {n!r} is not in nodes")
            via = np.array(_get(st, "via", []) or [], dtype=float).reshape(-1, 2)
            verts = np.vstack([np.asarray(nodes[a], dtype=float), via, np.asarray(nodes[b], dtype=float)])
            two_way = bool(_get(st, "two_way", True))
            fwd, rev = street_road_ids(sid)
            common = dict(lanes=_get(st, "lanes", 1), lane_width=float(_get(st, "lane_width", 3.5)),
                          speed_limit=float(_get(st, "speed_limit", 13.9)))
            try:
                roads.append(Road(id=fwd, vertices=verts, start_node=a, end_node=b, twin=rev if two_way else None,
                                  **common))
                if two_way:
                    roads.append(roads[-1].reversed(id=rev))
            except ValueError as exc:
                raise ValueError(f"street {sid!r}: {exc}") from exc
        return cls(roads, nodes)

    # ------------------------------------------------------------------ graph queries
    def successors(self, road_id: str) -> list[str]:
        """Roads leaving ``road_id``'s end node, without its twin (no U-turn) unless the twin is the only way on."""
        road = self._road(road_id)
        out = self._out[road.end_node]
        onward = [r for r in out if r != road.twin]
        return onward if onward else list(out)

    def route(self, from_node: str, to_node: str) -> list[str]:
        """Shortest sequence of roads (by centre-line length) from ``from_node`` to ``to_node`` (Dijkstra).

        Returns ``[]`` when the nodes are equal; raises ``ValueError`` for unknown or unreachable nodes.
        """
        for n in (from_node, to_node):
            if n not in self.nodes:
                raise ValueError(f"route: unknown node {n!r}")
        dist = {from_node: 0.0}
        via: dict[str, str] = {}
        heap = [(0.0, from_node)]
        done: set[str] = set()
        while heap:
            d, n = heapq.heappop(heap)
            if n in done:
                continue
            if n == to_node:
                break
            done.add(n)
            for rid in self._out[n]:
                road = self.roads[rid]
                nd = d + road.length
                if nd < dist.get(road.end_node, np.inf):
                    dist[road.end_node] = nd
                    via[road.end_node] = rid
                    heapq.heappush(heap, (nd, road.end_node))
        if to_node not in dist:
            raise ValueError(f"route: node {to_node!r} cannot be reached from {from_node!r}")
        path: list[str] = []
        n = to_node
        while n != from_node:
            rid = via[n]
            path.append(rid)
            n = self.roads[rid].start_node
        return path[::-1]

    def random_route(self, start_road: str, n_roads: int, rng: np.random.Generator) -> list[str]:
        """A seeded random walk of ``n_roads`` roads from ``start_road``, each next drawn uniformly from successors.

        Stops early only if a road has no way on at all (a one-way dead end).
        """
        if n_roads < 1:
            raise ValueError(f"random_route: n_roads must be >= 1, got {n_roads}")
        self._road(start_road)
        out = [start_road]
        while len(out) < n_roads:
            nxt = self.successors(out[-1])
            if not nxt:
                break
            out.append(nxt[int(rng.integers(len(nxt)))])
        return out

    def nearest(self, p_xy: np.ndarray) -> tuple[str, float, float]:
        """(road_id, s, lateral) of the road point nearest to ``p_xy`` (m), over all roads (:meth:`nearest_many` of
        one point).

        Twins share a centre-line; between them the one with the point on its right (``lateral <= 0``, its own
        carriageway) wins.
        """
        ids, s, lat = self.nearest_many(np.asarray(p_xy, dtype=float)[:2])
        return ids[0], float(s[0]), float(lat[0])

    def project_on(self, road_ids: Sequence[str], points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(s, lateral) of each of the (P, 2) ``points`` (m) projected onto the road ``road_ids[i]``: what
        :meth:`Road.project` gives, to within 1e-9 m, in one compiled call (:mod:`worlds.roads.projection`)."""
        s, lat, _ = project_pairs(self._road_tables(), np.array([self._rank[r] for r in road_ids], dtype=np.int64),
                                  points)
        return s, lat

    def nearest_many(self, points: np.ndarray) -> tuple[list[str], np.ndarray, np.ndarray]:
        """(road ids, arc lengths, lateral offsets) of the road point nearest to each of the (P, 2) ``points`` (m):
        the candidate roads from a k-d tree of samples along every road, all (point, candidate) pairs projected in one
        compiled call (:mod:`worlds.roads.projection`), the nearest by distance (to the micrometre), then the road
        with the point on its right, then the road id."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if len(pts) == 0:
            return [], np.zeros(0), np.zeros(0)
        if not self.roads:
            raise ValueError("nearest: the network has no roads")
        tree, owner = self._search_index()
        d0, _ = tree.query(pts)
        near = tree.query_ball_point(pts, d0 + _SEARCH_SPACING / 2 + 1e-9)
        counts = np.fromiter(map(len, near), dtype=np.int64, count=len(near))
        sample = np.fromiter(itertools.chain.from_iterable(near), dtype=np.int64, count=int(counts.sum()))
        n_roads = len(self._ids)
        pair = np.unique(np.repeat(np.arange(len(pts), dtype=np.int64), counts) * n_roads + owner[sample])
        point_of, road_of = pair // n_roads, pair % n_roads  # each point's candidate roads once, in index order
        s, lat, dist = project_pairs(self._road_tables(), road_of, pts[point_of])
        # only a road within 2 µm of a point's nearest can tie it at the micrometre: |round(d, 6) - d| <= 0.5 µm
        least = np.full(len(pts), np.inf)
        np.minimum.at(least, point_of, dist)
        close = np.flatnonzero(dist <= least[point_of] + 2e-6)
        best: list[tuple | None] = [None] * len(pts)
        for i, k, si, li, di in zip(point_of[close].tolist(), road_of[close].tolist(), s[close].tolist(),
                                    lat[close].tolist(), dist[close].tolist(), strict=True):
            key = (round(di, 6), 0 if li <= 0 else 1, self._ids[k], si, li)
            if best[i] is None or key[:3] < best[i][:3]:
                best[i] = key
        return [b[2] for b in best], np.array([b[3] for b in best]), np.array([b[4] for b in best])

    def _road_tables(self) -> RoadTables:
        """Every road's table end to end (made at the first batch projection), kept beside the network rather than
        in it: the map cache stores a network's own state, and these are derived from its roads."""
        tables = _TABLES.get(self)
        if tables is None:
            tables = _TABLES[self] = RoadTables.of([self.roads[rid] for rid in self._ids])
        return tables

    def _search_index(self) -> tuple[cKDTree, np.ndarray]:
        if self._index is None:
            pts, owner = [], []
            for k, rid in enumerate(self._ids):
                road = self.roads[rid]
                n = max(1, int(np.ceil(road.length / _SEARCH_SPACING)))
                pts.append(road.point(np.linspace(0.0, road.length, n + 1)))
                owner.append(np.full(n + 1, k))
            self._index = (cKDTree(np.vstack(pts)), np.concatenate(owner))
        return self._index

    def total_length(self) -> float:
        """Sum of the lengths of all directed roads (m); a two-way street counts twice (see :meth:`street_length`)."""
        return float(sum(r.length for r in self.roads.values()))

    def street_length(self) -> float:
        """Length of street centre-line (m): every two-way street once."""
        return float(sum(r.length for r in self.roads.values() if r.twin is None or r.id < r.twin))

    def is_connected(self) -> bool:
        """True if every node can be reached from every other by driving (strong connectivity of the directed graph)."""
        if not self.nodes:
            return False
        return self.strong_components()[0] == 1

    def strong_components(self) -> tuple[int, dict[str, int]]:
        """(number of strongly connected components, component label of every node)."""
        ids = list(self.nodes)
        index = {n: i for i, n in enumerate(ids)}
        rows = [index[r.start_node] for r in self.roads.values()]
        cols = [index[r.end_node] for r in self.roads.values()]
        g = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(ids), len(ids))).tocsr()
        n, labels = connected_components(g, directed=True, connection="strong")
        return int(n), {nid: int(labels[i]) for nid, i in index.items()}

    def out_roads(self, node: str) -> list[str]:
        """Roads leaving ``node``."""
        if node not in self.nodes:
            raise ValueError(f"unknown node {node!r}")
        return list(self._out[node])

    def _road(self, road_id: str) -> Road:
        try:
            return self.roads[road_id]
        except KeyError:
            raise ValueError(f"unknown road {road_id!r}") from None

    def __repr__(self) -> str:
        return f"RoadNetwork({len(self.nodes)} nodes, {len(self.roads)} roads, {self.total_length():.0f} m)"


def _get(obj: Any, key: str, default: Any) -> Any:
    """``obj[key]`` for mappings, ``obj.key`` otherwise; ``default`` when missing or None."""
    val = obj.get(key, default) if isinstance(obj, Mapping) else getattr(obj, key, default)
    return default if val is None else val
