"""Background traffic generated on a world's roads (the world file's ``traffic:`` section, :class:`TrafficSpec`).

:func:`with_traffic` adds ``traffic.cars`` ground vehicles of role traffic to a world once its road network is built:
each starts at a seeded random point of the network (a road drawn with probability proportional to its length, a
point uniform along it, on the rightmost lane) at least ``min_spacing_m`` from every other car's start, and drives a
seeded random walk from there. Kinematic dynamics, so the compiled built-in fleet steps them. With ``engine: sumo``
the entries only name SUMO's slots (the car fleet hands them to SUMO, which places and routes its vehicles).
"""

from __future__ import annotations

import numpy as np

from worlds.roads.network import RoadNetwork
from worlds.schema import GroundVehicleSpec, World

__all__ = ["TrafficPlacementError", "start_point", "with_traffic"]

_END_MARGIN = 5.0  # m kept free at each end of a road: no car starts inside a junction
_TRIES_PER_CAR = 50


class TrafficPlacementError(ValueError):
    """The network has no room for the requested traffic."""


def start_point(network: RoadNetwork, road_id: str, s: float, lane: int = 0) -> np.ndarray:
    """(2,) start position (m) of a car at arc length ``s`` on ``lane`` of road ``road_id``."""
    road = network.roads[road_id]
    return np.asarray(road.point(min(max(s, 0.0), road.length), road.lane_offset(lane)), dtype=float)


def with_traffic(world: World, network: RoadNetwork, rng: np.random.Generator) -> World:
    """``world`` with its ``traffic.cars`` generated cars appended to ``ground_vehicles`` (``world`` itself when it
    asks for none).

    Raises
    ------
    TrafficPlacementError
        When the roads cannot hold that many cars ``min_spacing_m`` apart (the message says how many fit).
    """
    spec = world.traffic
    if spec.cars == 0:
        return world
    taken = {g.id for g in world.ground_vehicles}
    ids = [f"{spec.id_prefix}{k + 1}" for k in range(spec.cars)]
    clash = sorted(taken.intersection(ids))
    if clash:
        raise TrafficPlacementError(f"traffic.id_prefix {spec.id_prefix!r} gives ids the world already uses: "
                                    f"{clash[:5]}")
    if spec.engine == "sumo":  # slots: SUMO places and routes its vehicles; the entries name the slots
        first = next(iter(network.roads))
        slots = [GroundVehicleSpec(id=ids[k], type=spec.types[0], colour=spec.colours[k % len(spec.colours)],
                                   role="traffic", dynamics="kinematic", route={"random_walk_from": first})
                 for k in range(spec.cars)]
        return world.model_copy(update={"ground_vehicles": [*world.ground_vehicles, *slots]})
    roads = [r for r in network.roads.values() if r.length > 2 * _END_MARGIN]
    if not roads:
        raise TrafficPlacementError(f"traffic.cars = {spec.cars}: the network has no road longer than "
                                    f"{2 * _END_MARGIN:g} m to start a car on")
    lengths = np.array([r.length - 2 * _END_MARGIN for r in roads])
    prob = lengths / lengths.sum()
    grid = _Grid(spec.min_spacing_m)
    for g in world.ground_vehicles:
        grid.add(start_point(network, g.route.roads[0] if g.route.roads else g.route.random_walk_from,
                             g.route.start_s, g.route.lane))
    cars = []
    driver = spec.driver.model_dump(exclude_unset=True) | {"rate_hz": spec.rate_hz}
    for k in range(spec.cars):
        for _ in range(_TRIES_PER_CAR):
            q = int(rng.choice(len(roads), p=prob))
            s = _END_MARGIN + float(rng.uniform(0.0, lengths[q]))
            xy = start_point(network, roads[q].id, s)
            if not grid.near(xy):
                break
        else:
            raise TrafficPlacementError(
                f"traffic.cars = {spec.cars}: placed {k} cars {spec.min_spacing_m:g} m apart on the "
                f"{lengths.sum() / 1000:.1f} km of roads and found no room for more after {_TRIES_PER_CAR} tries; ask "
                "for fewer cars or a smaller traffic.min_spacing_m")
        grid.add(xy)
        cars.append(GroundVehicleSpec(
            id=ids[k], type=spec.types[k % len(spec.types)], colour=spec.colours[k % len(spec.colours)],
            role="traffic", dynamics="kinematic", driver=driver,
            route={"random_walk_from": roads[q].id, "start_s": round(s, 3)}))
    return world.model_copy(update={"ground_vehicles": [*world.ground_vehicles, *cars]})


class _Grid:
    """Points on a uniform grid of cell ``r``: is a new point within ``r`` of one of them?"""

    def __init__(self, r: float) -> None:
        self.r = float(r)
        self.cells: dict[tuple[int, int], list[np.ndarray]] = {}

    def _cell(self, xy: np.ndarray) -> tuple[int, int]:
        return int(np.floor(xy[0] / self.r)), int(np.floor(xy[1] / self.r))

    def add(self, xy: np.ndarray) -> None:
        self.cells.setdefault(self._cell(xy), []).append(np.asarray(xy, dtype=float))

    def near(self, xy: np.ndarray) -> bool:
        cx, cy = self._cell(xy)
        return any(float(np.hypot(*(q - xy))) < self.r
                   for dx in (-1, 0, 1) for dy in (-1, 0, 1) for q in self.cells.get((cx + dx, cy + dy), ()))
