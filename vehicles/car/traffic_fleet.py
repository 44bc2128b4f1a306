"""The built-in traffic fleet: kinematic cars whose drivers and bicycle models step together in compiled code at one
rate, their scene boxes placed only when something looks.

The car fleet (:class:`vehicles.car.fleet.CarFleet`) hands every ``dynamics: kinematic`` car to a :class:`TrafficFleet`
(one per driver rate). At each of its ticks (every ``physics_hz / rate_hz`` physics ticks) the fleet

1. runs one driver step of every car in one compiled call (:func:`vehicles.car.traffic_kernel.drive_all`: projection
   on the lane path, leader search on a uniform grid, Stanley steering, speed envelope and IDM+); the few cars whose
   step does something rare (rebuild the lane path, enter a new road, redraw the cruise speed, stop at or leave a stop
   line: a few per car per road) take it in their Python :class:`~vehicles.car.driver.Driver`, which keeps the
   routes, random walks, random draws and events;
2. integrates every car's kinematic bicycle over all the physics ticks to its next step at once
   (:func:`~vehicles.car.traffic_kernel.integrate`) and keeps each tick's state, so that :meth:`TrafficFleet.poses`
   answers for any physics tick of the period exactly, not interpolated.

The arithmetic is the Python driver's and bicycle's, operation for operation: a car here drives the trajectory a
:class:`~vehicles.car.driver.Driver` with a :class:`~vehicles.car.bicycle.KinematicBicycle` stepped every physics tick
drives, to the last bit (tests/vehicles/test_traffic_fleet.py).

Scene bodies. Each car's :class:`~vehicles.car.box_body.CarBoxBody` stays where it was last placed until
:meth:`TrafficFleet.sync_scene` (before a sensor scan or a camera frame: every box at the pose of that tick) or
:meth:`TrafficFleet.sync_near` (before each physics step: the boxes within a radius of a UAV or a physics car, and
those left there by an earlier placement, so contacts never meet a box where the car no longer is).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vehicles.car.box_body import CarBoxBody, yaw_quaternion
from vehicles.car.driver import Driver
from vehicles.car.driver_config import LeaderInfo
from vehicles.car.lane_path import PathProjection
from vehicles.car.params import CarParams
from vehicles.car.traffic_kernel import (CFG, MODE_DONE, MODE_DRIVE, MODE_STOPPED, R_OMEGA, R_V, R_VFWD, R_VX, R_VY,
                                         R_X, R_Y, R_YAW, R_YAWREAD, ROWS, drive_all, integrate, locate_all,
                                         start_reading)
from vehicles.car.traffic_source import OtherCars, TrafficPoses

__all__ = ["TrafficFleet"]

_MODES = {"drive": MODE_DRIVE, "stopped": MODE_STOPPED, "done": MODE_DONE}
_TWO = 2.0  # the exponent of the IDM term, passed at run time (see vehicles.car.traffic_kernel)
_NEAR_MARGIN = 10.0  # m: how far a car or a UAV may move within one fleet period, with room to spare (30 m/s x 0.1 s)


class TrafficFleet:
    """Kinematic cars stepped together (see the module docstring).

    Parameters
    ----------
    client_id : int
        PyBullet client holding the cars' boxes.
    drivers : Sequence[Driver]
        The cars' drivers, built (spawn poses, routes, random generators) and not yet stepped; all with one
        ``config.rate_hz``.
    params : Sequence[CarParams]
        The cars.
    ids : Sequence[str]
        One id per car.
    physics_hz : int
        Physics rate (Hz).
    """

    def __init__(self, client_id: int, drivers: Sequence[Driver], params: Sequence[CarParams], ids: Sequence[str],
                 physics_hz: int) -> None:
        n = len(drivers)
        if n == 0 or len(params) != n or len(ids) != n:
            raise ValueError(f"TrafficFleet needs one driver, params and id per car, got {len(drivers)}/"
                             f"{len(params)}/{len(ids)}")
        rates = {d.config.rate_hz for d in drivers}
        if len(rates) != 1:
            raise ValueError(f"TrafficFleet steps its cars at one rate; the drivers ask for {sorted(rates)} Hz")
        self.client_id, self.physics_hz = client_id, int(physics_hz)
        self.drivers, self.params, self.ids = list(drivers), list(params), list(ids)
        self.rate_hz = next(iter(rates))
        self.every = drivers[0].config.ticks_per_update(physics_hz)
        self.dt = 1.0 / physics_hz
        spawns = [d.spawn_pose() for d in drivers]
        self.boxes = [CarBoxBody(client_id, par, xy, yaw) for par, (xy, yaw) in zip(params, spawns, strict=True)]
        self.body_ids = np.array([b.body_id for b in self.boxes], dtype=int)
        self.lengths = np.array([par.length for par in params])
        self.ground_z = np.array([b.z for b in self.boxes])
        self.cfg = np.array([[self._setting(d, par, name) for name in CFG] for d, par in zip(drivers, params,
                                                                                             strict=True)])
        self._codes = {rid: k for k, rid in enumerate(drivers[0].network.roads)}
        self._road_ids = np.array(list(self._codes), dtype=object)  # code -> road id
        # state (x, y, yaw, speed, steer, beta, yaw rate) and the readings of every tick of the current period
        self.S = np.zeros((n, 7))
        self.S[:, 0:2] = [xy for xy, _ in spawns]
        self.S[:, 2] = [yaw for _, yaw in spawns]
        self.buf = np.zeros((n, self.every + 1, len(ROWS)))
        start_reading(self.buf, self.S, self.cfg)
        self._prev = self.buf[:, 0].copy()  # readings one tick before buf[:, 0] (tick 0: none; a_W = 0 there)
        self._t0 = 0  # physics tick of buf[:, 0]
        # per-car driver state mirrored for the compiled step (written back from a Driver after each Python step)
        self.proj = np.zeros((n, 4))
        self.proj[:, 3] = -1
        self.mode = np.zeros(n, dtype=np.int64)
        self.release_tick = np.zeros(n, dtype=np.int64)
        self.next_cruise = np.full(n, -1, dtype=np.int64)
        self.last_code = np.zeros(n, dtype=np.int64)
        self.off_road = np.zeros(n, dtype=bool)
        self._paths: list[object] = [None] * n
        self._alloc(n, 8, 2, 2)
        for i in range(n):
            self._resync(i)
        self.cmd = np.zeros((n, 3))  # (accel, steer, hold) of the period being integrated
        integrate(self.S, self.cmd, self.cfg, self.dt, self.buf)
        self._placed = np.zeros(n, dtype=np.int64)  # tick of each box's last placement
        self._box_xy = np.array([xy for xy, _ in spawns], dtype=float)
        self._events: list[dict] = []
        self._near, self._near_key = np.zeros(0, dtype=int), (-1, 0)  # cars near the points this period (sync_near)
        self.python_steps = 0  # driver steps taken by the Python drivers (rare: path rebuilds, stops, ...)
        self.compiled_steps = 0

    @staticmethod
    def _setting(d: Driver, par: CarParams, name: str) -> float:
        derived = {"decel_plan": d.decel_plan, "decel_max": d.decel_max, "accel_max": d.accel_max}
        if name in derived:
            return float(derived[name])
        return float(getattr(d.config, name) if hasattr(d.config, name) else getattr(par, name))

    # ----------------------------------------------------------------------------------------------- packing
    def _alloc(self, n: int, m: int, k: int, j: int) -> None:
        """(Re)allocate the packed paths for ``m`` points, ``k`` roads and ``j`` junctions per car, keeping rows."""
        old = getattr(self, "P_n", None)
        shapes = {"P_xy": (n, m, 2), "P_t": (n, m, 2), "P_seg": (n, m), "P_s": (n, m), "P_head": (n, m),
                  "P_kappa": (n, m), "P_cap": (n, m), "P_ridx": (n, m), "P_corner": (n, m), "P_laneoff": (n, m),
                  "P_roads": (n, m), "P_lanew": (n, k), "R_code": (n, k), "R_width": (n, k), "J_s": (n, j),
                  "J_flag": (n, j)}
        kinds = {"P_ridx": np.int64, "R_code": np.int64, "P_corner": np.bool_, "J_flag": np.bool_}
        for name, shape in shapes.items():
            new = np.zeros(shape, dtype=kinds.get(name, np.float64))
            if old is not None:
                prev = getattr(self, name)
                new[tuple(slice(0, s) for s in prev.shape)] = prev
            setattr(self, name, new)
        if old is None:
            self.P_n = np.zeros(n, dtype=np.int64)
            self.J_n = np.zeros(n, dtype=np.int64)
            self.ends_route = np.zeros(n, dtype=np.bool_)

    def _resync(self, i: int) -> None:
        """Copy driver ``i``'s state (path, stops, mode, cruise, projection) into the packed arrays."""
        d = self.drivers[i]
        path = d.path
        npts, nroads, njun = len(path.s), len(path.roads), len(d._junction_s)
        m, k, j = self.P_s.shape[1], self.R_code.shape[1], self.J_s.shape[1]
        if npts > m or nroads > k or njun > j:
            self._alloc(len(self.drivers), max(m, int(1.5 * npts)), max(k, 2 * nroads), max(j, 2 * njun))
        if path is not self._paths[i]:
            self._paths[i] = path
            self.P_n[i] = npts
            self.P_xy[i, :npts] = path.xy
            self.P_t[i, :npts - 1] = path._t
            self.P_seg[i, :npts - 1] = path._seg
            self.P_s[i, :npts] = path.s
            self.P_head[i, :npts] = path.heading
            self.P_kappa[i, :npts] = path.kappa
            self.P_ridx[i, :npts] = path.road_index
            self.P_corner[i, :npts] = path.in_corner
            self.P_laneoff[i, :npts] = path.lane_offset
            self.P_roads[i, :npts] = path.road_s
            for q, road in enumerate(path.roads):
                self.P_lanew[i, q] = road.lane_width
                self.R_width[i, q] = road.lanes * road.lane_width
                self.R_code[i, q] = self._codes[d.plan.road_ids[q]]
        self.P_cap[i, :npts] = d._caps()
        self.J_n[i] = njun
        self.J_s[i, :njun] = d._junction_s
        self.J_flag[i, :njun] = d.plan.stop_flags[:njun]
        self.ends_route[i] = d._ends_route
        self.mode[i] = _MODES[d.mode]
        self.release_tick[i] = d._release_tick
        self.next_cruise[i] = -1 if d._next_cruise_tick is None else d._next_cruise_tick
        self.last_code[i] = self._codes[d._last_road]
        if d._proj is not None:
            pr = d._proj
            self.proj[i] = (pr.s, pr.lateral, pr.heading, pr.index)

    # ------------------------------------------------------------------------------------------------ stepping
    def advance(self, tick: int, others: OtherCars) -> None:
        """After the physics step of ``tick``: one driver step of every car and the bicycle ticks up to the next, if
        ``tick`` is one of the fleet's ticks."""
        if tick % self.every:
            return
        if tick != self._t0 + self.every:
            raise RuntimeError(f"TrafficFleet.advance: tick {tick} is not the fleet's next step "
                               f"({self._t0 + self.every})")
        n = len(self.drivers)
        X = np.ascontiguousarray(self.buf[:, self.every])
        prev_proj = self.proj.copy()
        flag, leader = np.zeros(n, dtype=np.bool_), np.zeros((n, 3))
        off = self.off_road.copy()
        ox = np.column_stack([others.xy, others.yaw, others.speed]) if len(others.length) else np.zeros((0, 4))
        drive_all(tick, X, ox, np.asarray(others.length, dtype=float), self.P_xy,
                  self.P_t, self.P_seg, self.P_s, self.P_head, self.P_kappa, self.P_cap, self.P_ridx, self.P_corner,
                  self.P_lanew, self.P_laneoff, self.P_n, self.R_code, self.R_width, self.J_s, self.J_flag, self.J_n,
                  self.ends_route, self.proj, self.last_code, self.mode, self.release_tick, self.next_cruise,
                  self.cfg, _TWO, self.cmd, flag, leader, off)
        slow = np.flatnonzero(flag)
        self.python_steps += len(slow)
        self.compiled_steps += n - len(slow)
        for i in slow:
            self._python_step(int(i), tick, X[i], prev_proj[i], leader[i])
        for i in np.flatnonzero(off != self.off_road):
            if not flag[i]:
                self._road_event(int(i), tick, bool(off[i]))
        self._prev = self.buf[:, self.every - 1].copy()
        self.buf[:, 0] = self.buf[:, self.every]
        self._t0 = tick
        integrate(self.S, self.cmd, self.cfg, self.dt, self.buf)

    def _python_step(self, i: int, tick: int, x: np.ndarray, prev: np.ndarray, leader: np.ndarray) -> None:
        d = self.drivers[i]
        d._proj = None if prev[3] < 0 else PathProjection(s=float(prev[0]), lateral=float(prev[1]),
                                                          heading=float(prev[2]), index=int(prev[3]))
        lead = None if leader[2] < 0 else LeaderInfo(gap=float(leader[0]), speed=float(leader[1]),
                                                     index=int(leader[2]))
        cmd = d.update(np.array([x[R_X], x[R_Y]]), float(x[R_YAWREAD]), float(x[R_VFWD]), tick, lead,
                       float(x[R_OMEGA]))
        self.cmd[i] = (cmd.accel, cmd.steer, 1.0 if cmd.hold else 0.0)
        self._resync(i)
        self._events += [dict(e, car=i) for e in d.pop_events()]
        road_id, _, lateral = d.road_position()
        road = d.network.roads[road_id]
        off = abs(lateral) > road.lanes * road.lane_width
        if off != self.off_road[i]:
            self._road_event(i, tick, off)

    def _road_event(self, i: int, tick: int, off: bool) -> None:
        d = self.drivers[i]
        pr = self.proj[i]
        d._proj = PathProjection(s=float(pr[0]), lateral=float(pr[1]), heading=float(pr[2]), index=int(pr[3]))
        road_id, s, lateral = d.road_position()
        self.off_road[i] = off
        self._events.append({"type": "car_left_road" if off else "car_back_on_road", "car": i, "tick": tick,
                             "road": road_id, "s": s, "lateral": lateral})

    # -------------------------------------------------------------------------------------------------- reading
    def _rows(self, tick: int) -> np.ndarray:
        k = tick - self._t0
        if not 0 <= k <= self.every:
            raise ValueError(f"TrafficFleet: tick {tick} is outside the fleet's period [{self._t0}, "
                             f"{self._t0 + self.every}]")
        return self.buf[:, k]

    def readings(self, tick: int) -> tuple[np.ndarray, np.ndarray]:
        """(readings at ``tick``, readings at ``tick - 1``), rows of :data:`~vehicles.car.traffic_kernel.ROWS`;
        the second is None at tick 0."""
        now = self._rows(tick)
        if tick == 0:
            return now, None
        return now, (self._prev if tick == self._t0 else self.buf[:, tick - 1 - self._t0])

    def poses(self, tick: int) -> TrafficPoses:
        r = self._rows(tick)
        return TrafficPoses(tick=tick, xy=r[:, [R_X, R_Y]].copy(), yaw=r[:, R_YAWREAD].copy(), speed=r[:, R_V].copy(),
                            v_xy=r[:, [R_VX, R_VY]].copy(), yaw_rate=r[:, R_OMEGA].copy(),
                            active=np.ones(len(r), dtype=bool))

    def road_positions(self, tick: int) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
        r = self._rows(tick)
        out = np.zeros((len(r), 3))
        locate_all(np.ascontiguousarray(r[:, [R_X, R_Y]]), self.P_xy, self.P_t, self.P_seg, self.P_s, self.P_head,
                   self.P_ridx, self.P_laneoff, self.P_n, self.proj, self.P_roads, out)
        codes = self.R_code[np.arange(len(r)), out[:, 0].astype(np.int64)]  # the roads of the cars' paths
        return self._road_ids[codes].tolist(), out[:, 1].copy(), out[:, 2].copy(), self.mode != MODE_DRIVE

    # ---------------------------------------------------------------------------------------------- the scene
    def _place(self, idx: np.ndarray, tick: int) -> None:
        idx = np.asarray(idx, dtype=np.int64)
        if not len(idx):
            return
        rows = self._rows(tick)[idx]
        boxes = self.boxes
        for i, x, y, yaw in zip(idx.tolist(), rows[:, R_X].tolist(), rows[:, R_Y].tolist(), rows[:, R_YAW].tolist(),
                                strict=True):
            boxes[i].place(x, y, yaw_quaternion(yaw))
        self._box_xy[idx] = rows[:, [R_X, R_Y]]
        self._placed[idx] = tick

    def sync_scene(self, tick: int) -> None:
        self._place(np.flatnonzero(self._placed != tick), tick)

    def sync_near(self, tick: int, points_xy: np.ndarray, radius: float) -> None:
        """Place the boxes within ``radius`` of ``points_xy`` at their pose of ``tick``. The cars that may be that
        near during the period (at its start or end, or with the box left there, within ``radius`` +
        :data:`_NEAR_MARGIN` of the points) are found once per period; each tick places those of them not yet
        placed for it (a superset of the cars within ``radius``)."""
        pts = np.asarray(points_xy, dtype=float).reshape(-1, 2)
        if not len(pts):
            return
        if self._near_key != (self._t0, len(pts)):
            reach = radius + _NEAR_MARGIN
            near = np.zeros(len(self.drivers), dtype=bool)
            ends = (self.buf[:, 0], self.buf[:, self.every])
            for q in pts:  # a handful of points (UAVs, physics cars) against every car
                for xy in (ends[0][:, [R_X, R_Y]], ends[1][:, [R_X, R_Y]], self._box_xy):
                    near |= np.hypot(xy[:, 0] - q[0], xy[:, 1] - q[1]) < reach
            self._near, self._near_key = np.flatnonzero(near), (self._t0, len(pts))
        idx = self._near[self._placed[self._near] != tick]
        if len(idx):
            self._place(idx, tick)

    def pop_events(self) -> list[dict]:
        ev, self._events = self._events, []
        return ev

    def close(self) -> None:
        pass

    def __len__(self) -> int:
        return len(self.drivers)
