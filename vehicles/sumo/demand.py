"""Traffic demand for SUMO: a pool of N random trips kept full, one new trip for every vehicle that arrives.

At the start N vehicles are inserted at random free positions on random edges (the network is full at once, no
ramp-up); each later arrival is replaced by a new trip departing at the start of a random edge. Origins and
destinations are drawn from skytrack's own :class:`numpy.random.Generator` (spawned from the run's seed); the route is
SUMO's fastest path between them (``simulation.findRoute``). Insertion positions, speeds and driver imperfection come
from SUMO's own generator, seeded with ``--seed``. So the number of vehicles on the road stays near N (below it only
while a new trip waits for room to enter), and one seed gives one run.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType

import numpy as np

__all__ = ["DemandConfig", "TripPool"]


@dataclass(frozen=True, kw_only=True)
class DemandConfig:
    """How the trip pool inserts vehicles.

    Attributes
    ----------
    initial_depart_pos : str
        SUMO ``departPos`` of the first N vehicles (``"random_free"``: spread over their first edge).
    depart_pos : str
        SUMO ``departPos`` of the replacement trips (``"base"``: the start of the edge).
    depart_lane : str
        SUMO ``departLane`` (``"best"``: the lane that suits the route).
    depart_speed : str
        SUMO ``departSpeed`` (``"desired"``: the vehicle's desired speed on that edge, if safe).
    min_route_edges : int
        Shortest route accepted for a trip (edges); shorter draws are drawn again.
    max_draws : int
        Draws of an origin-destination pair before a trip is given up (a network with unreachable parts).
    """

    initial_depart_pos: str = "random_free"
    depart_pos: str = "base"
    depart_lane: str = "best"
    depart_speed: str = "desired"
    min_route_edges: int = 2
    max_draws: int = 50

    def __post_init__(self) -> None:
        if self.min_route_edges < 1:
            raise ValueError(f"DemandConfig.min_route_edges must be >= 1, got {self.min_route_edges}")
        if self.max_draws < 1:
            raise ValueError(f"DemandConfig.max_draws must be >= 1, got {self.max_draws}")


class TripPool:
    """Inserts random trips into a running libsumo simulation.

    Parameters
    ----------
    lib : module
        The started libsumo module.
    edges : list[str]
        SUMO edge ids trips may start and end on.
    rng : numpy.random.Generator
        Draws the origins and destinations.
    type_id : str
        SUMO vehicle type of the trips.
    config : DemandConfig
        Insertion settings.
    prefix : str
        Vehicle ids are ``f"{prefix}{k}"`` and route ids ``f"{prefix}r{k}"``, k counting from 0.
    """

    def __init__(self, lib: ModuleType, edges: list[str], rng: np.random.Generator, type_id: str,
                 config: DemandConfig, prefix: str = "t") -> None:
        if len(edges) < 2:
            raise ValueError(f"TripPool: the network needs at least 2 edges for trips, got {len(edges)}")
        self._lib, self._edges, self._rng = lib, list(edges), rng
        self.type_id, self.config, self.prefix = type_id, config, prefix
        self.count = 0
        self.given_up = 0

    def owns(self, vehicle_id: str) -> bool:
        """True when ``vehicle_id`` is one of this pool's trips."""
        return vehicle_id.startswith(self.prefix)

    def add(self, n: int, *, initial: bool = False) -> None:
        """Insert ``n`` new trips departing now (``initial``: at random free positions, else at edge starts)."""
        cfg = self.config
        pos = cfg.initial_depart_pos if initial else cfg.depart_pos
        for _ in range(n):
            edges = self._draw_route()
            if edges is None:
                self.given_up += 1
                continue
            vid, rid = f"{self.prefix}{self.count}", f"{self.prefix}r{self.count}"
            self.count += 1
            self._lib.route.add(rid, edges)
            self._lib.vehicle.add(vid, rid, typeID=self.type_id, depart="now", departLane=cfg.depart_lane,
                                  departPos=pos, departSpeed=cfg.depart_speed)

    def _draw_route(self) -> list[str] | None:
        """Edges of the fastest route between a random origin and a random other destination edge."""
        n = len(self._edges)
        for _ in range(self.config.max_draws):
            a, b = (int(k) for k in self._rng.integers(n, size=2))
            if a == b:
                continue
            edges = list(self._lib.simulation.findRoute(self._edges[a], self._edges[b], vType=self.type_id).edges)
            if len(edges) >= self.config.min_route_edges:
                return edges
        return None
