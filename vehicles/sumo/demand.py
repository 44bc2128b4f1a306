"""Traffic demand for SUMO: a pool of N random trips kept full, and flows between given roads.

Trips. At the start N vehicles are inserted at random free positions on random edges (the network is full at once,
no ramp-up); each later arrival is replaced by a new trip departing at the start of a random edge. Origins and
destinations are drawn from skytrack's own :class:`numpy.random.Generator` (spawned from the run's seed); the route is
SUMO's fastest path between them (``simulation.findRoute``). Insertion positions, speeds and driver imperfection come
from SUMO's own generator, seeded with ``--seed``. So the number of vehicles on the road stays near N (below it only
while a new trip waits for room to enter), and one seed gives one run.

Flows. A :class:`Flow` sends vehicles from the start of one road to the end of another along SUMO's fastest route
between them (through the roads ``via``, in order, if given), departing as a Poisson process of ``per_hour``
vehicles an hour within ``[begin_s, end_s)``: at each SUMO step the number of departures over the step's overlap with
that window is drawn from the same generator (Poisson, mean ``per_hour / 3600 · overlap``), so a count over T seconds
is Poisson with mean ``per_hour · T / 3600``.
The flows share the scene slots the trips leave (``capacity``); a departure that would need more is refused and
counted (:attr:`FlowStreams.refused`; the source records a ``traffic_flow_refused`` event), never queued unseen.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import ModuleType

import numpy as np

__all__ = ["DemandConfig", "Flow", "FlowStreams", "TripPool"]


@dataclass(frozen=True, kw_only=True)
class Flow:
    """A stream of vehicles between two roads (see the module docstring).

    Attributes
    ----------
    origin, destination : str
        skytrack road ids: departures at the start of ``origin``, arrivals at the end of ``destination``.
    via : tuple[str, ...]
        Road ids the route passes, in order (SUMO's fastest route from each to the next).
    per_hour : float
        Mean departures per hour (> 0).
    begin_s, end_s : float
        Simulated seconds within which vehicles depart, ``0 <= begin_s < end_s`` (``end_s`` may be inf).
    """

    origin: str
    destination: str
    per_hour: float
    begin_s: float = 0.0
    end_s: float = math.inf
    via: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "via", tuple(self.via))
        if not (math.isfinite(self.per_hour) and self.per_hour > 0):
            raise ValueError(f"Flow.per_hour must be finite and > 0, got {self.per_hour!r}")
        if not (math.isfinite(self.begin_s) and 0 <= self.begin_s < self.end_s):
            raise ValueError(f"Flow: 0 <= begin_s < end_s required, got begin_s {self.begin_s!r}, end_s "
                             f"{self.end_s!r}")

    def expected(self, t0: float, t1: float) -> float:
        """Mean departures in simulated seconds ``[t0, t1)``."""
        overlap = max(0.0, min(t1, self.end_s) - max(t0, self.begin_s))
        return self.per_hour / 3600.0 * overlap


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
    flows : tuple[Flow, ...]
        Flows besides the trips (departures at ``depart_pos``, ``depart_lane``, ``depart_speed``).
    """

    initial_depart_pos: str = "random_free"
    depart_pos: str = "base"
    depart_lane: str = "best"
    depart_speed: str = "desired"
    min_route_edges: int = 2
    max_draws: int = 50
    flows: tuple[Flow, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "flows", tuple(self.flows))
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


class FlowStreams:
    """Inserts the vehicles of :class:`Flow` s into a running libsumo simulation (see the module docstring).

    Parameters
    ----------
    lib : module
        The started libsumo module.
    flows : Sequence[Flow]
        The flows.
    road_to_edge : Mapping[str, str]
        skytrack road id -> SUMO edge id.
    rng : numpy.random.Generator
        Draws the departures.
    type_id : str
        SUMO vehicle type.
    config : DemandConfig
        Insertion settings.
    capacity : int
        Most flow vehicles in SUMO at once (on the road or waiting to enter): the scene slots the trips leave.
    prefix : str
        Vehicle ids are ``f"{prefix}{k}_{j}"`` (flow k, its j-th vehicle), route ids ``f"{prefix}r{k}"``.

    Raises
    ------
    ValueError
        A flow's road is not in the network, or SUMO finds no route from its origin to its destination.
    """

    def __init__(self, lib: ModuleType, flows: Sequence[Flow], road_to_edge: Mapping[str, str],
                 rng: np.random.Generator, type_id: str, config: DemandConfig, capacity: int,
                 prefix: str = "f") -> None:
        if capacity < 0:
            raise ValueError(f"FlowStreams: capacity must be >= 0, got {capacity}")
        self._lib, self._rng, self.flows = lib, rng, list(flows)
        self.type_id, self.config, self.capacity, self.prefix = type_id, config, int(capacity), prefix
        self.departed = [0] * len(self.flows)
        self.refused = [0] * len(self.flows)
        self.alive: set[str] = set()
        for k, f in enumerate(self.flows):
            stops = [("origin", f.origin), *(("via", r) for r in f.via), ("destination", f.destination)]
            for what, road in stops:
                if road not in road_to_edge:
                    raise ValueError(f"flow {k}: {what} {road!r} is not a road of the network")
            edges = [road_to_edge[f.origin]]
            for (_, a), (_, b) in zip(stops, stops[1:], strict=False):  # the fastest route between consecutive roads
                leg = list(lib.simulation.findRoute(road_to_edge[a], road_to_edge[b], vType=type_id).edges)
                if a != b and not leg:
                    raise ValueError(f"flow {k}: no route from {a!r} to {b!r}")
                edges += leg[1:]
            lib.route.add(f"{prefix}r{k}", edges)

    def owns(self, vehicle_id: str) -> bool:
        """True when ``vehicle_id`` is one of the flows' vehicles."""
        return vehicle_id.startswith(self.prefix)

    def arrived(self, vehicle_id: str) -> None:
        """``vehicle_id`` left SUMO: its room is free again."""
        self.alive.discard(vehicle_id)

    def depart(self, t0: float, t1: float) -> list[int]:
        """Insert the departures of simulated seconds ``[t0, t1)``; the flow index of each refused one."""
        cfg, refused = self.config, []
        for k, f in enumerate(self.flows):
            mean = f.expected(t0, t1)
            for _ in range(int(self._rng.poisson(mean)) if mean > 0 else 0):
                if len(self.alive) >= self.capacity:
                    self.refused[k] += 1
                    refused.append(k)
                    continue
                vid = f"{self.prefix}{k}_{self.departed[k]}"
                self.departed[k] += 1
                self._lib.vehicle.add(vid, f"{self.prefix}r{k}", typeID=self.type_id, depart="now",
                                      departLane=cfg.depart_lane, departPos=cfg.depart_pos,
                                      departSpeed=cfg.depart_speed)
                self.alive.add(vid)
        return refused
