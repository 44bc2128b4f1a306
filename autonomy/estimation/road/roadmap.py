"""A road network seen by the road-constrained filters: cached biarc approximations, lane priors, map distance.

The approximation of each road is built on first use (:meth:`RoadApproximation.from_road` with ``vertex_spacing``).
"Distance to the map" is measured outside the carriageway: a point on any lane of a road is at distance 0 from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from autonomy.estimation.road.constraint import RoadConstraintParams, lane_prior
from autonomy.estimation.road.segments import RoadApproximation
from worlds.roads.network import RoadNetwork
from worlds.roads.road import Road

__all__ = ["RoadMap", "RoadCandidate"]


@dataclass(frozen=True)
class RoadCandidate:
    """A road near a position: its id, the arc length and left offset of the position on it (m), and the distance
    outside its carriageway (m)."""

    road_id: str
    s: float
    lateral: float
    excess: float


class RoadMap:
    """Road network plus what the filters need from it.

    Parameters
    ----------
    network : RoadNetwork
        The roads.
    params : RoadConstraintParams
        Lane priors (offset, σ_ℓ) per road come from these.
    vertex_spacing : float or None
        Resample each road's centre-line at most this far apart before the biarc fit (m); None: use its vertices.
    line_curvature : float
        Curvature below which a biarc piece becomes a line (1/m).
    """

    def __init__(self, network: RoadNetwork, params: RoadConstraintParams, *, vertex_spacing: float | None = 10.0,
                 line_curvature: float = 1e-4) -> None:
        self.network = network
        self.params = params
        self.vertex_spacing = vertex_spacing
        self.line_curvature = line_curvature
        self._approx: dict[str, RoadApproximation] = {}
        self._lanes = {rid: lane_prior(r, params) for rid, r in network.roads.items()}
        self._boxes = {rid: (r.samples.min(axis=0), r.samples.max(axis=0)) for rid, r in network.roads.items()}
        # the boxes as arrays, rows in the network's order, for the one-pass box test of :meth:`candidates`
        self._ids = list(self._boxes)
        self._lo = np.array([lo for lo, _ in self._boxes.values()], dtype=float).reshape(-1, 2)
        self._hi = np.array([hi for _, hi in self._boxes.values()], dtype=float).reshape(-1, 2)
        self._width = np.array([r.lanes * r.lane_width for r in network.roads.values()], dtype=float)

    def road(self, road_id: str) -> Road:
        """The road ``road_id``."""
        return self.network.roads[road_id]

    def approximation(self, road_id: str) -> RoadApproximation:
        """The (cached) biarc approximation of ``road_id``."""
        a = self._approx.get(road_id)
        if a is None:
            a = RoadApproximation.from_road(self.network.roads[road_id], max_spacing=self.vertex_spacing,
                                            line_curvature=self.line_curvature)
            self._approx[road_id] = a
        return a

    def lane(self, road_id: str) -> tuple[float, float]:
        """(assumed lateral offset ℓ0, σ_ℓ) of ``road_id`` in m."""
        return self._lanes[road_id]

    @property
    def lanes(self) -> dict[str, tuple[float, float]]:
        """Lane priors of every road."""
        return dict(self._lanes)

    def excess(self, road: Road, p: np.ndarray) -> tuple[float, float, float]:
        """(s, lateral, distance outside the carriageway) of ``p`` on ``road`` (m), beyond the ends included."""
        s, lat = road.project(p)
        right, left = road.edge_offsets
        if road.twin is not None:  # the twin's carriageway is the other half of the street
            left = -right
        d_lat = max(0.0, lat - left, right - lat)
        d_total = float(np.hypot(*(road.point(s) - p)))
        d_along = math.sqrt(max(0.0, d_total * d_total - lat * lat))
        return s, lat, math.hypot(d_lat, d_along)

    def candidates(self, p: np.ndarray, max_excess: float) -> list[RoadCandidate]:
        """Roads whose carriageway lies within ``max_excess`` m of ``p`` (2,), in the network's order.

        The roads whose bounding box, grown by ``max_excess`` plus the carriageway's width, misses ``p`` are dropped
        in one array pass (a city has thousands of roads: one test per road in Python cost 36 ms a call).
        """
        p = np.asarray(p, dtype=float)[:2]
        margin = (max_excess + self._width)[:, None]
        near = ~(np.any(p < self._lo - margin, axis=1) | np.any(p > self._hi + margin, axis=1))
        out = []
        for k in np.flatnonzero(near).tolist():
            rid = self._ids[k]
            road = self.network.roads[rid]
            s, lat, ex = self.excess(road, p)
            if ex <= max_excess:
                out.append(RoadCandidate(rid, s, lat, ex))
        return out

    def distance_to_map(self, p: np.ndarray) -> float:
        """Distance (m) from ``p`` (2,) to the nearest carriageway of the network."""
        rid, _, _ = self.network.nearest(np.asarray(p, dtype=float)[:2])
        return self.excess(self.network.roads[rid], np.asarray(p, dtype=float)[:2])[2]
