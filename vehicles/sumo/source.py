"""SUMO co-simulation as a traffic source (:class:`~vehicles.car.traffic_source.TrafficSource`): libsumo in process.

SUMO drives the background traffic on a network made from skytrack's roads (:mod:`vehicles.sumo.network`) at its own
step length ``1 / rate_hz`` (``rate_hz`` dividing the physics rate). Its vehicles are mirrored onto a fixed number of
slots, one static PyBullet box per slot (:class:`~vehicles.car.box_body.CarBoxBody`): a departing vehicle takes the
lowest free slot, an arriving one frees it, a free slot's body is parked out of sight (``park_z`` below the ground)
and flagged inactive. Bodies move only when asked (:meth:`SumoTraffic.sync_scene`, :meth:`SumoTraffic.sync_near`).

Time: SUMO runs one step ahead. At construction it steps twice, giving the states at ticks 0 and ``period``; at each
of its own ticks ``t`` (a multiple of ``period``) :meth:`SumoTraffic.advance` steps it to ``t + period``, so
:meth:`SumoTraffic.poses` interpolates between two known states at every tick (:mod:`vehicles.sumo.slots`). The
physics cars given to ``advance`` at ``t`` are placed into SUMO for the step to ``t + period`` at their constant-speed
prediction for that time (``vehicle.moveToXY``, exact lateral position, ``keepRoute=2``), as vehicles of their own
type that SUMO never moves itself: SUMO's car following and junction logic see them.

Frames: SUMO reports a vehicle's front bumper and a compass angle (degrees clockwise from north); skytrack's poses are
the centre of mass midway along the body, ``xy = front - length / 2 (cos yaw, sin yaw)``, ``yaw = pi/2 - angle``.

libsumo holds one simulation per process: a second :class:`SumoTraffic` while one is open is refused; :meth:`close`
ends the simulation so that another can start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pybullet as p

from vehicles.car.box_body import CarBoxBody
from vehicles.car.params import CarParams, load_car
from vehicles.car.traffic_source import OtherCars, TrafficPoses
from vehicles.sumo._runtime import import_libsumo
from vehicles.sumo.demand import DemandConfig, FlowStreams, TripPool
from vehicles.sumo.network import NetConfig, SumoNet, build_sumo_net
from vehicles.sumo.slots import SlotStates
from worlds.roads.network import RoadNetwork

__all__ = ["SumoTraffic", "SumoTrafficConfig", "make_sumo_traffic"]

_TRAFFIC_TYPE = "skytrack_traffic"
_PHYSICS_TYPE = "skytrack_physics"
_PHYSICS_PREFIX = "skytrack_physics_"
_STOPPED_SPEED = 0.1  # m/s; a slot slower than this is reported stopped
_NO_STATE = {0x42: (0.0, 0.0), 0x43: 0.0, 0x40: 0.0, 0x50: ""}  # a vehicle SUMO has no state for (teleporting)
_active: SumoTraffic | None = None  # the one libsumo simulation of this process

_NEAR_MARGIN = 10.0  # m; sync_near's candidates hold while no point has moved farther than this from where it was


def _nearest_d2(xy: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Squared distance (m²) from each of ``xy`` (n, 2) to the nearest of ``pts`` (k, 2)."""
    return ((xy[:, None, :] - pts[None, :, :]) ** 2).sum(axis=2).min(axis=1)


