"""A fleet of cars driven along roads: the run loop's view of all ground vehicles.

Per tick the run loop calls ``apply_actuation()``, ``p.stepSimulation()``, ``after_step(tick)``. Actuation hands each
physics car's driver's last :class:`~vehicles.car.driver_config.DriveCommand` to its multibody
(:mod:`vehicles.car.dynamics`). After the step the fleet reads the physics cars' state and runs their drivers due at
that tick; the kinematic cars step in a compiled :class:`~vehicles.car.traffic_fleet.TrafficFleet` at their drivers'
rate, which keeps every physics tick of their bicycle models and places their boxes in the scene only when something
looks (:meth:`CarFleet.sync_scene` before sensors and cameras, and the boxes near a UAV or a physics car before each
physics step). Leaders are found among all cars, so physics and kinematic cars drive in one traffic.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pybullet as p
from scipy.spatial import cKDTree

from vehicles.car.driver import Driver
from vehicles.car.driver_config import DriverConfig
from vehicles.car.dynamics import CAR_DYNAMICS, make_dynamics
from vehicles.car.params import CarParams
from vehicles.car.road_protocol import NetworkLike
from vehicles.car.route import Route
from vehicles.car.traffic import find_leaders
from vehicles.car.traffic_fleet import TrafficFleet
from vehicles.car.traffic_kernel import R_OMEGA, R_VFWD, R_VX, R_VY, R_X, R_Y, R_YAW, R_YAWREAD
from vehicles.car.traffic_source import OtherCars, TrafficSource

__all__ = ["CarFleet", "CarState", "SYNC_RADIUS"]

SYNC_RADIUS = 15.0
"""m: a kinematic car's box within this distance of a UAV or a physics car is placed before every physics step (a box
nearer than a car length plus a UAV's size is the most a contact can involve; the rest wait for a sensor)."""


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
        (N, 3) accelerations, finite difference of v_W over one physics step (m/s^2); 0 for an external traffic
        source's slots.
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
    active : np.ndarray | None
        (N,) True for a car on the road; False for a traffic source's slot holding no vehicle now (its body parked out
        of sight, its row to be ignored). None: every car is active.
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
    active: np.ndarray | None = None


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
    active: np.ndarray


