"""Routes of cars over a road network: a fixed list of road ids, or a seeded random walk extended on demand."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vehicles.car.road_protocol import NetworkLike

__all__ = ["Route", "RoutePlan"]


@dataclass(frozen=True, kw_only=True)
class Route:
    """Where one car drives.

    Attributes
    ----------
    roads : tuple[str, ...]
        Fixed route: consecutive road ids. Empty for a random walk.
    random_walk : bool
        Drive a seeded random walk over the network from ``start_road`` (the network's ``random_route``,
        extended whenever fewer than a few roads remain ahead).
    start_road : str | None
        First road of a random walk (ignored for a fixed route, whose first road is ``roads[0]``).
    start_s : float
        Spawn arc length on the first road (m), >= 0.
    lane : int
        Lane to drive in (0 = rightmost), clipped to each road's lane count.
    stops : tuple[str, ...] | None
        Node ids of the junctions to stop at. None: stop at each junction with the driver's ``stop_probability``.
    """

    roads: tuple[str, ...] = ()
    random_walk: bool = False
    start_road: str | None = None
    start_s: float = 0.0
    lane: int = 0
    stops: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "roads", tuple(self.roads))
        if self.random_walk:
            if self.start_road is None:
                raise ValueError("Route.start_road is required for a random walk, got None")
            if self.roads:
                raise ValueError(f"Route.roads must be empty for a random walk, got {self.roads}")
        elif not self.roads:
            raise ValueError("Route.roads must list at least one road id (or set random_walk=True), got ()")
        if not (math.isfinite(self.start_s) and self.start_s >= 0):
            raise ValueError(f"Route.start_s must be >= 0 m, got {self.start_s}")
        if self.lane < 0:
            raise ValueError(f"Route.lane must be >= 0, got {self.lane}")
        if self.stops is not None:
            object.__setattr__(self, "stops", tuple(self.stops))

    @property
    def first_road(self) -> str:
        """Id of the road the car spawns on."""
        return self.roads[0] if self.roads else str(self.start_road)


class RoutePlan:
    """The roads a car still has to drive, with a stop decision for the junction at the end of each.

    Parameters
    ----------
    route : Route
        The route.
    network : NetworkLike
        Road graph (only ``roads`` and ``random_route`` are used).
    stop_probability : float
        Probability of stopping at a junction when ``route.stops`` is None.
    chunk : int
        Number of roads asked from ``random_route`` per extension.
    rng : np.random.Generator
        Source of the random walk and of the stop draws.
    """

    def __init__(self, route: Route, network: NetworkLike, stop_probability: float, chunk: int,
                 rng: np.random.Generator) -> None:
        self.route = route
        self.network = network
        self.stop_probability = stop_probability
        self.chunk = chunk
        self.rng = rng
        self.road_ids: list[str] = []
        self.stop_flags: list[bool] = []
        self.finite = not route.random_walk
        for rid in route.roads:
            if rid not in network.roads:
                raise ValueError(f"Route.roads: unknown road id {rid!r}")
        if route.first_road not in network.roads:
            raise ValueError(f"Route.start_road: unknown road id {route.first_road!r}")
        self._append(list(route.roads) if route.roads else [route.first_road])
        if route.random_walk:
            self.extend()

    def _append(self, ids: list[str]) -> None:
        for rid in ids:
            if self.road_ids:
                prev = self.network.roads[self.road_ids[-1]]
                if prev.end_node != self.network.roads[rid].start_node:
                    raise ValueError(f"Route.roads: road {rid!r} does not start where {prev.id!r} ends")
            node = self.network.roads[rid].end_node
            if self.route.stops is not None:
                flag = node in self.route.stops
            else:
                flag = bool(self.rng.random() < self.stop_probability)
            self.road_ids.append(rid)
            self.stop_flags.append(flag)

    def extend(self) -> bool:
        """Append roads of a random walk from the last road; False when the walk reaches a dead end."""
        if self.finite:
            return False
        last = self.road_ids[-1]
        ids = list(self.network.random_route(last, self.chunk + 1, self.rng))
        if ids and ids[0] == last:
            ids = ids[1:]
        if not ids:
            self.finite = True
            return False
        self._append(ids)
        return True

    def advance(self, n: int = 1) -> None:
        """Drop the first ``n`` roads (driven)."""
        del self.road_ids[:n]
        del self.stop_flags[:n]

    def clear_stop(self, k: int) -> None:
        """Mark the junction at the end of planned road ``k`` as served."""
        self.stop_flags[k] = False
