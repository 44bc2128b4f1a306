"""Which junctions of a road network a map's traffic signals control.

A map marks signals as points (OpenStreetMap: ``highway=traffic_signals`` nodes, often on each approach a few metres
before the junction rather than on the junction itself, and ``crossing=traffic_signals`` crossings on its legs). A
junction here is a node with at least three neighbouring nodes. It is signalised when

* a signal lies on it (within :data:`AT_NODE_M`), or
* signals lie on at least half (rounded up) of its approaches: an approach is a road ending at the junction (the
  roads from one neighbouring node count once), and a signal lies on it when it is within ``on_road_m`` of the
  road's centre-line and within ``join_m`` of its end along it.

So a junction mapped with signals on its legs gets a light, while a lone signalised crossing mid-block (one approach
of a junction 20 m away) does not. The rule plays the part of netconvert's ``--tls.guess-signals`` for the networks
skytrack builds itself (SUMO never sees the map, only skytrack's road graph).
"""

from __future__ import annotations

import math

import numpy as np

from worlds.roads.network import RoadNetwork

__all__ = ["AT_NODE_M", "JOIN_M", "ON_ROAD_M", "junctions", "signalised_junctions"]

AT_NODE_M = 2.0
"""A signal this near a junction node (m) is on it."""
JOIN_M = 25.0
"""Default greatest distance (m) along an approach from a signal to the junction it controls."""
ON_ROAD_M = 3.0
"""Default greatest distance (m) of a signal from an approach's centre-line (the map's way, up to the road fit)."""


def junctions(network: RoadNetwork) -> dict[str, set[str]]:
    """Junction node -> its neighbouring nodes, for every node with at least three (roads in either direction)."""
    near: dict[str, set[str]] = {n: set() for n in network.nodes}
    for road in network.roads.values():
        if road.start_node != road.end_node:
            near[road.start_node].add(road.end_node)
            near[road.end_node].add(road.start_node)
    return {n: nb for n, nb in near.items() if len(nb) >= 3}


def signalised_junctions(network: RoadNetwork, signals_xy: np.ndarray, join_m: float = JOIN_M,
                         on_road_m: float = ON_ROAD_M) -> tuple[str, ...]:
    """The junctions (sorted node ids) that the signals at ``signals_xy`` (K, 2) m control (module docstring)."""
    for name, v in (("join_m", join_m), ("on_road_m", on_road_m)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"signalised_junctions: {name} must be finite and > 0 m, got {v!r}")
    pts = np.asarray(signals_xy, dtype=float).reshape(-1, 2)
    if not np.all(np.isfinite(pts)):
        raise ValueError("signalised_junctions: signal positions must be finite")
    joints = junctions(network)
    if not len(pts) or not joints:
        return ()
    ids = list(joints)
    xy = np.array([network.nodes[n] for n in ids])
    d = np.hypot(xy[:, None, 0] - pts[None, :, 0], xy[:, None, 1] - pts[None, :, 1])
    lit = {ids[k] for k in np.flatnonzero((d <= AT_NODE_M).any(axis=1))}
    incoming: dict[str, list] = {}
    for road in network.roads.values():
        if road.start_node != road.end_node and road.end_node in joints:
            incoming.setdefault(road.end_node, []).append(road)
    reach = join_m + on_road_m
    for k in np.flatnonzero(d.min(axis=1) <= reach):  # junctions with a signal within reach at all
        node = ids[k]
        q = pts[d[k] <= reach]
        approaches = {r.start_node for r in incoming.get(node, ())}
        signalled = set()
        for road in incoming.get(node, ()):
            s, lat = road.project_many(q)  # s is clipped to the road: a signal past either end is not on it
            if np.any((np.abs(lat) <= on_road_m) & (s > 0.0) & (s < road.length) & (road.length - s <= join_m)):
                signalled.add(road.start_node)
        if signalled and len(signalled) >= math.ceil(len(approaches) / 2):
            lit.add(node)
    return tuple(sorted(lit))
