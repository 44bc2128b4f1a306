"""A world, built: the PyBullet scene, the vehicle fleets, each UAV's sensors and agent, and one tick of the run
loop."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pybullet as p

from autonomy.agent import Agent
from autonomy.estimation.setmem.tracker import SetMembershipTracker
from autonomy.estimation.tracker import SingleTargetTracker
from autonomy.fusion.base_station import InformationReporter
from autonomy.fusion.hcmci_team import HcmciConfig, HcmciTeam
from autonomy.fusion.measurement_sharing import DetectionMessage, relayed
from autonomy.fusion.track_fusion import TrackFusion, TrackFusionConfig
from autonomy.guidance.setpoints import UnicycleSetpoint, VelocitySetpoint
from autonomy.guidance.types import OwnState, TargetEstimate, TeammateState
from autonomy.sensing.camera import CAR_RGBA
from autonomy.sensing.channel import scheduled_links
from autonomy.sensing.measurement import Sensor
from autonomy.sensing.messages import EstimateMessage, StateMessage
from autonomy.sensing.scene import SensorPose, TargetTruth
from simulator.clock import Clock
from simulator.decoys import StaticDecoys, build_decoys
from simulator.registry import build_estimator, build_guidance, build_sensor
from simulator.record import RunRecorder
from simulator.scene import Scene, SceneConfig
from simulator.scene_query import PybulletSceneQuery
from simulator.search_team import SearchTeamRun
from simulator.seeding import RunSeeds
from vehicles.quadrotor.commands import UnicycleCommand, VelocityCommand
from worlds.build import build_geometry
from worlds.errors import WorldError, WorldIssue
from worlds.loader import LoadedWorld

__all__ = ["Assembly", "Prepared", "WALL_PHASES", "build_assembly", "prepare"]

# phases of a tick whose wall time a run reports (metrics ``wall_time_breakdown_s``): actuation and low-level control
# of all vehicles, the PyBullet step, sensors (with their raycasts), the agents (estimation, fusion, guidance and the
# messages between them), recording (events, truth, collision checks)
WALL_PHASES = ("vehicles", "physics", "sensors", "autonomy", "record")


@dataclass
class SensorSlot:
    uav: int
    sensor: Sensor
    divisor: int
    rng: np.random.Generator
    name: str


@dataclass
class AgentSlot:
    uav: int
    agent: Agent
    divisor: int
    hcmci: bool = False  # estimates as a member of the HCMCI consensus team
    measurements: bool = False  # takes the teammates' detections (fusion method measurements)
    search: bool = False  # a set-membership searcher: steps with the search team
    fuse_sets: bool = False  # ... and fuses its sets with the teammates it is linked to (fusion method sets)


@dataclass
class Assembly:
    """Everything a run steps, with the tick of DESIGN.md in :meth:`step`."""

    clock: Clock
    scene: Scene
    recorder: RunRecorder
    buildings: list
    network: Any
    quads: Any
    cars: Any
    uav_ids: list[str]
    car_ids: list[str]
    car_kinds: tuple[str, ...]
    target_index: int | None
    scene_query: PybulletSceneQuery
    sensors: list[SensorSlot] = field(default_factory=list)
    agents: list[AgentSlot] = field(default_factory=list)
    record_div: int = 12
    latest_estimates: dict[int, Any] = field(default_factory=dict)
    latest_local: dict[int, Any] = field(default_factory=dict)
    latest_setpoints: dict[int, Any] = field(default_factory=dict)
    world_spec: Any = None
    channel: Any = None
    _outage_ticks: list = field(default_factory=list)
    _heard: dict = field(default_factory=dict)
    _shared: dict = field(default_factory=dict)
    _local: dict = field(default_factory=dict)
    _sharing: bool = False
    event_counts_by_uav: dict = field(default_factory=dict)
    _contacts: set = field(default_factory=set)
    hcmci: HcmciTeam | None = None
    consensus_linked_steps: dict[int, int] = field(default_factory=dict)  # per UAV: team steps with a link up
    consensus_links: list[int] = field(default_factory=list)  # per team step: links up between nodes with a track
    wall_s: dict[str, float] = field(default_factory=lambda: dict.fromkeys(WALL_PHASES, 0.0))  # wall time per phase
    shared_received: dict[int, int] = field(default_factory=dict)  # per UAV: teammates' detections delivered to it
    decoys: StaticDecoys | None = None
    search: SearchTeamRun | None = None
    base_station: Any = None  # simulator.base_station.BaseStation when UAVs fuse at the base (paper 001)

    # -- truth ---------------------------------------------------------------------------------------------------
    def target_truth(self) -> TargetTruth:
        """The ground vehicles, then the static decoys (rows ``len(car_ids) + k``; cars' cone rows are unused)."""
        if self.cars is None and self.decoys is None:
            return TargetTruth.empty()
        if self.cars is None:
            p, v, yaw, kinds, segs = np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), (), np.zeros(0, int)
        else:
            st = self.cars.state
            p, v, yaw, kinds, segs = st.p_W, st.v_W, np.asarray(st.yaw), self.car_kinds, np.asarray(self.cars.body_ids)
        if self.decoys is None:
            return TargetTruth(ids=np.arange(len(kinds)), p_W=p, v_W=v, kind=kinds, yaw=yaw, seg_ids=segs)
        d, n = self.decoys, len(kinds)
        return TargetTruth(ids=np.arange(n + len(d)), p_W=np.vstack([p, d.p_W]),
                           v_W=np.vstack([v, np.zeros((len(d), 3))]), kind=(*kinds, *("decoy",) * len(d)),
                           yaw=np.concatenate([yaw, d.yaw]),
                           cone_axis_W=np.vstack([np.tile([0.0, 0.0, 1.0], (n, 1)), d.cone_axis_W]),
                           cone_half_angle=np.concatenate([np.full(n, np.pi), d.cone_half_angle]),
                           seg_ids=np.concatenate([segs, d.body_ids]))

    def own_state(self, i: int, t: float) -> OwnState:
        st = self.quads.state
        return OwnState(t=t, p_W=st.p_W[i], v_W=st.v_W[i], yaw=_yaw(st.q_WB[i]))

    def inbox(self, i: int, t: float, tick: int) -> tuple[list[TeammateState], list[TargetEstimate]]:
        """What UAV ``i`` knows of its team: states and shared target estimates.

        Perfect comms: the teammates' true states and their latest local estimates. Radio: the last of each that got
        through the channel.
        """
        shared = self._shared.setdefault(i, {})
        if self.channel is None:
            st = self.quads.state
            mates = [TeammateState(id=j, t=t, p_W=st.p_W[j], v_W=st.v_W[j], yaw=_yaw(st.q_WB[j]))
                     for j in range(len(self.uav_ids)) if j != i]
            estimates = [e for j, e in self._local.items() if j != i and e is not None]
            return mates, estimates
        known = self._heard.setdefault(i, {})
        for env in self.channel.receive(self.uav_ids[i], tick):
            msg = env.message
            j = self.uav_ids.index(msg.sender)
            if isinstance(msg, StateMessage):
                known[j] = TeammateState(id=j, t=msg.t_sent, p_W=msg.p_W, v_W=msg.v_W, yaw=msg.yaw,
                                         plan_p_W=msg.plan_p_W, plan_dt=msg.plan_dt)
            elif isinstance(msg, EstimateMessage):
                n = msg.x.size // 2
                shared[j] = TargetEstimate(t=msg.t_estimate, p_W=msg.x[:n], v_W=msg.x[n:], P=msg.P)
            elif isinstance(msg, DetectionMessage):
                self._deliver_detections(i, relayed(msg.detections, env.t_arrival - msg.t_sent))
        return [known[j] for j in sorted(known)], [shared[j] for j in sorted(shared)]

    def _share_estimate(self, i: int, est: TargetEstimate | None, t: float, tick: int) -> None:
        if self.channel is None:
            self._local[i] = est
            return
        if est is None or est.P is None:
            return
        st = self.quads.state
        msg = EstimateMessage(sender=self.uav_ids[i], receiver=None, t_sent=t, target_id=0,
                              x=np.concatenate([est.p_W, est.v_W]), P=est.P, t_estimate=est.t)
        self.channel.send(msg, self._positions(st), tick)

    def _positions(self, st: Any) -> dict[str, np.ndarray]:
        """Every UAV's position by id in the fleet state ``st``: where the radio sends from and to."""
        return {u: st.p_W[k] for k, u in enumerate(self.uav_ids)}

    def _share_detections(self, i: int, detections: list, t: float, tick: int) -> None:
        """Send UAV ``i``'s ``detections`` to the teammates that take them (fusion method measurements): over the radio
        (loss and delay; they arrive in :meth:`inbox`), or under perfect comms at once to the teammates that
        ``comms.links`` joins to ``i`` without an outage at ``tick``."""
        takers = [a.uav for a in self.agents if a.measurements and a.uav != i]
        if not detections or not takers:
            return
        if self.channel is None:
            up = scheduled_links(self.uav_ids, self.world_spec.comms.links, self._outage_ticks, tick)
            for j in takers:
                if up[i, j]:
                    self._deliver_detections(j, relayed(detections, 0.0))
            return
        positions = self._positions(self.quads.state)
        for j in takers:
            self.channel.send(DetectionMessage(sender=self.uav_ids[i], receiver=self.uav_ids[j], t_sent=t,
                                               detections=tuple(detections)), positions, tick)

    def _deliver_detections(self, j: int, detections: list) -> None:
        if self.agents[j].measurements:
            self.agents[j].agent.receive(detections)
            self.shared_received[j] = self.shared_received.get(j, 0) + len(detections)

    def _broadcast_state(self, i: int, t: float, tick: int) -> None:
        st = self.quads.state
        plan = getattr(self.agents[i].agent.guidance, "planned_path", lambda: None)()
        msg = StateMessage(sender=self.uav_ids[i], receiver=None, t_sent=t, p_W=st.p_W[i].copy(),
                           v_W=st.v_W[i].copy(), yaw=_yaw(st.q_WB[i]), plan_p_W=plan,
                           plan_dt=float(getattr(getattr(self.agents[i].agent.guidance, "config", None), "dt", 1.0)))
        self.channel.send(msg, self._positions(st), tick)

    def links_up(self, uavs: list[int], tick: int) -> np.ndarray:
        """(n, n) bool: which links between ``uavs`` (indices) are up at ``tick``. Radio: one erasure draw per link
        (fixed topology, range, blockage and outages included); perfect comms: the pairs of ``comms.links`` (every
        pair without it) less the scheduled outages, and less the pairs a building stands between when
        ``comms.block_by_buildings``."""
        ids = [self.uav_ids[j] for j in uavs]
        if self.channel is not None:
            st = self.quads.state
            return self.channel.sample_links(ids, {u: st.p_W[j] for u, j in zip(ids, uavs, strict=True)}, tick)
        up = scheduled_links(ids, self.world_spec.comms.links, self._outage_ticks, tick)
        if self.world_spec.comms.block_by_buildings and len(uavs) > 1:
            p_W = self.quads.state.p_W[uavs]
            iu, ju = np.triu_indices(len(uavs), k=1)
            clear = np.asarray(self.scene_query.line_of_sight(p_W[iu], p_W[ju]), dtype=bool)
            up[iu[~clear], ju[~clear]] = up[ju[~clear], iu[~clear]] = False
        return up

    def _team_step(self, t: float, tick: int, slots: list[AgentSlot]) -> dict[int, tuple[Any, int]]:
        """Estimation of the HCMCI agents due at ``tick``, as one team: each UAV's (estimate, detections used)."""
        if not slots:
            return {}
        uavs = [a.uav for a in slots]
        ready = [a.agent.take_ready(t) for a in slots]
        estimates, fused = self.hcmci.step(t, [a.agent.estimator for a in slots], ready, self.links_up(uavs, tick))
        for j, degree in zip(uavs, fused.adjacency.sum(axis=1), strict=True):  # a cut-off node fuses only itself
            self.consensus_linked_steps[j] = self.consensus_linked_steps.get(j, 0) + bool(degree > 0)
        self.consensus_links.append(fused.active_links)
        return {j: (est, len(r)) for j, est, r in zip(uavs, estimates, ready, strict=True)}

    def _outage_events(self, tick: int, t: float) -> None:
        for a, b, start, end in self._outage_ticks:
            if tick == max(start, 1):
                self._event(tick, t, {"type": "link_outage_start", "link": [a, b]})
            elif tick == end:
                self._event(tick, t, {"type": "link_outage_end", "link": [a, b]})

    # -- the tick ------------------------------------------------------------------------------------------------
    def step(self, tick: int) -> None:
        wall, clock = self.wall_s, time.perf_counter
        t0 = clock()
        fleets = [f for f in (self.quads, self.cars) if f is not None]
        for f in fleets:                       # 1. actuators
            f.apply_actuation()
        t1 = clock()
        self.scene.step()                      # 2. physics
        t2 = clock()
        for f in fleets:                       # 3. low-level controllers
            f.after_step(tick)
        t3 = clock()
        wall["vehicles"] += (t1 - t0) + (t3 - t2)
        wall["physics"] += t2 - t1
        t = self.clock.time(tick)
        due = [slot for slot in self.sensors if tick % slot.divisor == 0]
        if due:                                # 4. sensors
            truth = self.target_truth()
            st = self.quads.state
            for slot in due:
                pose = SensorPose(p_W=st.p_W[slot.uav], q_WB=st.q_WB[slot.uav], v_W=st.v_W[slot.uav])
                out = slot.sensor.measure(t, pose, truth, self.scene_query, slot.rng)
                self._record_detections(tick, t, slot, out)
                for a in self.agents:
                    if a.uav == slot.uav:
                        a.agent.receive(out.detections)
                if self.search is not None:
                    self.search.on_scan(slot.uav, t, slot.sensor.latency_s, out)
                self._share_detections(slot.uav, list(out.detections), t, tick)
        t4 = clock()
        wall["sensors"] += t4 - t3
        agents = [a for a in self.agents if tick % a.divisor == 0]
        team = self._team_step(t, tick, [a for a in agents if a.hcmci])  # 5. agents: the consensus team estimates,
        searched = self.search.step(self, t, tick, [a for a in agents if a.search]) if self.search else {}
        for a in agents:  # the search team runs its whole step; then every other agent fuses and plans
            mates, shared = self.inbox(a.uav, t, tick)
            own = self.own_state(a.uav, t)
            if a.uav in searched:
                result = searched[a.uav]
            elif a.uav in team:
                result = a.agent.act(t, own, mates, *team[a.uav])
            else:
                result = a.agent.step(t, own, mates, shared if a.agent.fusion is not None else ())
            self.quads.set_command(a.uav, _to_command(result.setpoint))
            if self.channel is not None:  # after planning, so the plan sent starts from the state sent
                self._broadcast_state(a.uav, t, tick)
            if self._sharing:
                self._share_estimate(a.uav, result.local_estimate, t, tick)
            self.latest_estimates[a.uav] = result.estimate
            self.latest_local[a.uav] = result.local_estimate
            self.latest_setpoints[a.uav] = result.setpoint
            self._record_agent(tick, t, a.uav, result)
        if self.base_station is not None and agents:  # their scans' information goes to the base over the radio
            self.base_station.step(tick, t, self._positions(self.quads.state), [a.uav for a in agents])
        t5 = clock()
        wall["autonomy"] += t5 - t4
        if self._outage_ticks:
            self._outage_events(tick, t)
        for f in fleets:                       # 6. record
            for ev in f.pop_events():
                self._event(tick, t, dict(ev))
        if tick % self.record_div == 0:
            self._record_truth(tick, t)
            self._check_collisions(tick, t)
        wall["record"] += clock() - t5

    # -- recording -----------------------------------------------------------------------------------------------
    def _record_truth(self, tick: int, t: float) -> None:
        if self.quads is not None:
            st = self.quads.state
            n = len(self.uav_ids)
            self.recorder.append_rows("uav_truth", {
                "tick": np.full(n, tick), "t": np.full(n, t), "uav": np.arange(n),
                "x": st.p_W[:, 0], "y": st.p_W[:, 1], "z": st.p_W[:, 2],
                "qx": st.q_WB[:, 0], "qy": st.q_WB[:, 1], "qz": st.q_WB[:, 2], "qw": st.q_WB[:, 3],
                "vx": st.v_W[:, 0], "vy": st.v_W[:, 1], "vz": st.v_W[:, 2]})
        if self.cars is not None:
            st = self.cars.state
            n = len(self.car_ids)
            self.recorder.append_rows("vehicle_truth", {
                "tick": np.full(n, tick), "t": np.full(n, t), "vehicle": np.arange(n),
                "x": st.p_W[:, 0], "y": st.p_W[:, 1], "z": st.p_W[:, 2], "yaw": np.asarray(st.yaw),
                "vx": st.v_W[:, 0], "vy": st.v_W[:, 1], "vz": st.v_W[:, 2],
                "ax": st.a_W[:, 0], "ay": st.a_W[:, 1], "az": st.a_W[:, 2], "speed": np.asarray(st.speed),
                "road": np.asarray(list(st.road_id), dtype=str), "s": np.asarray(st.s),
                "lateral": np.asarray(st.lateral)})

    def _record_detections(self, tick: int, t: float, slot: SensorSlot, out: Any) -> None:
        for d, tid in zip(out.detections, out.truth_ids, strict=True):
            z = np.full(4, np.nan)
            z[: min(4, d.z.size)] = d.z[:4]
            self.recorder.append("detections", tick=tick, t_meas=d.t_meas, t_arrival=d.t_arrival, uav=slot.uav,
                                 sensor=slot.name, kind=d.kind, truth_id=int(tid),
                                 z0=z[0], z1=z[1], z2=z[2], z3=z[3])

    def _record_agent(self, tick: int, t: float, uav: int, result: Any) -> None:
        estimator = self.agents[uav].agent.estimator
        road = (getattr(estimator, "road_id", None) or "") if getattr(estimator, "on_road", False) else ""
        self.recorder.append("estimates", **_estimate_row(tick, t, uav, result.local_estimate, result.used_detections,
                                                          str(road)))
        if self.agents[uav].measurements:
            self._record_sharing(tick, t, uav, estimator)
        if self.agents[uav].agent.fusion is not None:
            self.recorder.append("fused_estimates", **_estimate_row(tick, t, uav, result.estimate, 0))
        sp = result.setpoint
        cmd = {"tick": tick, "t": t, "uav": uav, "kind": type(sp).__name__, "speed": np.nan, "heading_rate": np.nan,
               "altitude": np.nan, "vx": np.nan, "vy": np.nan, "vz": np.nan}
        if isinstance(sp, UnicycleSetpoint):
            cmd.update(speed=sp.speed, heading_rate=sp.heading_rate, altitude=sp.altitude)
        elif isinstance(sp, VelocitySetpoint):
            cmd.update(vx=sp.v_W[0], vy=sp.v_W[1], vz=sp.v_W[2])
        self.recorder.append("commands", **cmd)

    def _record_sharing(self, tick: int, t: float, uav: int, estimator: Any) -> None:
        """``measurement_sharing``: per agent step, the teammates' detections delivered to UAV ``uav`` so far and those
        its tracker's updates used so far (counted by the sensor ids that are not the UAV's own)."""
        own = {s.name for s in self.sensors if s.uav == uav}
        used = getattr(estimator, "used_by_sensor", {})
        self.recorder.append("measurement_sharing", tick=tick, t=t, uav=uav,
                             received=self.shared_received.get(uav, 0),
                             own_used=sum(n for k, n in used.items() if k in own),
                             mates_used=sum(n for k, n in used.items() if k not in own))

    def _check_collisions(self, tick: int, t: float) -> None:
        if self.quads is None:
            return
        now = set()
        names = self._body_names()
        for i, body in enumerate(self.quads.body_ids):
            for c in p.getContactPoints(bodyA=int(body), physicsClientId=self.scene.client):
                other = c[2]
                now.add((i, other))
        for i, other in sorted(now - self._contacts):
            self._event(tick, t, {"type": "collision", "uav": i, "uav_id": self.uav_ids[i],
                                  "other": names.get(other, f"body {other}")})
        self._contacts = now

    def _event(self, tick: int, t: float, ev: dict) -> None:
        kind = ev.pop("type")
        if "uav" in ev:
            key = (kind, int(ev["uav"]))
            self.event_counts_by_uav[key] = self.event_counts_by_uav.get(key, 0) + 1
        self.recorder.event(kind, tick, t, **ev)

    def _body_names(self) -> dict[int, str]:
        names = {self.scene.ground_id: "ground"}
        names.update({b: "building" for b in self.scene.building_ids})
        if self.quads is not None:
            names.update({int(b): f"uav {u}" for b, u in zip(self.quads.body_ids, self.uav_ids, strict=True)})
        if self.cars is not None:
            names.update({int(b): f"vehicle {c}" for b, c in zip(self.cars.body_ids, self.car_ids, strict=True)})
        return names

    def close(self) -> None:
        self.scene.close()