@dataclass(frozen=True, kw_only=True)
class SumoTrafficConfig:
    """Settings of a SUMO traffic source.

    Attributes
    ----------
    n_vehicles : int
        Trips kept in the network (see :mod:`vehicles.sumo.demand`).
    n_slots : int
        Scene bodies (>= ``n_vehicles``; vehicles on the road never exceed ``n_vehicles``).
    rate_hz : float
        SUMO steps per second; ``physics_hz / rate_hz`` must be a whole number.
    physics_hz : float
        The run's physics rate (Hz).
    car : str
        Car type of the traffic (:func:`vehicles.car.params.load_car`): body size and SUMO's length, width, top speed
        and acceleration.
    ground_z : float
        Height of the road surface (m).
    park_z : float
        Height of the centre of mass of a parked (inactive) slot's body (m), below the ground.
    park_spacing : float
        Spacing along x of the parked bodies (m), so that they do not overlap.
    time_to_teleport : float
        SUMO's ``--time-to-teleport`` (s): a vehicle stuck this long jumps ahead; while it jumps its slot is inactive.
        Negative: never.
    net : NetConfig
        How the road network is converted.
    demand : DemandConfig
        How trips are inserted.
    sumo_args : tuple[str, ...]
        Extra command-line options for SUMO.
    """

    n_vehicles: int
    n_slots: int
    rate_hz: float = 10.0
    physics_hz: float = 240.0
    car: str = "sedan"
    ground_z: float = 0.0
    park_z: float = -50.0
    park_spacing: float = 10.0
    time_to_teleport: float = 300.0
    net: NetConfig = field(default_factory=NetConfig)
    demand: DemandConfig = field(default_factory=DemandConfig)
    sumo_args: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.n_vehicles < 0:
            raise ValueError(f"SumoTrafficConfig.n_vehicles must be >= 0, got {self.n_vehicles}")
        if self.n_slots < max(1, self.n_vehicles):
            raise ValueError(f"SumoTrafficConfig.n_slots must be >= n_vehicles ({self.n_vehicles}) and >= 1, "
                             f"got {self.n_slots}")
        if not (self.rate_hz > 0 and self.physics_hz > 0):
            raise ValueError(f"SumoTrafficConfig: rate_hz and physics_hz must be > 0, got {self.rate_hz}, "
                             f"{self.physics_hz}")
        ratio = self.physics_hz / self.rate_hz
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(f"SumoTrafficConfig.rate_hz {self.rate_hz} Hz must divide physics_hz "
                             f"{self.physics_hz} Hz a whole number of times")
        if not self.park_z < self.ground_z:
            raise ValueError(f"SumoTrafficConfig.park_z must be below ground_z {self.ground_z} m, got {self.park_z}")

    @property
    def period(self) -> int:
        """Physics ticks per SUMO step."""
        return int(round(self.physics_hz / self.rate_hz))


