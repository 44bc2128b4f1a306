"""Road-following driver: Stanley lateral control on the lane centre-line, a curvature-aware speed envelope,
IDM+ car following, junction stops with seeded dwell times, traffic lights where a signal source says, and random
cruise-speed changes. Pure numpy.

Traffic lights. A driver given a :attr:`Driver.signal` (the traffic source's light states: SUMO's for a physics car
among SUMO traffic) asks it, for each junction on its path ahead, for the state of the link from the road it enters
the junction on to the road it leaves by: red (``r``, ``R``, red-yellow ``u``) is a stop at that junction's stop line
unless the car could not stop before it even braking its hardest (distance to the line under
``v² / (2 b_max) − w``, ``w`` the stop window, so a car braking to the line keeps stopping there); yellow (``y``,
``Y``) is one where it can still stop at the planned deceleration (distance at least ``v² / (2 b_plan) − w``),
otherwise the car goes on; anything else (green ``G`` / ``g``, off, no light) is no stop. A car
stopped at a light goes when the link shows neither red nor yellow. Lights draw nothing from the driver's generator,
so a driver without a signal source drives exactly as before.

Lateral law (Stanley; Thrun et al., J. Field Robotics 23(9), 2006) at the front axle p_f = p + (L/2)(cos psi, sin psi):
    delta = wrap(psi_path(p_f) - psi) - atan(k e_f / (v + v_soft)) - c (omega - v kappa_path),
with e_f the signed lateral offset of p_f from the lane path (left positive). In a steady turn e_f -> 0 exactly for
the kinematic bicycle, since the path heading at the front axle exceeds the car's heading by the steering angle.
Longitudinal law: see :mod:`vehicles.car.longitudinal`.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from vehicles.car.driver_config import DriveCommand, DriverConfig, LeaderInfo
from vehicles.car.lane_path import LanePath, PathProjection
from vehicles.car.longitudinal import curve_speed, idm_plus_accel, path_envelope_accel
from vehicles.car.params import CarParams
from vehicles.car.road_protocol import NetworkLike
from vehicles.car.route import Route, RoutePlan

__all__ = ["Driver"]

_BACK_MARGIN = 5.0  # metres of already-driven lane kept at the start of a rebuilt path
_RED, _YELLOW = ("r", "R", "u"), ("y", "Y")  # light states (SUMO's letters) that stop a car (module docstring)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class Driver:
    """Drives one car along its route.

    Parameters
    ----------
    config : DriverConfig
        Behaviour.
    params : CarParams
        The car (wheelbase, steering and acceleration limits, length for the stop line at a route end).
    route : Route
        Where to drive.
    network : NetworkLike
        The road graph.
    rng : np.random.Generator
        Source of random walks, stop decisions, dwell times and cruise speeds.
    physics_hz : int
        Physics rate (Hz) in whose ticks the ``tick`` argument of :meth:`update` counts; ``config.rate_hz`` must
        divide it.
    """

    def __init__(self, *, config: DriverConfig, params: CarParams, route: Route, network: NetworkLike,
                 rng: np.random.Generator, physics_hz: int = 240) -> None:
        config.ticks_per_update(physics_hz)
        self.config, self.params, self.route, self.network, self.rng = config, params, route, network, rng
        self.plan = RoutePlan(route, network, config.stop_probability, config.random_walk_chunk, rng)
        self.accel_max = min(config.accel, params.max_accel)
        self.decel_max = min(config.decel_max, params.max_decel)
        self.decel_plan = min(config.decel_plan, self.decel_max)
        self.cruise_fraction = float(rng.uniform(*config.cruise_fraction_range))
        self._next_cruise_tick: int | None = None
        self.mode = "drive"  # "drive" | "stopped" | "done"
        self._release_tick = 0
        self._stop_road = ""
        self.signal: Callable[[str, str], str] | None = None  # light state of a link (module docstring)
        self._at_light: tuple[str, str] | None = None  # the link whose light holds the stopped car
        self._tick = 0
        self._last_road = route.first_road
        self._ticks_per_second = physics_hz
        self._events: list[dict] = []
        self._proj: PathProjection | None = None
        self._cap: tuple[LanePath, float, np.ndarray] | None = None  # (path, cruise fraction, caps): see _caps
        self.command = DriveCommand(accel=0.0, steer=0.0, hold=False, tick=0)
        first = network.roads[route.first_road]
        if route.start_s > first.length:
            raise ValueError(f"Route.start_s {route.start_s} m exceeds the length {first.length:.1f} m of {first.id!r}")
        self._build(route.start_s)

    # ----------------------------------------------------------------- path
    def _build(self, s_start: float) -> None:
        cfg, plan = self.config, self.plan
        total, n = -s_start, 0
        while True:
            if n == len(plan.road_ids) and not plan.extend():
                break
            total += self.network.roads[plan.road_ids[n]].length
            n += 1
            if total >= cfg.path_horizon:
                break
        roads = [self.network.roads[r] for r in plan.road_ids[:n]]
        self.path = LanePath(roads, [self.route.lane] * n, s_start, cfg.path_ds, cfg.corner_length)
        self._ends_route = n == len(plan.road_ids) and plan.finite
        self._proj = None
        self._junction_s: list[float] = self.path.junction_s.tolist()
        self._v_curve = curve_speed(self.path.kappa, cfg.lateral_accel_max)

    def _maybe_rebuild(self, p_xy: np.ndarray) -> None:
        """Move the path forward once the car is on a later road's own lane section, or extend a short path."""
        path, proj = self.path, self._proj
        i = proj.index
        if path.in_corner[i] or path.in_corner[min(i + 1, len(path.s) - 1)]:
            return
        k = int(path.road_index[i])
        short = path.length - proj.s < self.config.path_horizon - 4 * self.config.corner_length
        if k == 0 and (not short or self._ends_route):
            return
        sel = np.flatnonzero((path.road_index == k) & ~path.in_corner)
        i0 = max(int(sel[0]), i - int(_BACK_MARGIN / self.config.path_ds))
        self.plan.advance(k)
        self._build(float(path.road_s[i0]))
        self._proj = self.path.project(p_xy, hint=int(round((path.s[i] - path.s[i0]) / self.config.path_ds)))

    # ---------------------------------------------------------------- state
    @property
    def road_id(self) -> str:
        """Id of the road the car is on (the incoming road in the first half of a junction corner)."""
        k = 0 if self._proj is None else int(self.path.road_index[self._proj.index])
        return self.plan.road_ids[k]

    def road_position(self) -> tuple[str, float, float]:
        """(road id, arc length on it (m), lateral offset from its centre-line (m)) at the last update."""
        if self._proj is None:
            k, s = 0, float(self.path.road_s[0])
            return self.plan.road_ids[0], s, float(self.path.lane_offset[0])
        k, s = self.path.locate(self._proj.s)
        return self.plan.road_ids[k], s, self._proj.lateral + float(self.path.lane_offset[self._proj.index])

    def spawn_pose(self) -> tuple[np.ndarray, float]:
        """Spawn position (2,) m on the lane centre at the route's start and heading (rad)."""
        return self.path.xy[0].copy(), float(self.path.heading[0])

    @property
    def stopped(self) -> bool:
        """Standing at a junction or at the end of the route."""
        return self.mode != "drive"

    def pop_events(self) -> list[dict]:
        """Events since the last call (``car_stop``, ``car_go``, ``car_enter_road``, ``car_route_end``)."""
        ev, self._events = self._events, []
        return ev

    def _event(self, kind: str, **kw) -> None:
        self._events.append({"type": kind, "tick": self._tick, **kw})

    def locate(self, p_xy: np.ndarray) -> tuple[str, float, float]:
        """(road id, arc length on it (m), lateral offset from its centre-line (m)) of a point near the car.

        Exact on road sections; inside junction corners the offset is measured from the corner curve.
        """
        proj = self.path.project(p_xy, None if self._proj is None else self._proj.index, window=20)
        k, s = self.path.locate(proj.s)
        return self.plan.road_ids[k], s, proj.lateral + float(self.path.lane_offset[proj.index])

    # ---------------------------------------------------------------- stops
    def _next_stop(self, s_car: float, v: float = 0.0) -> tuple[float, int] | None:
        """(path arc length of the next stop line (m), planned road index or -1 for the route end): a planned stop, a
        red light ahead (module docstring) or the route's end."""
        for k, s_j in enumerate(self._junction_s):
            if s_j <= s_car - 3 * self.config.stop_window:
                continue
            if self.plan.stop_flags[k] or (self.signal is not None and self._light_stops(k, s_j - s_car, v)):
                return s_j, k
        if self._ends_route:
            return max(self.path.length - 0.5 * self.params.length - 1.0, 0.0), -1
        return None

    def _link(self, k: int) -> tuple[str, str] | None:
        """(road in, road out) of the junction at the end of planned road ``k``, None past the plan."""
        ids = self.plan.road_ids
        return (ids[k], ids[k + 1]) if k + 1 < len(ids) else None

    def _light_stops(self, k: int, distance: float, v: float) -> bool:
        """Whether the light of junction ``k``, ``distance`` m ahead, stops a car at ``v`` m/s (module docstring)."""
        link = self._link(k)
        if link is None:
            return False
        state = self.signal(*link)
        slack = self.config.stop_window  # a car braking to the line keeps stopping there (a planned stop's window)
        if state in _RED:
            return distance >= v * v / (2.0 * self.decel_max) - slack
        return state in _YELLOW and distance >= v * v / (2.0 * self.decel_plan) - slack

    # --------------------------------------------------------------- update
    def update(self, p_xy: np.ndarray, yaw: float, speed: float, tick: int, leader: LeaderInfo | None = None,
               yaw_rate: float | None = None) -> DriveCommand:
        """One driver step from the car's pose (m, rad), forward speed (m/s) and optional yaw rate (rad/s)."""
        self._tick = tick
        cfg = self.config
        p_xy = np.asarray(p_xy, dtype=float)[:2]
        hint = None if self._proj is None else self._proj.index
        self._proj = self.path.project(p_xy, hint)
        self._maybe_rebuild(p_xy)
        proj = self._proj
        road_now = self.road_id
        if road_now != self._last_road:
            self._event("car_enter_road", road=road_now, prev=self._last_road)
            self._last_road = road_now
        v = max(float(speed), 0.0)
        self._update_cruise(tick)
        stop = self._next_stop(proj.s, v)
        if self.mode == "drive" and stop is not None and stop[0] - proj.s < cfg.stop_window and v < cfg.stopped_speed:
            road, _, _ = self.road_position()
            if stop[1] < 0:
                self.mode = "done"
                self._event("car_route_end", road=road)
            else:
                self.mode = "stopped"
                node = self.network.roads[self.plan.road_ids[stop[1]]].end_node
                if not self.plan.stop_flags[stop[1]]:  # a light: wait until it no longer shows red or yellow
                    self._at_light = self._link(stop[1])
                    self._event("car_stop", road=road, node=node, dwell=None, light=True)
                else:
                    self._stop_road = self.plan.road_ids[stop[1]]
                    dwell = float(self.rng.uniform(*cfg.dwell_range))
                    self._release_tick = tick + int(round(dwell * self._ticks_per_second))
                    self._event("car_stop", road=road, node=node, dwell=dwell)
        if self.mode == "stopped" and self._at_light is not None:
            if self.signal is None or self.signal(*self._at_light) not in _RED + _YELLOW:
                self.mode, self._at_light = "drive", None
                self._event("car_go", road=self.road_position()[0])
                stop = self._next_stop(proj.s, v)
        elif self.mode == "stopped" and tick >= self._release_tick:
            self.mode = "drive"
            self.plan.clear_stop(self.plan.road_ids.index(self._stop_road))
            self._event("car_go", road=self.road_position()[0])
            stop = self._next_stop(proj.s, v)
        steer = self._steer(p_xy, yaw, v, yaw_rate)
        if self.mode != "drive":
            self.command = DriveCommand(accel=-self.decel_max, steer=steer, hold=True, tick=tick)
            return self.command
        accel = self._accel(proj, v, stop, leader)
        self.command = DriveCommand(accel=accel, steer=steer, hold=False, tick=tick)
        return self.command

    def _update_cruise(self, tick: int) -> None:
        cfg = self.config
        if cfg.cruise_change_period <= 0:
            return
        if self._next_cruise_tick is None or tick >= self._next_cruise_tick:
            if self._next_cruise_tick is not None:
                self.cruise_fraction = float(self.rng.uniform(*cfg.cruise_fraction_range))
            gap = self.rng.exponential(cfg.cruise_change_period)
            self._next_cruise_tick = tick + max(1, int(gap * self._ticks_per_second))

    def _steer(self, p_xy: np.ndarray, yaw: float, v: float, yaw_rate: float | None) -> float:
        cfg, par = self.config, self.params
        half_l = 0.5 * par.wheelbase
        pf = self.path.project_xy(float(p_xy[0]) + half_l * math.cos(yaw), float(p_xy[1]) + half_l * math.sin(yaw),
                                  self._proj.index, window=80)  # the front axle
        delta = _wrap(pf.heading - yaw) - math.atan2(cfg.stanley_gain * pf.lateral, v + cfg.stanley_softening)
        if yaw_rate is not None and cfg.yaw_damping > 0:
            delta -= cfg.yaw_damping * (yaw_rate - v * float(self.path.kappa[pf.index]))
        return min(max(delta, -par.max_steer), par.max_steer)

    def _caps(self) -> np.ndarray:
        """(N,) speed cap of every path point (m/s): curve speed, cruise fraction of the speed limit, top speed.

        Kept until the path or the cruise fraction changes.
        """
        path, fraction = self.path, self.cruise_fraction
        if self._cap is None or self._cap[0] is not path or self._cap[1] != fraction:
            cap = np.minimum(self._v_curve, np.minimum(fraction * path.speed_limit, self.params.max_speed))
            self._cap = (path, fraction, cap)
        return self._cap[2]

    def _accel(self, proj: PathProjection, v: float, stop: tuple[float, int] | None,
               leader: LeaderInfo | None) -> float:
        cfg, path = self.config, self.path
        reach = v * v / (2 * self.decel_plan) + cfg.lookahead_margin
        i0 = proj.index
        i1 = min(max(path.search(proj.s + reach), i0 + 2), len(path.s))  # path points from the car's segment on
        with_stop = stop is not None and stop[0] - proj.s <= reach
        a = path_envelope_accel(v, path.s, self._caps(), i0, i1, proj.s, stop[0] - proj.s if with_stop else 0.0,
                                with_stop, cfg.speed_gain, self.decel_plan, max(2.0, 2 * v / cfg.rate_hz))
        if leader is not None:
            a = min(a, idm_plus_accel(v, leader.speed, leader.gap, s0=cfg.idm_s0, time_headway=cfg.idm_time_headway,
                                      accel=self.accel_max, decel=self.decel_plan))
        return float(min(max(a, -self.decel_max), self.accel_max))