class CarFleet:
    """Cars, their drivers and their actuation.

    Physics cars step their drivers and multibodies here, at the physics rate; kinematic cars are handed to a
    compiled :class:`~vehicles.car.traffic_fleet.TrafficFleet` (one per driver rate) that steps them together and
    places their boxes lazily (:meth:`sync_scene`, and before each physics step the boxes near :attr:`near_points`).
    Car following sees every car, of either kind, both ways.

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
    sources : Sequence[TrafficSource]
        External traffic (SUMO co-simulation, :mod:`vehicles.sumo`): each source's slots are cars after the listed
        ones, in order; the source steps them, the physics cars' drivers follow its active vehicles and it hears
        where the physics cars are.

    Attributes
    ----------
    near_points : Callable[[], np.ndarray] | None
        Where the run's other dynamic bodies are ((K, 3) m: the UAVs); each physics step first places the kinematic
        cars' boxes within :data:`SYNC_RADIUS` of them or of a physics car. A body more than :data:`SYNC_RADIUS`
        above the top of the highest box (a UAV at its cruise altitude) is within that distance of none, and places
        none. None: the physics cars only.
    """

    def __init__(self, client_id: int, params: Sequence[CarParams], drivers: Sequence[DriverConfig],
                 routes: Sequence[Route], network: NetworkLike, physics_hz: int, rng: np.random.Generator,
                 dynamics: Sequence[str] | None = None, sources: Sequence[TrafficSource] = ()) -> None:
        n = len(params)
        dynamics = ["physics"] * n if dynamics is None else list(dynamics)
        if not (len(drivers) == n == len(routes) == len(dynamics)) or (n == 0 and not sources):
            raise ValueError(f"CarFleet needs one params, driver config, route and dynamics per car, got "
                             f"{len(params)}/{len(drivers)}/{len(routes)}/{len(dynamics)}")
        for kind in dynamics:
            if kind not in CAR_DYNAMICS:
                raise ValueError(f"car dynamics must be one of {sorted(CAR_DYNAMICS)}, got {kind!r}")
        self.client_id, self.physics_hz, self.params = client_id, int(physics_hz), list(params)
        self._every = [cfg.ticks_per_update(physics_hz) for cfg in drivers]
        self.drivers = [Driver(config=cfg, params=par, route=rt, network=network, rng=g, physics_hz=physics_hz)
                        for cfg, par, rt, g in zip(drivers, params, routes, rng.spawn(n), strict=True)]
        spawns = [d.spawn_pose() for d in self.drivers]
        self._check_spawns(spawns)
        self._phys = [i for i in range(n) if dynamics[i] == "physics"]
        self.dynamics = {i: make_dynamics("physics", client_id, params[i], *spawns[i], self.physics_hz)
                         for i in self._phys}
        self.traffic: list[tuple[np.ndarray, TrafficFleet]] = []  # (world indices, fleet) per driver rate
        kin = [i for i in range(n) if dynamics[i] == "kinematic"]
        for rate in sorted({drivers[i].rate_hz for i in kin}):
            idx = np.array([i for i in kin if drivers[i].rate_hz == rate], dtype=int)
            fleet = TrafficFleet(client_id, [self.drivers[i] for i in idx], [params[i] for i in idx],
                                 [f"car{i}" for i in idx], physics_hz)
            self.traffic.append((idx, fleet))
        self.sources: list[tuple[np.ndarray, TrafficSource]] = []
        start = n
        for src in sources:
            self.sources.append((np.arange(start, start + len(src.ids)), src))
            start += len(src.ids)
        self._kinematic = [fleet for _, fleet in [*self.traffic, *self.sources]]  # what moves boxes lazily
        lights = next((src.signal for src in sources if hasattr(src, "signal")), None)
        for i in self._phys:  # physics cars stop at the source's traffic lights (kinematic ones step compiled)
            self.drivers[i].signal = lights
        self._n = start
        body = np.zeros(start, dtype=int)
        for i, dyn in self.dynamics.items():
            body[i] = dyn.body_id
        for idx, fleet in self.traffic:
            body[idx] = fleet.body_ids
        for idx, src in self.sources:
            body[idx] = src.body_ids
        self.body_ids = body
        self._lengths = [par.length for par in params] + [float(x) for _, src in self.sources for x in src.lengths]
        self._length_arr = np.array(self._lengths)
        self._events: list[tuple[int, dict]] = []
        self._off_road = np.zeros(n, dtype=bool)
        self._tick = 0
        self._every_gcd = math.gcd(*(self._every[i] for i in self._phys)) if self._phys else 0
        self._rows: list[tuple[float, ...]] = []
        self._prev_rows: list[tuple[float, ...]] | None = None  # None: no step yet (a_W = 0)
        self._read()
        self._prev_rows = None
        self._cache: CarState | None = None
        self.near_points: Callable[[], np.ndarray] | None = None
        self._near_ceiling = self._box_top() + SYNC_RADIUS  # m: no box is within reach of a body above it

    def _box_top(self) -> float:
        """The highest any kinematic car's box reaches (m): over each box, the top of its shape above its centre of
        mass (PyBullet's bounding box) plus the height its centre of mass is placed at (``ground_z``); -inf
        without kinematic cars."""
        top = -np.inf
        for _, fleet in [*self.traffic, *self.sources]:
            for body, z in zip(fleet.body_ids.tolist(), np.asarray(fleet.ground_z, dtype=float).tolist(), strict=True):
                base = p.getBasePositionAndOrientation(body, physicsClientId=self.client_id)[0][2]
                top = max(top, z + p.getAABB(body, physicsClientId=self.client_id)[1][2] - base)
        return top

    def _check_spawns(self, spawns: list[tuple[np.ndarray, float]]) -> None:
        if len(spawns) < 2:
            return
        xy = np.array([xy for xy, _ in spawns])
        half = 0.5 * np.array([par.length for par in self.params])
        tree = cKDTree(xy)
        for i, j in sorted(tree.query_pairs(2 * float(half.max()))):  # every pair closer than the longest car
            gap = float(np.linalg.norm(xy[j] - xy[i]))
            need = half[i] + half[j]
            if gap < need:
                raise ValueError(f"CarFleet: cars {i} and {j} spawn {gap:.2f} m apart, closer than their half "
                                 f"lengths {need:.2f} m; separate their Route.start_s")

    def _read(self) -> None:
        """Read every physics car's state row; the arrays of all cars are made when first needed (:meth:`_arrays`)."""
        self._prev_rows, self._rows = self._rows, [self.dynamics[i].state_row() for i in self._phys]
        self._arr: _Arrays | None = None
        self._mot: tuple[np.ndarray, ...] | None = None
        self._phys_x: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def _phys_readings(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The physics cars' rows of the last tick as an array, with their headings (from the quaternion) and forward
        speeds, in scalar math (a handful of cars); kept until the next read."""
        if self._phys_x is None:
            rows = self._rows
            h = [math.atan2(2 * (r[6] * r[5] + r[3] * r[4]), 1 - 2 * (r[4] * r[4] + r[5] * r[5])) for r in rows]
            v = [r[7] * math.cos(hh) + r[8] * math.sin(hh) for r, hh in zip(rows, h, strict=True)]
            self._phys_x = (np.array(rows), np.array(h), np.array(v))
        return self._phys_x

    def _motion(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(xy, heading, forward speed, yaw rate, active) of every car at the last tick, kept until the next read: what
        the physics cars' drivers read at their steps, without the rest of :meth:`_arrays` (a tick that reads no
        state needs no more)."""
        if self._mot is None:
            n, tick = self._n, self._tick
            xy, yaw, speed, omega = np.zeros((n, 2)), np.zeros(n), np.zeros(n), np.zeros(n)
            active = np.ones(n, dtype=bool)
            if self._phys:
                idx = self._phys
                x, h, v = self._phys_readings()
                xy[idx], yaw[idx], speed[idx], omega[idx] = x[:, 0:2], h, v, x[:, 12]
            for idx, fleet in self.traffic:
                now, _ = fleet.readings(tick)
                xy[idx, 0], xy[idx, 1] = now[:, R_X], now[:, R_Y]
                omega[idx], yaw[idx], speed[idx] = now[:, R_OMEGA], now[:, R_YAWREAD], now[:, R_VFWD]
            for idx, src in self.sources:
                ps = src.poses(tick)
                xy[idx], yaw[idx], speed[idx], omega[idx], active[idx] = ps.xy, ps.yaw, ps.speed, ps.yaw_rate, ps.active
            self._mot = (xy, yaw, speed, omega, active)
        return self._mot

    def _arrays(self) -> _Arrays:
        """Every car's reading at the last tick as arrays (:meth:`_motion` and the rest), with its acceleration, the
        finite difference of v_W over the last physics step."""
        if self._arr is None:
            n, tick = self._n, self._tick
            xy, yaw, speed, omega, active = self._motion()
            p_W, q_WB, v_W, a_W = np.zeros((n, 3)), np.zeros((n, 4)), np.zeros((n, 3)), np.zeros((n, 3))
            p_W[:, :2] = xy
            if self._phys:
                idx = self._phys
                x, _, _ = self._phys_readings()
                p_W[idx, 2], q_WB[idx], v_W[idx] = x[:, 2], x[:, 3:7], x[:, 7:10]
                if self._prev_rows is not None:
                    a_W[idx] = (x[:, 7:10] - np.array(self._prev_rows)[:, 7:10]) * self.physics_hz
            for idx, fleet in self.traffic:
                now, prev = fleet.readings(tick)
                p_W[idx, 2] = fleet.ground_z
                half = 0.5 * now[:, R_YAW]
                q_WB[idx, 2], q_WB[idx, 3] = np.sin(half), np.cos(half)
                v_W[idx, 0], v_W[idx, 1] = now[:, R_VX], now[:, R_VY]
                if prev is not None:
                    a_W[idx, 0] = (now[:, R_VX] - prev[:, R_VX]) * self.physics_hz
                    a_W[idx, 1] = (now[:, R_VY] - prev[:, R_VY]) * self.physics_hz
            for idx, src in self.sources:
                ps = src.poses(tick)
                p_W[idx, 2] = src.ground_z
                q_WB[idx, 2], q_WB[idx, 3] = np.sin(0.5 * ps.yaw), np.cos(0.5 * ps.yaw)
                v_W[idx, :2] = ps.v_xy
                if ps.a_xy is not None:  # the derivative of v_xy as the source moves it (SUMO: over its step)
                    a_W[idx, 0], a_W[idx, 1] = ps.a_xy[:, 0], ps.a_xy[:, 1]
            self._arr = _Arrays(p_W=p_W, q_WB=q_WB, v_W=v_W, omega_z=omega, a_W=a_W, yaw=yaw, speed=speed,
                                active=active)
        return self._arr

    def apply_actuation(self) -> None:
        """Run-loop phase 1: each physics car's dynamics acts on its driver's last command; the kinematic cars' boxes
        near a dynamic body (:attr:`near_points`, the physics cars) move to their pose of the coming tick."""
        for i, dyn in self.dynamics.items():
            dyn.actuate(self.drivers[i].command)
        if self.traffic or self.sources:
            near = self._phys_readings()[0][:, 0:2] if self._phys else None
            if self.near_points is not None:
                q = np.asarray(self.near_points(), dtype=float).reshape(-1, 3)
                ceiling = self._near_ceiling
                if any(z < ceiling for z in q[:, 2].tolist()):  # most ticks none: UAVs fly above every box's reach
                    low = q[:, 2] < ceiling
                    near = q[low, :2] if near is None else np.concatenate((near, q[low, :2]))
            if near is not None:
                for fleet in self._kinematic:
                    fleet.sync_near(self._tick + 1, near, SYNC_RADIUS)

    def sync_scene(self) -> None:
        """Place every kinematic car's box at its pose of the last tick (before sensors or cameras look)."""
        for _, fleet in [*self.traffic, *self.sources]:
            fleet.sync_scene(self._tick)

    def close(self) -> None:
        """Release the external traffic sources (a SUMO simulation); idempotent."""
        for _, src in self.sources:
            src.close()

    def after_step(self, tick: int) -> None:
        """After ``p.stepSimulation()``: read the cars' state and run the drivers due at ``tick``."""
        self._read()
        self._tick = tick
        self._cache = None
        if self.traffic:
            others = None
            for idx, fleet in self.traffic:
                if tick % fleet.every == 0:
                    if others is None:
                        others = self._others()
                    fleet.advance(tick, others)
                    self._events += [(int(idx[e["car"]]), dict(e, car=int(idx[e["car"]])))
                                     for e in fleet.pop_events()]
        for idx, src in self.sources:
            src.advance(tick, self._others())
            self._events += [(int(idx[e["car"]]), dict(e, car=int(idx[e["car"]]))) if "car" in e else (-1, dict(e))
                             for e in src.pop_events()]  # a source's own events (a refused flow) name no car
        if self._phys and tick % self._every_gcd == 0:
            due = [i for i in self._phys if tick % self._every[i] == 0]
            if due:
                xy, yaw, speed, omega, active = self._motion()
                lead_xy = np.where(active[:, None], xy, np.inf)  # a slot without a vehicle leads no one
                leaders = find_leaders(self.drivers, lead_xy, yaw, speed, self._lengths, followers=due)
                for i in due:
                    drv = self.drivers[i]
                    drv.update(xy[i], float(yaw[i]), float(speed[i]), tick, leaders[i], float(omega[i]))
                    self.dynamics[i].on_driver_update(float(speed[i]))
                    self._events += [(i, dict(e, car=i)) for e in drv.pop_events()]
                    self._check_road(i, tick)

    def _others(self) -> OtherCars:
        """The physics cars at the last tick, as a traffic fleet's leader search sees them."""
        if not self._phys:
            return OtherCars.none()
        x, h, v = self._phys_readings()  # not the all-car arrays: this is asked at every tick of an external source
        return OtherCars(xy=x[:, 0:2], yaw=h, speed=v, length=self._length_arr[self._phys])

    def _check_road(self, i: int, tick: int) -> None:
        """Events when a car's centre leaves the street (|lateral| > lanes x lane_width) or comes back."""
        drv = self.drivers[i]
        road_id, s, lateral = drv.road_position()  # where the update just projected the car
        road = drv.network.roads[road_id]
        off = abs(lateral) > road.lanes * road.lane_width
        if off != self._off_road[i]:
            self._off_road[i] = off
            self._events.append((i, {"type": "car_left_road" if off else "car_back_on_road", "car": i, "tick": tick,
                                     "road": road_id, "s": s, "lateral": lateral}))

    @property
    def state(self) -> CarState:
        """Ground truth after the last ``after_step``."""
        if self._cache is None:
            x = self._arrays()
            n = self._n
            road_id, s, lateral = np.full(n, "", dtype=object), np.zeros(n), np.zeros(n)
            stopped = np.zeros(n, dtype=bool)
            for i in self._phys:
                road_id[i], s[i], lateral[i] = self.drivers[i].locate(x.p_W[i, :2])
                stopped[i] = self.drivers[i].stopped
            for idx, src in [*self.traffic, *self.sources]:
                ids, s_f, lat_f, stop_f = src.road_positions(self._tick)
                road_id[idx], s[idx], lateral[idx], stopped[idx] = ids, s_f, lat_f, stop_f
            road_id = road_id.tolist()
            self._cache = CarState(
                tick=self._tick, p_W=x.p_W.copy(), q_WB=x.q_WB.copy(), v_W=x.v_W.copy(), a_W=x.a_W.copy(),
                yaw=x.yaw.copy(), speed=x.speed.copy(), road_id=road_id, s=s, lateral=lateral, stopped=stopped,
                active=None if not self.sources else x.active.copy())
        return self._cache

    def pop_events(self) -> list[dict]:
        """Events since the last call, in the order of the ticks and, within a tick, of the cars: ``car_stop``,
        ``car_go``, ``car_enter_road``, ``car_route_end``, ``car_left_road``, ``car_back_on_road`` (and a traffic
        source's: ``traffic_depart``, ``traffic_arrive``, ``traffic_flow_refused``); each has ``type`` and ``tick``,
        and all but the source's own (``traffic_flow_refused``) ``car`` (index)."""
        ev, self._events = self._events, []
        ev.sort(key=lambda ie: (ie[1]["tick"], ie[0]))  # stable: a car's own events keep their order
        return [e for _, e in ev]

    def __len__(self) -> int:
        return self._n