class SumoTraffic:
    """Background traffic driven by SUMO in this process (see the module docstring).

    Parameters
    ----------
    network : RoadNetwork
        skytrack's roads; SUMO's network is made from them (cached in ``work_dir``).
    config : SumoTrafficConfig
        Settings.
    client_id : int
        PyBullet client of the scene.
    seed : int
        SUMO's ``--seed``.
    rng : numpy.random.Generator
        Draws the trips' origins and destinations.
    work_dir : str or Path
        Where the network files are written and cached.
    """

    def __init__(self, network: RoadNetwork, config: SumoTrafficConfig, *, client_id: int, seed: int,
                 rng: np.random.Generator, work_dir: str | Path) -> None:
        global _active
        if _active is not None:
            raise RuntimeError("a SUMO traffic simulation is already running in this process (libsumo holds one); "
                               "close() it before starting another")
        self.config, self.network, self.client_id = config, network, client_id
        self._lib = import_libsumo()
        self.net: SumoNet = build_sumo_net(network, work_dir, config.net)
        self.params: CarParams = load_car(config.car)
        n = config.n_slots
        self.ids = [f"sumo{k}" for k in range(n)]
        self.lengths = np.full(n, self.params.length)
        self.ground_z = np.full(n, config.ground_z + self.params.cog_height)
        self._park_xy = np.stack([np.arange(n) * config.park_spacing, np.zeros(n)], axis=1)
        self._bodies = [CarBoxBody(client_id, self.params, self._park_xy[k], 0.0, config.ground_z) for k in range(n)]
        self.body_ids = np.array([b.body_id for b in self._bodies], dtype=int)
        self._placed = np.full(n, -1, dtype=np.int64)  # tick each body was last placed at; -1: parked
        self._park_all()
        self._slots = SlotStates(n)
        # road_positions' last answer per slot, kept while the slot's edge and position stay the same to the bit:
        # the edge, x, y it was for (None, NaN: none yet), then the road, arc length and lateral offset
        self._road_memo = (np.full(n, None, dtype=object), np.full(n, np.nan), np.full(n, np.nan),
                           np.full(n, "", dtype=object), np.zeros(n), np.zeros(n))
        self._events: list[dict] = []
        self._physics: list[str] = []  # SUMO ids of the physics cars' copies, by index in OtherCars
        self._physics_live: set[str] = set()  # those SUMO has now
        self._physics_routes = 0
        self._pose_cache: TrafficPoses | None = None
        self._near: tuple | None = None  # sync_near's candidates: (SUMO step, points, radius, slots)
        self._parked: tuple | None = None  # the state of the slots (see _park) whose bodies off the road are parked
        self._closed = False
        self._start(seed)
        _active = self
        try:
            self._links = self._light_links()
            self._tls_state: dict[str, str] = {}
            self._tls_at = None
            self._flows = None
            if config.demand.flows:  # their own generator: the trips draw what they drew without flows
                self._flows = FlowStreams(self._lib, config.demand.flows, self.net.road_to_edge, rng.spawn(1)[0],
                                          _TRAFFIC_TYPE, config.demand, capacity=config.n_slots - config.n_vehicles)
            self._trips = TripPool(self._lib, sorted(self.net.edge_to_road), rng, _TRAFFIC_TYPE, config.demand)
            self._trips.add(config.n_vehicles, initial=True)
            if config.n_vehicles and not self._trips.count:
                raise ValueError("SUMO traffic: no trip could be routed on this network (no two edges connected)")
            self._t_prev, self._t_next = -2 * config.period, -config.period
            self._step()  # the state at tick 0
            self._step()  # and at tick period
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ SUMO
    def _start(self, seed: int) -> None:
        cfg = self.config
        args = ["sumo", "--net-file", str(self.net.net_file), "--step-length", repr(1.0 / cfg.rate_hz),
                "--seed", str(int(seed)), "--begin", "0", "--time-to-teleport", repr(float(cfg.time_to_teleport)),
                "--collision.action", "warn", "--no-step-log", "true", "--no-warnings", "true",
                "--duration-log.disable", "true", "--xml-validation", "never", *cfg.sumo_args]
        self._lib.start(args)
        try:
            vt = self._lib.vehicletype
            vt.copy("DEFAULT_VEHTYPE", _TRAFFIC_TYPE)
            vt.setLength(_TRAFFIC_TYPE, self.params.length)
            vt.setWidth(_TRAFFIC_TYPE, self.params.width)
            vt.setHeight(_TRAFFIC_TYPE, self.params.height)
            vt.setMaxSpeed(_TRAFFIC_TYPE, self.params.max_speed)
            vt.setAccel(_TRAFFIC_TYPE, self.params.max_accel)
            vt.setEmergencyDecel(_TRAFFIC_TYPE, self.params.max_decel)
            vt.copy("DEFAULT_VEHTYPE", _PHYSICS_TYPE)
            vt.setSpeedFactor(_PHYSICS_TYPE, 1.0)
        except BaseException:
            self._lib.close()
            raise

    def _light_links(self) -> dict[tuple[str, str], list[tuple[str, int]]]:
        """(edge in, edge out) -> the (traffic light, link index) pairs of every lane-to-lane link between them."""
        lib, out = self._lib, {}
        for tls in lib.trafficlight.getIDList():
            for k, group in enumerate(lib.trafficlight.getControlledLinks(tls)):
                for lane_in, lane_out, _ in group:
                    key = (lib.lane.getEdgeID(lane_in), lib.lane.getEdgeID(lane_out))
                    if (tls, k) not in out.setdefault(key, []):
                        out[key].append((tls, k))
        return out

    def signal(self, road_in: str, road_out: str) -> str:
        """The light of the link from skytrack road ``road_in`` into ``road_out`` (:attr:`Driver.signal
        <vehicles.car.driver.Driver.signal>`): ``"r"`` when any of its lanes' links shows red or red-yellow, else
        ``"y"`` for yellow, ``"G"`` for green, ``""`` where no light controls it. The state is SUMO's after its latest
        step, which runs one step (``1 / rate_hz``) ahead of the physics."""
        to_edge = self.net.road_to_edge
        links = self._links.get((to_edge.get(road_in), to_edge.get(road_out)))
        if not links:
            return ""
        if self._tls_at != self._t_next:  # the states of SUMO's latest step, read once per light
            self._tls_state, self._tls_at = {}, self._t_next
        chars = ""
        for tls, k in links:
            state = self._tls_state.get(tls)
            if state is None:
                state = self._tls_state[tls] = self._lib.trafficlight.getRedYellowGreenState(tls)
            chars += state[k]
        if any(c in "rRu" for c in chars):
            return "r"
        if any(c in "yY" for c in chars):
            return "y"
        return "G" if any(c in "Gg" for c in chars) else ""

    def _step(self) -> None:
        """Step SUMO once: the next state becomes the previous one, the new one is read into the slots."""
        lib, slots, period = self._lib, self._slots, self.config.period
        slots.begin_step()
        if self._flows is not None:
            t = lib.simulation.getTime()
            for k in self._flows.depart(t, t + 1.0 / self.config.rate_hz):
                self._events.append({"type": "traffic_flow_refused", "flow": k, "tick": self._t_next + period})
        lib.simulation.step()
        self._t_prev, self._t_next = self._t_next, self._t_next + period
        arrived = 0
        for vid in lib.simulation.getArrivedIDList():
            self._physics_live.discard(vid)
            k = slots.release(vid)
            if k is not None:
                self._events.append({"type": "traffic_arrive", "car": k, "slot": k, "tick": self._t_next,
                                     "vehicle": vid})
            if self._trips.owns(vid):
                arrived += 1
            elif self._flows is not None and self._flows.owns(vid):
                self._flows.arrived(vid)
        for vid in lib.simulation.getDepartedIDList():
            if vid.startswith(_PHYSICS_PREFIX):
                continue
            k = slots.take(vid)
            lib.vehicle.subscribe(vid, (0x42, 0x43, 0x40, 0x50))  # position, angle, speed, road id
            self._events.append({"type": "traffic_depart", "car": k, "slot": k, "tick": self._t_next,
                                 "vehicle": vid})
        if arrived:
            self._trips.add(arrived)
        self._read_states()
        self._pose_cache = None
        self._near = None

    def _read_states(self) -> None:
        """Every occupied slot's state at the step just taken, from the vehicles' subscriptions (plain lists: this
        runs for every vehicle at every SUMO step)."""
        res = self._lib.vehicle.getAllSubscriptionResults()
        slots = self._slots
        ks = [k for k, v in enumerate(slots.vehicle) if v is not None]
        rows = [res.get(slots.vehicle[k]) or _NO_STATE for k in ks]
        roads = [r[0x50] for r in rows]
        front = np.array([r[0x42] for r in rows], dtype=float).reshape(-1, 2)
        ang = np.radians(np.array([r[0x43] for r in rows], dtype=float))
        speed = np.array([r[0x40] for r in rows], dtype=float)
        on = np.array([bool(r) for r in roads], dtype=bool)
        yaw = np.arctan2(np.cos(ang), np.sin(ang))  # pi/2 - angle, wrapped
        idx = np.array(ks, dtype=np.int64)
        half = 0.5 * self.lengths[idx]
        xy = front - half[:, None] * np.stack([np.cos(yaw), np.sin(yaw)], axis=1)
        slots.end_step(idx, xy, yaw, speed, on, roads)

    def _place_physics(self, others: OtherCars) -> None:
        """Move SUMO's copies of the physics cars to their predicted pose at the next step, inserting a copy first
        where there is none yet (the first time, or after SUMO let it arrive)."""
        lib = self._lib
        m = len(others.speed)
        while len(self._physics) > m:
            vid = self._physics.pop()
            if vid in self._physics_live:
                self._physics_live.discard(vid)
                lib.vehicle.remove(vid)
        dt = self.config.period / self.config.physics_hz
        for i in range(m):
            yaw, length = float(others.yaw[i]), float(others.length[i])
            ahead = float(others.speed[i]) * dt + 0.5 * length  # centre of mass now -> front bumper at the next step
            x = float(others.xy[i, 0]) + ahead * math.cos(yaw)
            y = float(others.xy[i, 1]) + ahead * math.sin(yaw)
            if i == len(self._physics):
                self._physics.append(f"{_PHYSICS_PREFIX}{i}")
            vid = self._physics[i]
            if vid not in self._physics_live:
                self._insert_physics(vid, others.xy[i], length)
            lib.vehicle.moveToXY(vid, "", -1, x, y, angle=math.degrees(0.5 * math.pi - yaw) % 360.0, keepRoute=2)

    def _insert_physics(self, vid: str, xy: np.ndarray, length: float) -> None:
        """Add a physics car's copy on the edge of the skytrack road nearest to it (moveToXY then places it)."""
        lib = self._lib
        road, _, _ = self.network.nearest(xy)
        route = f"{vid}_route{self._physics_routes}"
        self._physics_routes += 1
        lib.route.add(route, [self.net.road_to_edge[road]])
        lib.vehicle.add(vid, route, typeID=_PHYSICS_TYPE, depart="now")
        lib.vehicle.setLength(vid, length)
        lib.vehicle.setSpeedMode(vid, 0)
        lib.vehicle.setLaneChangeMode(vid, 0)
        self._physics_live.add(vid)

    # ------------------------------------------------------------------ the traffic source protocol
    def advance(self, tick: int, others: OtherCars) -> None:
        """At each of SUMO's ticks (multiples of the period): hand SUMO the physics cars and step it one period
        ahead; at other ticks nothing."""
        self._check_open()
        if tick % self.config.period:
            return
        while self._t_next <= tick:  # more than once only if the caller skipped some of SUMO's ticks
            if self._t_next == tick:
                self._place_physics(others)
            self._step()

    def poses(self, tick: int) -> TrafficPoses:
        """Every slot's pose at ``tick`` (between the last two SUMO steps; see :mod:`vehicles.sumo.slots`)."""
        if self._pose_cache is not None and self._pose_cache.tick == tick:
            return self._pose_cache
        if not self._t_prev <= tick <= self._t_next:
            raise ValueError(f"poses({tick}): SUMO's states cover ticks {self._t_prev}..{self._t_next}; advance() "
                             f"it first")
        alpha = (tick - self._t_prev) / self.config.period
        self._pose_cache = self._slots.poses(tick, alpha, self.config.period / self.config.physics_hz)
        return self._pose_cache

    def sync_scene(self, tick: int) -> None:
        """Place every body at its slot's pose at ``tick``; parked slots stay parked."""
        self._sync(tick, np.ones(self.config.n_slots, dtype=bool))

    def sync_near(self, tick: int, points_xy: np.ndarray, radius: float) -> None:
        """Place the bodies of the slots within ``radius`` (m) of any of ``points_xy`` (K, 2) at ``tick``, and maybe
        of a few more (each at its pose of ``tick``).

        Asked before every physics step. The candidates are found once per SUMO step and set of points: the slots
        whose disc of the step (:meth:`SlotStates.reach`, which holds the slot at every tick of the step) comes within
        ``radius`` + :data:`_NEAR_MARGIN` of a point. They hold while no point is farther than the margin from where it
        was then (a slot within ``radius`` of a point is within ``radius`` + margin of where the point was); else they
        are found again. At each tick the candidates on the road are posed, position and heading alone
        (:meth:`SlotStates.positions`: the same numbers as their rows of :meth:`poses`), and placed."""
        pts = np.asarray(points_xy, dtype=float).reshape(-1, 2)
        if not len(pts):
            return
        near = self._near
        if (near is None or near[0] != self._t_next or near[1].shape != pts.shape or near[2] != radius
                or max(math.dist(a, b) for a, b in zip(pts.tolist(), near[1].tolist(), strict=True)) > _NEAR_MARGIN):
            centre, reach = self._slots.reach()
            d2 = _nearest_d2(centre, pts)
            near = self._near = (self._t_next, pts.copy(), radius,
                                 np.flatnonzero(d2 <= (radius + _NEAR_MARGIN + reach) ** 2))
        alpha = (tick - self._t_prev) / self.config.period
        active = self._slots.active_at(alpha)
        cand = near[3]
        if len(cand):
            due = active[cand] & (self._placed[cand] != tick)
            if due.any():
                xy, yaw = self._slots.positions(alpha, cand)  # the same candidates every tick of the step
                self._place(tick, cand[due], xy[due], yaw[due])
        self._park(active, alpha)

    def _sync(self, tick: int, want: np.ndarray) -> None:
        ps = self.poses(tick)
        place = np.flatnonzero(want & ps.active & (self._placed != tick))
        if len(place):
            self._place(tick, place, ps.xy[place], ps.yaw[place])
        self._park(ps.active, (tick - self._t_prev) / self.config.period)

    def _place(self, tick: int, place: np.ndarray, xy: np.ndarray, yaw: np.ndarray) -> None:
        """Bodies of the slots ``place`` to positions ``xy`` and headings ``yaw`` (their poses at ``tick``)."""
        cid, reset = self.client_id, p.resetBasePositionAndOrientation
        bodies, zs = self.body_ids[place].tolist(), self.ground_z[place].tolist()
        xs, ys = xy[:, 0].tolist(), xy[:, 1].tolist()
        half = 0.5 * yaw
        qz, qw = np.sin(half).tolist(), np.cos(half).tolist()
        for b, x, y, bz, sz, cw in zip(bodies, xs, ys, zs, qz, qw, strict=True):
            reset(b, (x, y, bz), (0.0, 0.0, sz, cw), physicsClientId=cid)
        self._placed[place] = tick

    def _park(self, active: np.ndarray, alpha: float) -> None:
        """Park the bodies of the slots no longer on the road (``active``: :meth:`SlotStates.active_at` ``alpha``).
        Once per state of the slots: which are on the road changes only with a step or at its end (``alpha`` 1), and
        meanwhile only slots on the road are placed."""
        key = (self._t_next, alpha >= 1.0)
        if self._parked == key:
            return
        self._parked = key
        cid, z = self.client_id, self.config.park_z
        park = np.flatnonzero(~active & (self._placed >= 0))
        for k in park.tolist():
            p.resetBasePositionAndOrientation(int(self.body_ids[k]), (*self._park_xy[k], z), (0.0, 0.0, 0.0, 1.0),
                                              physicsClientId=cid)
        self._placed[park] = -1

    def _park_all(self) -> None:
        for k, b in enumerate(self._bodies):
            p.resetBasePositionAndOrientation(b.body_id, (*self._park_xy[k], self.config.park_z), (0, 0, 0, 1),
                                              physicsClientId=self.client_id)

    def road_positions(self, tick: int) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
        """(skytrack road id, arc length, lateral offset, stopped) per slot at ``tick``; road ``""`` when inactive.

        The road is the one SUMO has the vehicle on at the nearer step; inside a junction (SUMO's internal lanes)
        it is the nearest road. Arc length and offset are the projection of the pose onto that road (all slots that
        moved in one compiled call: :meth:`~worlds.roads.network.RoadNetwork.project_on` and ``nearest_many``), kept
        per slot while the slot's edge and position stay the same to the bit (vehicles waiting at junctions)."""
        ps = self.poses(tick)
        edges = np.array(self._slots.roads_at((tick - self._t_prev) / self.config.period), dtype=object)
        m_edge, m_x, m_y, m_road, m_s, m_lat = self._road_memo
        x, y = ps.xy[:, 0], ps.xy[:, 1]
        kept = ps.active & (edges == m_edge) & (x == m_x) & (y == m_y)
        redo = np.flatnonzero(ps.active & ~kept)
        roads = np.array([self.net.road_of(e) for e in edges[redo].tolist()], dtype=object)
        on = roads != ""  # on a road's edge: projected onto it; the rest are inside junctions: the nearest road
        if on.any():  # one compiled call for every slot (a city's worth of Road.project)
            k = redo[on]
            m_s[k], m_lat[k] = self.network.project_on(roads[on].tolist(), ps.xy[k])
        if not on.all():
            k = redo[~on]
            ids, m_s[k], m_lat[k] = self.network.nearest_many(ps.xy[k])
            roads[~on] = ids
        m_edge[redo], m_x[redo], m_y[redo], m_road[redo] = edges[redo], x[redo], y[redo], roads
        road_ids = np.where(ps.active, m_road, "").tolist()
        s, lat = np.where(ps.active, m_s, 0.0), np.where(ps.active, m_lat, 0.0)
        return road_ids, s, lat, ps.active & (ps.speed < _STOPPED_SPEED)

    def pop_events(self) -> list[dict]:
        """``traffic_depart`` / ``traffic_arrive`` events since the last call: ``type``, ``car`` and ``slot`` (the
        slot index), ``tick`` (the tick from which :meth:`poses` shows the change), ``vehicle`` (SUMO's id)."""
        ev, self._events = self._events, []
        return ev

    def close(self) -> None:
        """End the SUMO simulation (the scene bodies stay, parked or where they were); idempotent."""
        global _active
        if self._closed:
            return
        self._closed = True
        if _active is self:
            _active = None
            self._lib.close()

    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeError("this SUMO traffic source is closed")

    @property
    def vehicles_on_road(self) -> int:
        """Slots holding a vehicle on the road at the latest SUMO step."""
        return int(self._slots.on[1].sum())

    def __enter__(self) -> SumoTraffic:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def make_sumo_traffic(network: RoadNetwork, *, n_vehicles: int, n_slots: int | None = None, rate_hz: float = 10.0,
                      physics_hz: float = 240.0, client_id: int, rng: np.random.Generator, work_dir: str | Path,
                      car: str = "sedan", ground_z: float = 0.0, net: NetConfig | None = None,
                      demand: DemandConfig | None = None, **options: object) -> SumoTraffic:
    """A :class:`SumoTraffic` from the run's pieces: SUMO's seed is drawn from ``rng`` (``rng.integers``), the
    trips' origins and destinations from a generator spawned from it; ``n_slots`` defaults to ``n_vehicles``.

    Further keyword ``options`` are :class:`SumoTrafficConfig` fields (``park_z``, ``time_to_teleport``,
    ``sumo_args``...). Raises :class:`~vehicles.sumo._runtime.SumoUnavailable` when SUMO is not installed."""
    config = SumoTrafficConfig(n_vehicles=n_vehicles, n_slots=n_vehicles if n_slots is None else n_slots,
                               rate_hz=rate_hz, physics_hz=physics_hz, car=car, ground_z=ground_z,
                               net=net or NetConfig(), demand=demand or DemandConfig(), **options)
    seed = int(rng.integers(0, 2**31 - 1))
    trips_rng = rng.spawn(1)[0]
    return SumoTraffic(network, config, client_id=client_id, seed=seed, rng=trips_rng, work_dir=work_dir)
