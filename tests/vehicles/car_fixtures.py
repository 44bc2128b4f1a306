"""Shared helpers of the car and driver tests: analytic test roads, a small network, a kinematic driving loop and a
PyBullet client with a ground plane (imported explicitly; not a conftest)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from vehicles.car.bicycle import KinematicBicycle
from vehicles.car.driver import Driver
from vehicles.car.driver_config import DriverConfig
from vehicles.car.params import CarParams
from vehicles.car.route import Route
from vehicles.car.traffic import find_leaders


@dataclass(eq=False)
class StraightRoad:
    """Straight road from ``a`` to ``b`` (m) with twin-style lanes on the right."""

    id: str
    a: tuple[float, float]
    b: tuple[float, float]
    start_node: str
    end_node: str
    lanes: int = 1
    lane_width: float = 3.5
    speed_limit: float = 15.0
    twin: str | None = None

    @property
    def length(self) -> float:
        return float(math.dist(self.a, self.b))

    @property
    def _h(self) -> float:
        return math.atan2(self.b[1] - self.a[1], self.b[0] - self.a[0])

    def point(self, s):
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        t = np.array([math.cos(self._h), math.sin(self._h)])
        return np.asarray(self.a) + s[..., None] * t

    def heading(self, s):
        return np.full(np.shape(s), self._h) if np.ndim(s) else self._h

    def curvature(self, s):
        return np.zeros(np.shape(s)) if np.ndim(s) else 0.0

    def project(self, p_xy):
        t = np.array([math.cos(self._h), math.sin(self._h)])
        d = np.asarray(p_xy, dtype=float)[:2] - np.asarray(self.a)
        s = float(np.clip(d @ t, 0.0, self.length))
        return s, float(t[0] * d[1] - t[1] * d[0])

    def lane_offset(self, lane: int = 0) -> float:
        return -(lane + 0.5) * self.lane_width


@dataclass(eq=False)
class ArcRoad:
    """Circular arc of signed curvature ``kappa`` (1/m; + = left) from ``start`` with initial ``heading`` (rad)."""

    id: str
    start: tuple[float, float]
    heading0: float
    kappa: float
    arc_length: float
    start_node: str
    end_node: str
    lanes: int = 1
    lane_width: float = 3.5
    speed_limit: float = 15.0
    twin: str | None = None

    @property
    def length(self) -> float:
        return self.arc_length

    @property
    def centre(self) -> np.ndarray:
        r = 1.0 / self.kappa
        return np.asarray(self.start) + r * np.array([-math.sin(self.heading0), math.cos(self.heading0)])

    def point(self, s):
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        h = self.heading0 + self.kappa * s
        r = 1.0 / self.kappa
        return self.centre + r * np.stack([np.sin(h), -np.cos(h)], axis=-1)

    def heading(self, s):
        h = self.heading0 + self.kappa * np.asarray(s, dtype=float)
        return (h + np.pi) % (2 * np.pi) - np.pi

    def curvature(self, s):
        return np.full(np.shape(s), self.kappa) if np.ndim(s) else self.kappa

    def project(self, p_xy):
        r = 1.0 / self.kappa
        d = np.asarray(p_xy, dtype=float)[:2] - self.centre
        ang = math.atan2(d[1], d[0])
        a0 = self.heading0 - math.copysign(math.pi / 2, self.kappa)
        dphi = ((ang - a0) * np.sign(self.kappa)) % (2 * math.pi)
        s = float(np.clip(dphi * abs(r), 0.0, self.length))
        lateral = float(abs(r) - np.hypot(*d)) * np.sign(self.kappa)
        return s, lateral

    def lane_offset(self, lane: int = 0) -> float:
        return -(lane + 0.5) * self.lane_width


@dataclass
class SimpleNetwork:
    """Road graph over test roads; random walks draw uniformly among successors."""

    roads: dict = field(default_factory=dict)

    def add(self, road) -> None:
        self.roads[road.id] = road

    def successors(self, road_id: str) -> list[str]:
        end = self.roads[road_id].end_node
        return [r.id for r in self.roads.values() if r.start_node == end]

    def random_route(self, start_road: str, n_roads: int, rng: np.random.Generator) -> list[str]:
        out = [start_road]
        while len(out) < n_roads:
            nxt = self.successors(out[-1])
            if not nxt:
                break
            out.append(nxt[int(rng.integers(len(nxt)))])
        return out


def s_curve_network(speed_limit: float = 15.0) -> SimpleNetwork:
    """Straight 60 m, left arc R = 40 m over 90 deg, straight 40 m, right arc R = 25 m over 90 deg, straight 80 m,
    chained with tangent continuity (no heading jumps at the nodes)."""
    net = SimpleNetwork()
    p, h = (0.0, 0.0), 0.0
    pieces = [("a", 0.0, 60.0), ("b", 1 / 40, 40 * math.pi / 2), ("c", 0.0, 40.0), ("d", -1 / 25, 25 * math.pi / 2),
              ("e", 0.0, 80.0)]
    for i, (rid, k, length) in enumerate(pieces):
        if k == 0.0:
            end = (p[0] + length * math.cos(h), p[1] + length * math.sin(h))
            road = StraightRoad(id=rid, a=p, b=end, start_node=f"n{i}", end_node=f"n{i + 1}", speed_limit=speed_limit)
        else:
            road = ArcRoad(id=rid, start=p, heading0=h, kappa=k, arc_length=length, start_node=f"n{i}",
                           end_node=f"n{i + 1}", speed_limit=speed_limit)
        net.add(road)
        p = tuple(road.point(road.length).tolist())
        h = float(road.heading(road.length))
    return net


@dataclass
class KinematicRun:
    """Time series of a kinematic multi-car run, one row per physics tick."""

    p_xy: np.ndarray
    yaw: np.ndarray
    speed: np.ndarray
    road: list
    stopped: np.ndarray
    events: list


def run_kinematic(network, params: CarParams, config: DriverConfig, routes: list[Route], seconds: float,
                  seed: int = 0, physics_hz: int = 240, speeds: list[float] | None = None) -> KinematicRun:
    """Drive kinematic bicycles with one shared driver config (and IDM leaders) for ``seconds``."""
    return run_kinematic_multi(network, params, [config] * len(routes), routes, seconds, seed, physics_hz, speeds)


def run_kinematic_multi(network, params: CarParams, configs: list[DriverConfig], routes: list[Route], seconds: float,
                        seed: int = 0, physics_hz: int = 240, speeds: list[float] | None = None) -> KinematicRun:
    """Drive kinematic bicycles with drivers (and IDM leaders) for ``seconds``; returns per-tick series."""
    config = configs[0]
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(len(routes))]
    drivers = [Driver(config=c, params=params, route=r, network=network, rng=g, physics_hz=physics_hz)
               for c, r, g in zip(configs, routes, rngs, strict=True)]
    cars = []
    for i, d in enumerate(drivers):
        p, yaw = d.spawn_pose()
        cars.append(KinematicBicycle(params, p, yaw, 0.0 if speeds is None else speeds[i]))
    every = config.ticks_per_update(physics_hz)
    n = int(round(seconds * physics_hz))
    P, Y, V, S, roads, events = np.zeros((n, len(cars), 2)), np.zeros((n, len(cars))), np.zeros((n, len(cars))), \
        np.zeros((n, len(cars)), dtype=bool), [], []
    for tick in range(n):
        for c, d in zip(cars, drivers, strict=True):
            c.step(d.command, 1.0 / physics_hz)
        if tick % every == 0:
            p_all = np.array([c.p_xy for c in cars])
            yaw_all = np.array([c.yaw for c in cars])
            v_all = np.array([c.speed for c in cars])
            leaders = find_leaders(drivers, p_all, yaw_all, v_all, [params.length] * len(cars))
            for i, (c, d) in enumerate(zip(cars, drivers, strict=True)):
                d.update(c.p_xy, c.yaw, c.speed, tick, leaders[i], c.yaw_rate)
                events += [dict(e, car=i) for e in d.pop_events()]
        P[tick] = [c.p_xy for c in cars]
        Y[tick] = [c.yaw for c in cars]
        V[tick] = [c.speed for c in cars]
        S[tick] = [d.stopped for d in drivers]
        roads.append([d.road_id for d in drivers])
    return KinematicRun(P, Y, V, roads, S, events)



def bullet_client(physics_hz: int = 240) -> int:
    """A DIRECT PyBullet client with gravity, a fixed time step 1 / physics_hz, the scene's contact breaking threshold
    and constraint-solver iterations, and a ground plane (friction 1)."""
    import pybullet as p

    from simulator.scene import SceneConfig

    c = p.connect(p.DIRECT)
    p.setGravity(0, 0, -9.81, physicsClientId=c)
    p.setTimeStep(1.0 / physics_hz, physicsClientId=c)
    # the simulator's contact settings, so these tests check the car the runs drive
    scene = SceneConfig()
    p.setPhysicsEngineParameter(contactBreakingThreshold=scene.contact_breaking_threshold,
                                numSolverIterations=scene.solver_iterations, physicsClientId=c)
    plane = p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=c), physicsClientId=c)
    p.changeDynamics(plane, -1, lateralFriction=1.0, physicsClientId=c)
    return c


@dataclass
class FleetRun:
    """Per-tick series of a physics fleet run (every ``stride`` ticks)."""

    p_W: np.ndarray
    yaw: np.ndarray
    speed: np.ndarray
    roll_pitch: np.ndarray
    road: list
    stopped: np.ndarray
    events: list


def run_fleet(fleet, client_id: int, seconds: float, physics_hz: int = 240, stride: int = 6) -> FleetRun:
    """Step ``fleet`` through the run loop for ``seconds``; record the state every ``stride`` ticks."""
    import pybullet as p

    n = int(round(seconds * physics_hz))
    P, Y, V, RP, roads, S, events = [], [], [], [], [], [], []
    for tick in range(1, n + 1):
        fleet.apply_actuation()
        p.stepSimulation(physicsClientId=client_id)
        fleet.after_step(tick)
        if tick % stride == 0:
            st = fleet.state
            P.append(st.p_W), Y.append(st.yaw), V.append(st.speed), roads.append(st.road_id), S.append(st.stopped)
            RP.append([p.getEulerFromQuaternion(q)[:2] for q in st.q_WB])
        events += fleet.pop_events()
    return FleetRun(np.array(P), np.array(Y), np.array(V), np.array(RP), roads, np.array(S), events)


def curvy_network():
    """A real spline road network: a curvy two-way street 'curvy' joined to a straight 'tail' street.

    The centre-line samples, every 10 m, y = 30 sin(2 pi x / 350) m for x in [0, 350] m (radius >= 103 m, faster than
    the 15 m/s limit) and then y = 20 sin(2 pi (x - 350) / 160) m for x in [350, 670] m (radius >= 32 m); each vertex
    turns by under 20 degrees, so the spline passes smoothly through all of them.
    """
    from worlds.roads.network import RoadNetwork

    x1 = np.arange(10.0, 350.0, 10.0)
    x2 = np.arange(350.0, 670.0, 10.0)
    via = np.r_[np.c_[x1, 30 * np.sin(2 * np.pi * x1 / 350)], np.c_[x2, 20 * np.sin(2 * np.pi * (x2 - 350) / 160)]]
    spec = {"nodes": {"A": [0.0, 0.0], "B": [670.0, 0.0], "C": [790.0, 60.0]},
            "streets": [{"id": "curvy", "nodes": ["A", "B"], "speed_limit": 15.0, "via": via.tolist()},
                        {"id": "tail", "nodes": ["B", "C"], "speed_limit": 15.0}]}
    return RoadNetwork.from_spec(spec)


def grid_network(n: int = 3, spacing: float = 120.0, speed_limit: float = 13.9):
    """A real n x n grid of two-way straight streets (``RoadNetwork.from_spec``); nodes ``"i_j"``."""
    from worlds.roads.network import RoadNetwork

    nodes = {f"{i}_{j}": [i * spacing, j * spacing] for i in range(n) for j in range(n)}
    streets = []
    for i in range(n):
        for j in range(n):
            if i + 1 < n:
                streets.append({"id": f"h{i}_{j}", "nodes": [f"{i}_{j}", f"{i + 1}_{j}"], "speed_limit": speed_limit})
            if j + 1 < n:
                streets.append({"id": f"v{i}_{j}", "nodes": [f"{i}_{j}", f"{i}_{j + 1}"], "speed_limit": speed_limit})
    return RoadNetwork.from_spec({"nodes": nodes, "streets": streets})
