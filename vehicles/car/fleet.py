"""A fleet of cars driven along roads: the run loop's view of all ground vehicles.

Per tick the run loop calls ``apply_actuation()``, ``p.stepSimulation()``, ``after_step(tick)``. Actuation hands each
driver's last :class:`~vehicles.car.driver_config.DriveCommand` to the car's dynamics (:mod:`vehicles.car.dynamics`):
motor targets of a physics car's multibody, or one step of a kinematic car's bicycle model and the placing of its box.
After the step the fleet reads every car's state and runs the drivers due at that tick, with the leaders found among
all cars, so physics and kinematic cars drive in one traffic.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vehicles.car.driver import Driver
from vehicles.car.driver_config import DriverConfig
from vehicles.car.dynamics import make_dynamics
from vehicles.car.params import CarParams
from vehicles.car.road_protocol import NetworkLike
from vehicles.car.route import Route
from vehicles.car.traffic import find_leaders

__all__ = ["CarFleet", "CarState"]


@dataclass(frozen=True, kw_only=True)
class CarState:
    """Ground truth of all cars after a physics step.

    Attributes
    ----------
    tick : int
        Physics tick of the state.
    p_W : np.ndarray
        (N, 3) centre-of-mass positions, world ENU (m).
    q_WB : np.ndarray
        (N, 4) body-to-world quaternions (x, y, z, w).
    v_W : np.ndarray
        (N, 3) velocities (m/s).
    a_W : np.ndarray
        (N, 3) accelerations, finite difference of v_W over one physics step (m/s^2).
    yaw : np.ndarray
        (N,) headings (rad).
    speed : np.ndarray
        (N,) forward speeds v_W . x_B (m/s).
    road_id : list[str]
        Road each car is on.
    s : np.ndarray
        (N,) arc length on that road (m).
    lateral : np.ndarray
        (N,) offset from the road's centre-line, positive left of travel (m).
    stopped : np.ndarray
        (N,) True while standing at a junction or at the end of the route.
    """

    tick: int
    p_W: np.ndarray
    q_WB: np.ndarray
    v_W: np.ndarray
    a_W: np.ndarray
    yaw: np.ndarray
    speed: np.ndarray
    road_id: list[str]
    s: np.ndarray
    lateral: np.ndarray
    stopped: np.ndarray


@dataclass(frozen=True)
class _Arrays:
    """One reading of all cars as arrays (rows per car; see :class:`CarState`)."""

    p_W: np.ndarray
    q_WB: np.ndarray
    v_W: np.ndarray
    omega_z: np.ndarray
    a_W: np.ndarray
    yaw: np.ndarray
    speed: np.ndarray


class CarFleet:
    """Cars, their drivers and their actuation.

    Parameters
    ----------
    client_id : int
        PyBullet client (gravity, time step 1 / physics_hz and a ground plane are the caller's).
    params, drivers, routes : Sequence
        One :class:`CarParams`, :class:`DriverConfig` and :class:`Route` per car; each car spawns at rest on its lane
        centre at ``route.start_s`` of its first road.
    network : NetworkLike
        Road graph.
    physics_hz : int
        Physics rate (Hz); every driver's ``rate_hz`` must divide it.
    rng : np.random.Generator
        Spawned into one child generator per car.
    dynamics : Sequence[str] | None
        How each car moves, a key of :data:`vehicles.car.dynamics.CAR_DYNAMICS` (``"physics"``: PyBullet multibody;
        ``"kinematic"``: kinematic bicycle carrying a box); None = all ``"physics"``.
    """

    def __init__(self, client_id: int, params: Sequence[CarParams], drivers: Sequence[DriverConfig],
                 routes: Sequence[Route], network: NetworkLike, physics_hz: int, rng: np.random.Generator,
                 dynamics: Sequence[str] | None = None) -> None:
        n = len(params)
        dynamics = ["physics"] * n if dynamics is None else list(dynamics)
        if not (len(drivers) == n == len(routes) == len(dynamics)) or n == 0:
            raise ValueError(f"CarFleet needs one params, driver config, route and dynamics per car, got "
                             f"{len(params)}/{len(drivers)}/{len(routes)}/{len(dynamics)}")
        self.client_id, self.physics_hz, self.params = client_id, int(physics_hz), list(params)
        self._every = [cfg.ticks_per_update(physics_hz) for cfg in drivers]
        self.drivers = [Driver(config=cfg, params=par, route=rt, network=network, rng=g, physics_hz=physics_hz)
                        for cfg, par, rt, g in zip(drivers, params, routes, rng.spawn(n), strict=True)]
        spawns = [d.spawn_pose() for d in self.drivers]
        self._check_spawns(spawns)
        self.dynamics = [make_dynamics(kind, client_id, par, xy, yaw, self.physics_hz)
                         for kind, par, (xy, yaw) in zip(dynamics, params, spawns, strict=True)]
        self.body_ids = np.array([d.body_id for d in self.dynamics], dtype=int)
        self._lengths = [par.length for par in params]
        self._events: list[dict] = []
        self._off_road = np.zeros(n, dtype=bool)
        self._tick = 0
        self._rows: list[tuple[float, ...]] = []
        self._prev_rows: list[tuple[float, ...]] | None = None  # None: no step yet (a_W = 0)
        self._read()
        self._prev_rows = None
        self._every_gcd = math.gcd(*self._every)
        self._cache: CarState | None = None

    def _check_spawns(self, spawns: list[tuple[np.ndarray, float]]) -> None:
        for i in range(len(spawns)):
            for j in range(i):
                gap = float(np.linalg.norm(spawns[i][0] - spawns[j][0]))
                need = 0.5 * (self.params[i].length + self.params[j].length)
                if gap < need:
                    raise ValueError(f"CarFleet: cars {j} and {i} spawn {gap:.2f} m apart, closer than their half "
                                     f"lengths {need:.2f} m; separate their Route.start_s")

    def _read(self) -> None:
        """Read every car's state row; the arrays are made from the rows when first needed (:meth:`_arrays`)."""
        self._prev_rows, self._rows = self._rows, [d.state_row() for d in self.dynamics]
        self._arr: _Arrays | None = None

    def _arrays(self) -> _Arrays:
        """The last rows as arrays, with the heading and forward speed of each car and its acceleration, the finite
        difference of v_W over the last physics step."""
        if self._arr is None:
            rows = self._rows
            x = np.array(rows)
            # heading and forward speed per car in scalar math: a handful of cars
            yaw = [math.atan2(2 * (r[6] * r[5] + r[3] * r[4]), 1 - 2 * (r[4] * r[4] + r[5] * r[5])) for r in rows]
            speed = np.array([r[7] * math.cos(h) + r[8] * math.sin(h) for r, h in zip(rows, yaw, strict=True)])
            v_W = x[:, 7:10]
            a_W = (np.zeros_like(v_W) if self._prev_rows is None
                   else (v_W - np.array(self._prev_rows)[:, 7:10]) * self.physics_hz)
            self._arr = _Arrays(p_W=x[:, 0:3], q_WB=x[:, 3:7], v_W=v_W, omega_z=x[:, 12], a_W=a_W,
                                yaw=np.array(yaw), speed=speed)
        return self._arr

    def apply_actuation(self) -> None:
        """Run-loop phase 1: each car's dynamics acts on its driver's last command."""
        for drv, dyn in zip(self.drivers, self.dynamics, strict=True):
            dyn.actuate(drv.command)

    def after_step(self, tick: int) -> None:
        """After ``p.stepSimulation()``: read the cars' state and run the drivers due at ``tick``."""
        self._read()
        self._tick = tick
        self._cache = None
        if tick % self._every_gcd:
            return
        due = [i for i, e in enumerate(self._every) if tick % e == 0]
        if not due:
            return
        x = self._arrays()
        leaders = find_leaders(self.drivers, x.p_W[:, :2], x.yaw, x.speed, self._lengths)
        for i in due:
            drv = self.drivers[i]
            drv.update(x.p_W[i, :2], float(x.yaw[i]), float(x.speed[i]), tick, leaders[i], float(x.omega_z[i]))
            self.dynamics[i].on_driver_update(float(x.speed[i]))
            self._events += [dict(e, car=i) for e in drv.pop_events()]
            self._check_road(i, tick)

    def _check_road(self, i: int, tick: int) -> None:
        """Events when a car's centre leaves the street (|lateral| > lanes x lane_width) or comes back."""
        drv = self.drivers[i]
        road_id, s, lateral = drv.road_position()  # where the update just projected the car
        road = drv.network.roads[road_id]
        off = abs(lateral) > road.lanes * road.lane_width
        if off != self._off_road[i]:
            self._off_road[i] = off
            self._events.append({"type": "car_left_road" if off else "car_back_on_road", "car": i, "tick": tick,
                                 "road": road_id, "s": s, "lateral": lateral})

    @property
    def state(self) -> CarState:
        """Ground truth after the last ``after_step``."""
        if self._cache is None:
            x = self._arrays()
            located = [d.locate(x.p_W[i, :2]) for i, d in enumerate(self.drivers)]
            self._cache = CarState(
                tick=self._tick, p_W=x.p_W.copy(), q_WB=x.q_WB.copy(), v_W=x.v_W.copy(), a_W=x.a_W.copy(),
                yaw=x.yaw.copy(), speed=x.speed.copy(),
                road_id=[r[0] for r in located], s=np.array([r[1] for r in located]),
                lateral=np.array([r[2] for r in located]), stopped=np.array([d.stopped for d in self.drivers]))
        return self._cache

    def pop_events(self) -> list[dict]:
        """Events since the last call: ``car_stop``, ``car_go``, ``car_enter_road``, ``car_route_end``,
        ``car_left_road``, ``car_back_on_road``; each has ``type``, ``car`` (index) and ``tick``."""
        ev, self._events = self._events, []
        return ev

    def __len__(self) -> int:
        return len(self.drivers)