def _estimate_row(tick: int, t: float, uav: int, est: TargetEstimate | None, used: int, road: str = "") -> dict:
    """One row of ``estimates``; ``road`` is the road a road-constrained estimator holds the target on ("" off the
    map or for unconstrained estimators)."""
    row = {"tick": tick, "t": t, "uav": uav, "valid": est is not None, "x": np.nan, "y": np.nan,
           "vx": np.nan, "vy": np.nan, "pxx": np.nan, "pxy": np.nan, "pyy": np.nan, "pvxvx": np.nan,
           "pvyvy": np.nan, "detections": used, "road": road}
    if est is not None:
        row.update(x=est.p_W[0], y=est.p_W[1], vx=est.v_W[0], vy=est.v_W[1])
        if est.P is not None:
            n = est.p_W.size
            row.update(pxx=est.P[0, 0], pxy=est.P[0, 1], pyy=est.P[1, 1], pvxvx=est.P[n, n], pvyvy=est.P[n + 1, n + 1])
    return row


def _yaw(q: np.ndarray) -> float:
    x, y, z, w = q
    return float(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


def _to_command(sp: Any) -> Any:
    if isinstance(sp, UnicycleSetpoint):
        return UnicycleCommand(speed=sp.speed, heading_rate=sp.heading_rate, altitude=sp.altitude)
    if isinstance(sp, VelocitySetpoint):
        return VelocityCommand(v_W=sp.v_W, yaw=sp.yaw)
    raise TypeError(f"guidance returned {type(sp).__name__}; expected UnicycleSetpoint or VelocitySetpoint")


@dataclass
class Prepared:
    """Everything built before the physics starts: geometry and the autonomy of each UAV (fails fast on bad input)."""

    loaded: LoadedWorld
    clock: Clock
    geometry: Any
    sensors: list[SensorSlot]
    agents: list[AgentSlot]
    hcmci: HcmciTeam | None = None


def prepare(loaded: LoadedWorld, clock: Clock, seeds: RunSeeds, options: Any) -> Prepared:
    """Build geometry, sensors, estimators and guidance; raises :class:`WorldError` naming the entry on a bad one."""
    from vehicles.quadrotor.airframes import load_airframe

    world = loaded.world
    geometry = build_geometry(world, loaded.path, seeds.generator("world/town"))
    issues = []
    for i, u in enumerate(world.uavs):
        try:
            load_airframe(u.airframe)
        except (KeyError, ValueError) as exc:
            issues.append(WorldIssue(f"uavs[{i}].airframe", u.airframe, f"a known airframe ({exc})"))
    if issues:
        raise WorldError(str(loaded.path), issues)
    sensors, agents, team = [], [], None
    for i, u in enumerate(world.uavs):
        for j, spec in enumerate(u.sensors):
            name = spec.id or f"{u.id}/{spec.type}{j}"
            where = f"uavs[{i}].sensors[{j}]"
            sensor = _checked(loaded, where, spec, lambda: build_sensor(spec, name, geometry.buildings))
            sensors.append(SensorSlot(uav=i, sensor=sensor, name=name, divisor=clock.divisor(spec.rate_hz, where),
                                      rng=seeds.generator(f"sensor/{u.id}/{j}")))
        if options.estimator_factory is not None:
            estimator = options.estimator_factory(i, u)
        else:
            estimator = _checked(loaded, f"uavs[{i}].autonomy.estimator", u.autonomy.estimator,
                                 lambda: build_estimator(u, i, geometry.network, geometry.buildings))
        if options.guidance_factory is not None:
            guidance = options.guidance_factory(i, u)
        else:
            guidance = _checked(loaded, f"uavs[{i}].autonomy.guidance", u.autonomy.guidance,
                                lambda: build_guidance(u, i, len(world.uavs), geometry.buildings, world.comms,
                                                       estimator))
        fusion, f = None, u.autonomy.fusion
        if f.method == "hcmci":
            _check_information_tracker(loaded, i, estimator, f.method)
            team = HcmciTeam(HcmciConfig(rounds=f.rounds, gain=f.b))  # one config for all: worlds.checks
        elif f.method == "base_station":
            _check_information_tracker(loaded, i, estimator, f.method)
            estimator = InformationReporter(estimator)
        elif f.method not in ("none", "measurements", "sets"):
            fusion = TrackFusion(TrackFusionConfig(method=f.method, max_age_s=f.max_age_s, q=f.q))
        agents.append(AgentSlot(uav=i, agent=Agent(u.id, estimator, guidance, fusion=fusion),
                                divisor=clock.divisor(u.autonomy.rate_hz, f"uavs[{i}].autonomy.rate_hz"),
                                hcmci=f.method == "hcmci", measurements=f.method == "measurements",
                                search=isinstance(estimator, SetMembershipTracker), fuse_sets=f.method == "sets"))
    return Prepared(loaded=loaded, clock=clock, geometry=geometry, sensors=sensors, agents=agents,
                    hcmci=team)


def _check_information_tracker(loaded: LoadedWorld, i: int, estimator: Any, method: str) -> None:
    """HCMCI and base-station fusion need the built-in tracker with the information filter (also when an estimator was
    passed in code)."""
    if not (isinstance(estimator, SingleTargetTracker) and estimator.config.filter == "scif"):
        raise WorldError(str(loaded.path), [WorldIssue(
            f"uavs[{i}].autonomy.estimator", type(estimator).__name__,
            f"the built-in tracker with the scif filter: fusion method {method} fuses its information")])


def _checked(loaded: LoadedWorld, where: str, spec: Any, build: Any) -> Any:
    try:
        return build()
    except WorldError:
        raise
    except (ValueError, TypeError, KeyError, ImportError) as exc:
        value = spec.model_dump(exclude_defaults=True) if hasattr(spec, "model_dump") else spec
        raise WorldError(str(loaded.path), [WorldIssue(where, value, f"a valid configuration ({exc})")]) from None


def build_assembly(prep: Prepared, seeds: RunSeeds, recorder: RunRecorder) -> Assembly:
    """Start PyBullet and build the scene and the fleets of a prepared world."""
    from simulator.base_station import build_base_station
    from simulator.factories import build_car_fleet, build_channel, fleet_options
    from vehicles.quadrotor.airframes import load_airframe
    from vehicles.quadrotor.fleet import QuadrotorFleet

    world, clock, geometry = prep.loaded.world, prep.clock, prep.geometry
    scene = Scene.create(SceneConfig(physics_hz=clock.physics_hz, gravity=world.environment.gravity,
                                     ground_size=tuple(world.terrain.size)))
    scene.add_buildings(geometry.buildings)
    if geometry.road_mesh is not None:
        scene.add_road_surface(geometry.road_mesh)

    quads = None
    if world.uavs:
        airframes = [load_airframe(u.airframe) for u in world.uavs]
        p0 = np.array([u.initial.position for u in world.uavs], dtype=float)
        yaw0 = np.radians([u.initial.yaw_deg for u in world.uavs])
        quads = QuadrotorFleet(scene.client, airframes, p0, yaw0, clock.physics_hz, fleet_options(world),
                               seeds.generator("vehicles/quadrotors"))
    cars, car_kinds = None, ()
    if world.ground_vehicles:
        cars = build_car_fleet(world, geometry.network, scene.client, clock.physics_hz,
                               seeds.generator("vehicles/cars"))
        car_kinds = tuple("decoy" if g.role == "decoy" else "car" for g in world.ground_vehicles)
        for body in cars.body_ids:  # paint the bodies in the colour the camera detector looks for
            p.changeVisualShape(int(body), -1, rgbaColor=CAR_RGBA, physicsClientId=scene.client)

    car_ids = [g.id for g in world.ground_vehicles]
    uav_ids = [u.id for u in world.uavs]
    target_ids = world.targets or [g.id for g in world.ground_vehicles if g.role == "target"]
    decoys = build_decoys(world.decoys, scene, CAR_RGBA)
    query = PybulletSceneQuery(scene.client, scene.occluders)
    outage_ticks = [(o.link[0], o.link[1], clock.ticks(o.start_s), clock.ticks(o.end_s)) for o in world.comms.outages]
    channel = build_channel(world, clock.physics_hz, seeds.generator("comms/channel"), query)
    return Assembly(clock=clock, scene=scene, recorder=recorder, buildings=geometry.buildings,
                    network=geometry.network, quads=quads, cars=cars, uav_ids=uav_ids,
                    car_ids=car_ids, car_kinds=car_kinds,
                    target_index=car_ids.index(target_ids[0]) if target_ids else None,
                    scene_query=query, sensors=prep.sensors, agents=prep.agents, world_spec=world,
                    channel=channel, base_station=build_base_station(world, prep.agents, channel, recorder),
                    _outage_ticks=outage_ticks, hcmci=prep.hcmci,
                    _sharing=any(a.agent.fusion is not None for a in prep.agents),
                    record_div=clock.divisor(world.sim.record_hz, "sim.record_hz"), decoys=decoys,
                    search=_search_team(prep.agents, car_ids, target_ids, car_kinds, decoys))


def _search_team(agents: list[AgentSlot], car_ids: list[str], target_ids: list[str], car_kinds: tuple[str, ...],
                 decoys: StaticDecoys | None) -> SearchTeamRun | None:
    """The search team of the set-membership agents, judged on the target rows of the truth (the tracked vehicles)
    and its decoy rows (vehicles of role decoy, then the static decoys); None without such agents."""
    members = [a for a in agents if a.search]
    if not members:
        return None
    n = len(car_ids)
    team = SearchTeamRun(members=[a.uav for a in members],
                         fusing={a.uav for a in members if a.fuse_sets},
                         target_rows=[car_ids.index(t) for t in target_ids],
                         decoy_rows=[k for k in range(n) if car_kinds[k] == "decoy"]
                         + list(range(n, n + (len(decoys) if decoys is not None else 0))))
    team.attach(members)
    return team
