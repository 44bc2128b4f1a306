"""Road surfaces: carriageway footprints (shapely) and a flat triangle mesh for rendering (trimesh).

Each directed road covers the strip between its edge offsets (:attr:`Road.edge_offsets`): ``[-lanes*w, 0]`` to the
right of a two-way street's dividing line, ``[-lanes*w/2, +lanes*w/2]`` for a one-way road, so twin strips tile the full
street width without overlapping. Strips are sampled along the centre-line at most ``spacing`` metres apart and at most
``max_turn`` radians of heading change apart. On the inside of a bend tighter than the strip (radius below the edge
offset, only on short service roads) the edge is kept at 0.9 times the radius so the strip does not fold over.
"""

from __future__ import annotations

import numpy as np
import shapely
import trimesh
from shapely.geometry import Polygon

from worlds.roads.network import RoadNetwork
from worlds.roads.road import Road

__all__ = ["road_edges", "road_polygon", "road_polygons", "road_surface_mesh"]

_SPACING = 2.0  # m
_MAX_TURN = np.deg2rad(5.0)  # rad of heading change between strip samples
_MAX_INNER = 0.9  # largest |offset * curvature| on the inside of a bend


def _stations(road: Road, spacing: float, max_turn: float) -> np.ndarray:
    """Arc lengths (m) sampling ``road`` for its strip: uniform, dense enough in distance and in heading change."""
    if road.vertices.shape[0] == 2:
        return np.array([0.0, road.length])
    n = max(1, int(np.ceil(road.length / spacing)), int(np.ceil(road.total_turn / max_turn)))
    return np.linspace(0.0, road.length, n + 1)


def road_edges(road: Road, spacing: float = _SPACING, max_turn: float = _MAX_TURN) -> tuple[np.ndarray, np.ndarray]:
    """(right, left) carriageway edge polylines of ``road``, each (N, 2) in the direction of travel (m)."""
    s = _stations(road, spacing, max_turn)
    if road.vertices.shape[0] == 2:
        right, left = road.edge_offsets
        return road.point(s, right), road.point(s, left)
    ka = road.curvature(s)
    edges = []
    for off in road.edge_offsets:
        # On the inside of a bend tighter than the offset the edge would fold back: keep it short of the centre.
        off = np.where(off * ka > _MAX_INNER, _MAX_INNER / np.where(ka == 0, 1.0, ka), off)
        edges.append(road.point(s, off))
    return edges[0], edges[1]


def road_polygon(road: Road, spacing: float = _SPACING, max_turn: float = _MAX_TURN) -> Polygon:
    """Carriageway footprint of ``road`` as a shapely polygon (made valid if a tight bend folds the inner edge)."""
    right, left = road_edges(road, spacing, max_turn)
    poly = Polygon(np.vstack([right, left[::-1]]))
    return poly if poly.is_valid else shapely.make_valid(poly).buffer(0)


def road_polygons(network: RoadNetwork, spacing: float = _SPACING, max_turn: float = _MAX_TURN) -> dict[str, Polygon]:
    """Carriageway footprint of every road, by road id."""
    return {rid: road_polygon(r, spacing, max_turn) for rid, r in network.roads.items()}


def road_surface_mesh(network: RoadNetwork, z: float = 0.02, spacing: float = _SPACING,
                      max_turn: float = _MAX_TURN) -> trimesh.Trimesh:
    """Flat strips of every road's carriageway at height ``z`` (m), faces wound counter-clockwise seen from above.

    Strips overlap at junctions (all at the same height); the mesh is meant for rendering, not for physics.
    """
    verts, faces = [], []
    base = 0
    for road in network.roads.values():
        right, left = road_edges(road, spacing, max_turn)
        n = right.shape[0]
        v = np.empty((2 * n, 3))
        v[0::2, :2], v[1::2, :2], v[:, 2] = right, left, z
        i = base + 2 * np.arange(n - 1)
        # (R_i, R_i+1, L_i) and (L_i, R_i+1, L_i+1): counter-clockwise when left is to the left of travel.
        faces.append(np.stack([i, i + 2, i + 1], axis=1))
        faces.append(np.stack([i + 1, i + 2, i + 3], axis=1))
        verts.append(v)
        base += 2 * n
    if not verts:
        return trimesh.Trimesh(vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), dtype=np.int64), process=False)
    return trimesh.Trimesh(vertices=np.vstack(verts), faces=np.vstack(faces), process=False)
