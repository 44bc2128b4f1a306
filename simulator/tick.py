"""One tick of the run loop (DESIGN.md): :class:`Assembly` holds what a run steps, :meth:`Assembly.step` the six
phases.

1. vehicles apply actuator forces from their controllers' last outputs;
2. the physics steps;
3. low-level controllers run on the new state, and the divergence watchdog (:mod:`simulator.watchdog`) checks it;
4. sensors due at this tick measure (the cars' scene bodies first placed where the cars are: kinematic cars move their
   bodies only when something looks); their detections go to their agent, to the team protocols and to the teammates
   that take detections;
5. agents due at this tick: each team protocol does its team-level work (:mod:`autonomy.team.base`), then every due
   agent, in the world's order, reads its inbox, finishes its step and hands its set-point to its UAV, and its state
   and estimate go out to the team; the protocols end their step;
6. events, truth and collision checks are recorded.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from interfaces.setpoints import Setpoint
from autonomy.fusion.track_association import track_picture
from interfaces.state import OwnState, TargetEstimate
from autonomy.sensing.camera import Camera
from autonomy.sensing.channel import Channel
from autonomy.sensing.measurement import SensorOutput
from autonomy.sensing.scene import SceneQuery, SensorPose
from autonomy.team.base import TeamProtocol
from simulator.clock import Clock
from simulator.comms import Comms, Outage
from simulator.recording import Recording
from simulator.slots import AgentSlot, SensorSlot
from simulator.truth import Fleet, GroundFleet, Truth, UavFleet
from simulator.watchdog import Watchdog
from worlds.geometry import Building
from worlds.roads.network import RoadNetwork
from worlds.schema import World

__all__ = ["Assembly", "Physics", "TickContext", "WALL_PHASES"]

# phases of a tick whose wall time a run reports (metrics ``wall_time_breakdown_s``): actuation and low-level control
# of all vehicles, the PyBullet step, sensors (with their raycasts), the agents (estimation, fusion, guidance and the
# messages between them), recording (events, truth, collision checks)
WALL_PHASES = ("vehicles", "physics", "sensors", "autonomy", "record")


class Physics(Protocol):
    """What the tick needs of the physics engine: one step (a PyBullet scene, or a fake one in tests)."""

    def step(self) -> None: ...

    def close(self) -> None: ...


@dataclass(frozen=True)
class TickContext:
    """The :class:`~autonomy.team.base.TeamContext` of one tick."""

    t: float
    tick: int
    truth: Truth
    comms: Comms

    def own_state(self, uav: int) -> OwnState:
        return self.truth.own_state(uav, self.t)

    def links_up(self, uavs: Sequence[int]) -> np.ndarray:
        return self.comms.links_up(uavs, self.tick)


@dataclass
class Assembly:
    """Everything a run steps, with the tick of DESIGN.md in :meth:`step`."""

    clock: Clock
    scene: Physics
    truth: Truth
    comms: Comms
    recording: Recording
    teams: list[TeamProtocol]
    scene_query: SceneQuery
    uav_ids: list[str]
    car_ids: list[str]
    target_index: int | None
    sensors: list[SensorSlot] = field(default_factory=list)
    agents: list[AgentSlot] = field(default_factory=list)
    record_div: int = 12
    buildings: list[Building] = field(default_factory=list)
    network: RoadNetwork | None = None
    world_spec: World | None = None
    outages: list[Outage] = field(default_factory=list)
    latest_estimates: dict[int, TargetEstimate | None] = field(default_factory=dict)
    latest_local: dict[int, TargetEstimate | None] = field(default_factory=dict)
    latest_setpoints: dict[int, Setpoint] = field(default_factory=dict)
    wall_s: dict[str, float] = field(default_factory=lambda: dict.fromkeys(WALL_PHASES, 0.0))  # wall time per phase
    watchdog: Watchdog | None = None  # checks the state after each physics step (None: unchecked)

    def __post_init__(self) -> None:
        self._own_sensors = {a.uav: {s.name for s in self.sensors if s.uav == a.uav} for a in self.agents}
        self._team_of = {u: team for team in self.teams for u in team.members}
        self._takers = {u for team in self.teams if team.takes_detections for u in team.members}

    @property
    def quads(self) -> UavFleet | None:
        return self.truth.quads

    @property
    def cars(self) -> GroundFleet | None:
        return self.truth.cars

    @property
    def channel(self) -> Channel | None:
        return self.comms.channel

    def team_of(self, uav: int) -> TeamProtocol | None:
        """The team protocol UAV ``uav``'s agent belongs to."""
        return self._team_of.get(uav)

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
        if self.watchdog is not None:          # before any sensor or agent reads a diverged state
            self._watch(tick)
        t3 = clock()
        wall["vehicles"] += (t1 - t0) + (t3 - t2)
        wall["physics"] += t2 - t1
        t = self.clock.time(tick)
        self._sense(tick, t)                   # 4. sensors
        t4 = clock()
        wall["sensors"] += t4 - t3
        self._act(tick, t)                     # 5. agents
        t5 = clock()
        wall["autonomy"] += t5 - t4
        self._record(tick, t, fleets)          # 6. record
        wall["record"] += clock() - t5

    def _watch(self, tick: int) -> None:
        """The watchdog on the UAVs' state at every tick, and on the cars' at the ticks that record it (their state
        is computed once per tick that reads it: the record ticks read it anyway)."""
        cars = self.cars.state if self.cars is not None and tick % self.record_div == 0 else None
        self.watchdog.check(tick, None if self.quads is None else self.quads.live_state, cars)

    def _sense(self, tick: int, t: float) -> None:
        due = [slot for slot in self.sensors if tick % slot.divisor == 0]
        if not due:
            return
        if self.cars is not None:
            self.cars.sync_scene()
        truth = self.truth.targets()
        st = self.quads.state
        for slot in due:
            look = (slot.sensor.look_point(self.latest_estimates.get(slot.uav), t)
                    if isinstance(slot.sensor, Camera) else None)  # a gimbal cued by the last agent step's estimate
            pose = SensorPose(p_W=st.p_W[slot.uav], q_WB=st.q_WB[slot.uav], v_W=st.v_W[slot.uav], look_at_W=look)
            out = slot.sensor.measure(t, pose, truth, self.scene_query, slot.rng)
            self.recording.detections(tick, slot.uav, slot.name, out)
            self._deliver_scan(slot, t, out)
            self.comms.share_detections(slot.uav, list(out.detections), t, tick)

    def _deliver_scan(self, slot: SensorSlot, t: float, out: SensorOutput) -> None:
        coverage = out.extras.get("coverage")
        for a in self.agents:
            if a.uav == slot.uav:
                a.agent.receive(out.detections)
                if coverage is not None:
                    a.agent.receive_coverage(coverage)
        for team in self.teams:
            team.on_scan(slot.uav, t, slot.sensor.latency_s, out.extras)

    def _act(self, tick: int, t: float) -> None:
        due = [a for a in self.agents if tick % a.divisor == 0]
        if not due:
            return
        ctx = TickContext(t=t, tick=tick, truth=self.truth, comms=self.comms)
        decide = {}
        for team in self.teams:  # team-level work first (consensus, set fusion and sequential decisions)
            decide.update(team.step([a for a in due if a.uav in team.members], ctx))
        for a in due:  # then each agent in turn: its inbox, the rest of its step, its set-point, its messages
            mates, shared = self.comms.inbox(a.uav, t, tick)
            result = decide[a.uav](self.truth.own_state(a.uav, t), mates, shared)
            self.quads.set_command(a.uav, result.setpoint)
            self.comms.broadcast_state(a.uav, a.agent.guidance, t, tick)  # after planning: the plan starts here
            self.comms.share_estimate(a.uav, result.local_estimate, t, tick,
                                      picture=track_picture(a.agent.estimator, t))
            self.latest_estimates[a.uav] = result.estimate
            self.latest_local[a.uav] = result.local_estimate
            self.latest_setpoints[a.uav] = result.setpoint
            self.recording.agent(tick, t, a.uav, a.agent.estimator, result, fused=a.agent.fusion is not None)
            self.recording.tracks(tick, t, a.uav, a.agent.estimator)
            if a.uav in self._takers:
                self.recording.sharing(tick, t, a.uav, a.agent.estimator, self.comms.shared_received.get(a.uav, 0),
                                       self._own_sensors[a.uav])
        for team in self.teams:
            team.end_step([a for a in due if a.uav in team.members], ctx)

    def _record(self, tick: int, t: float, fleets: list[Fleet]) -> None:
        if self.outages:
            self.recording.outage_events(tick, t, self.outages)
        for f in fleets:
            for ev in f.pop_events():
                self.recording.event(tick, t, dict(ev))
        if tick % self.record_div == 0:
            self.recording.truth(tick, t, self.quads, self.cars)
            self.recording.collisions(tick, t)

    def close(self) -> None:
        try:
            if self.cars is not None and hasattr(self.cars, "close"):
                self.cars.close()  # an external traffic source (SUMO) ends its simulation
        finally:
            self.scene.close()

