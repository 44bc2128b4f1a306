"""A fake engine for exact tests of the tick without PyBullet (dm_control's ``FakePhysics`` idea).

The fleets' states are scripted (a function of the tick), the physics step only counts, the scene is
:class:`autonomy.sensing.fake_scene.FakeScene` (analytic raycasts), and nothing touches: the tick, the scheduler (which
sensor and agent runs at which tick), the radio (inbox, latency, outages) and the team protocols then run as in a
real run and can be checked exactly. Every fake appends what it does to a shared ``log`` so a test can check the
order of the phases.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from autonomy.sensing.channel import Channel
from autonomy.sensing.fake_scene import FakeScene
from autonomy.sensing.scene import SceneQuery
from simulator.clock import Clock
from simulator.comms import Outage
from simulator.prepare import build_teams, team_comms
from simulator.record import RunRecorder
from simulator.recording import Recording
from simulator.slots import AgentSlot, SensorSlot
from simulator.tick import Assembly
from simulator.truth import Truth
from vehicles.car.fleet import CarState
from interfaces.setpoints import FlightSetpoint
from vehicles.quadrotor.state import FleetState
from worlds.schema import CommsSection

__all__ = ["FakePhysics", "ScriptedCars", "ScriptedUavs", "fake_assembly"]

Script = Callable[[int], np.ndarray]
"""``script(tick) -> (N, 3)`` positions (m) of every vehicle after the physics step of ``tick``."""


@dataclass
class FakePhysics:
    """A physics step that only counts (and logs)."""

    log: list[tuple[str, int]] = field(default_factory=list)
    steps: int = 0
    closed: bool = False

    def step(self) -> None:
        self.steps += 1
        self.log.append(("physics", self.steps))

    def close(self) -> None:
        self.closed = True


class _Scripted:
    def __init__(self, name: str, script: Script, physics_hz: int, log: list[tuple[str, int]]) -> None:
        self.name = name
        self.script = script
        self.dt = 1.0 / physics_hz
        self.log = log
        self.tick = 0
        self.p_W = np.asarray(script(0), dtype=float)
        self.v_W = np.zeros_like(self.p_W)
        self.body_ids = np.arange(len(self.p_W))
        self.events: list[dict] = []

    def apply_actuation(self) -> None:
        self.log.append((f"{self.name}.actuation", self.tick + 1))

    def after_step(self, tick: int) -> None:
        p_W = np.asarray(self.script(tick), dtype=float)
        self.v_W = (p_W - self.p_W) / self.dt
        self.p_W, self.tick = p_W, tick
        self.log.append((f"{self.name}.after_step", tick))

    def pop_events(self) -> list[dict]:
        out, self.events = self.events, []
        return out


class ScriptedUavs(_Scripted):
    """UAVs at scripted positions, level, facing +x; the commands they get are kept in :attr:`commands`
    (tick, UAV index, command)."""

    def __init__(self, script: Script, physics_hz: int, log: list[tuple[str, int]] | None = None) -> None:
        super().__init__("uavs", script, physics_hz, [] if log is None else log)
        self.commands: list[tuple[int, int, FlightSetpoint]] = []

    @property
    def state(self) -> FleetState:
        n = len(self.p_W)
        return FleetState(p_W=self.p_W, q_WB=np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)), R_WB=np.tile(np.eye(3), (n, 1, 1)),
                          v_W=self.v_W, omega_B=np.zeros((n, 3)), rotor_speed=np.zeros((n, 4)),
                          thrust=np.zeros((n, 4)))

    @property
    def live_state(self) -> FleetState:
        return self.state

    def set_command(self, i: int, cmd: FlightSetpoint) -> None:
        self.commands.append((self.tick, i, cmd))
        self.log.append(("uavs.command", self.tick))


class ScriptedCars(_Scripted):
    """Ground vehicles at scripted positions on road ``road``."""

    def __init__(self, script: Script, physics_hz: int, log: list[tuple[str, int]] | None = None) -> None:
        super().__init__("cars", script, physics_hz, [] if log is None else log)

    def sync_scene(self) -> None:
        self.log.append(("cars.sync_scene", self.tick))

    @property
    def state(self) -> CarState:
        n = len(self.p_W)
        yaw = np.arctan2(self.v_W[:, 1], self.v_W[:, 0])
        return CarState(tick=self.tick, p_W=self.p_W, q_WB=np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)), v_W=self.v_W,
                        a_W=np.zeros((n, 3)), yaw=yaw, speed=np.linalg.norm(self.v_W, axis=1), road_id=["road"] * n,
                        s=np.zeros(n), lateral=np.zeros(n), stopped=np.zeros(n, dtype=bool))


def fake_assembly(*, clock: Clock, recorder: RunRecorder, uavs: ScriptedUavs, uav_ids: Sequence[str],
                  agents: Sequence[AgentSlot], methods: Sequence[str], sensors: Sequence[SensorSlot] = (),
                  cars: ScriptedCars | None = None, car_ids: Sequence[str] = (), channel: Channel | None = None,
                  comms: CommsSection | None = None, outages: Sequence[Outage] = (), scene: SceneQuery | None = None,
                  physics: FakePhysics | None = None, record_div: int = 1,
                  car_attributes: Mapping[str, np.ndarray] | None = None) -> Assembly:
    """An :class:`~simulator.tick.Assembly` on scripted fleets: the team protocols are built from each agent's
    fusion method (``methods``) as in a run (:func:`simulator.prepare.build_teams`; HCMCI with its default
    settings). ``car_attributes``: each car's class indices (:func:`simulator.truth.car_attributes`), or None."""
    query = scene if scene is not None else FakeScene()
    agents, teams = list(agents), build_teams(list(methods), list(agents), None)
    comm = team_comms(teams, agents, uav_ids=list(uav_ids), quads=uavs, channel=channel,
                      comms=comms or CommsSection(), outages=list(outages), scene_query=query)
    return Assembly(clock=clock, scene=physics if physics is not None else FakePhysics(),
                    truth=Truth(uavs, cars, ("car",) * len(car_ids), None, car_attributes), comms=comm,
                    recording=Recording(recorder, uav_ids, car_ids, None), teams=teams, scene_query=query,
                    uav_ids=list(uav_ids), car_ids=list(car_ids), target_index=0 if car_ids else None,
                    sensors=list(sensors), agents=agents, outages=list(outages), record_div=record_div)
