"""One environment episode: a world built and stepped exactly as ``skytrack run`` builds and steps it, with some UAVs'
guidance laws handed to a learner.

The run is built by :func:`simulator.prepare.prepare` and :func:`simulator.prepare.build_assembly` and stepped by
:meth:`simulator.tick.Assembly.step`; nothing of the loop is copied. Each learning UAV keeps its world-file sensors,
estimator and fusion; only its guidance law is replaced by a :class:`HeldSetpoint`, which

- keeps what the agent hands its guidance at each autonomy step (own state, target estimate, teammates' broadcast
  states: :class:`Knowledge`), which is the learner's observation, and
- returns the set-point the learner chose last.

The learner sees the knowledge of an autonomy step only once that step has run, so the episode stops right after it
(:meth:`Episode.advance`) and the learner's action is given to the UAV at that same tick (:meth:`Episode.act`),
replacing what the step set: the UAV flies each action from the tick its observation was made.
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from autonomy.team.set_fusion import SetFusionTeam
from interfaces.setpoints import Setpoint, UnicycleSetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState
from simulator.clock import Clock
from simulator.engine import RunOptions
from simulator.envs.event_log import EventLog
from simulator.prepare import build_assembly, prepare
from simulator.seeding import RunSeeds
from simulator.tick import Assembly
from worlds.build import WorldGeometry
from worlds.loader import LoadedWorld

__all__ = ["Episode", "HeldSetpoint", "Knowledge"]


@dataclass(frozen=True)
class Knowledge:
    """What a UAV's autonomy handed its guidance at one autonomy step (s, and the states of
    :mod:`interfaces.state`)."""

    t: float
    own: OwnState
    target: TargetEstimate | None
    teammates: tuple[TeammateState, ...]


class HeldSetpoint:
    """The guidance law of a learning UAV: keeps the agent's :class:`Knowledge`, returns the learner's set-point."""

    def __init__(self, setpoint: Setpoint) -> None:
        self.setpoint = setpoint
        self.knowledge: Knowledge | None = None

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> Setpoint:
        self.knowledge = Knowledge(t=t, own=own, target=target, teammates=tuple(teammates))
        return self.setpoint


class Episode:
    """A world run from tick 0, stopping at the learners' autonomy steps.

    Parameters
    ----------
    loaded : LoadedWorld
        The world.
    learners : sequence of int
        Indices of the UAVs whose guidance the learner replaces; all must run their autonomy at one rate.
    seed : int
        The run's seed (as ``skytrack run --seed``), >= 0.
    duration : float | None
        Simulated seconds (s); None = the world's ``sim.duration_s``.
    """

    def __init__(self, loaded: LoadedWorld, learners: Sequence[int], seed: int, duration: float | None) -> None:
        world = loaded.world
        self.clock = Clock(physics_hz=world.sim.physics_hz)
        self.n_ticks = self.clock.ticks(world.sim.duration_s if duration is None else duration)
        seeds = RunSeeds(seed)
        # prepare reads the code-given estimator and guidance factories of the options (none here), nothing else
        options = RunOptions(seed=seed, duration_s=duration, out_dir=Path(tempfile.gettempdir()), plots=False)
        prepared = prepare(loaded, self.clock, seeds, options)
        self.geometry: WorldGeometry = prepared.geometry
        slots = {a.uav: a for a in prepared.agents}
        rates = {slots[i].divisor for i in learners}
        if len(rates) != 1:
            raise ValueError(f"the learning UAVs must run their autonomy at one rate, got divisors "
                             f"{sorted(rates)} of the {self.clock.physics_hz} Hz physics")
        self.divisor = rates.pop()
        if self.n_ticks < self.divisor:
            raise ValueError(f"the episode ({self.n_ticks} ticks) is shorter than one autonomy step "
                             f"({self.divisor} ticks)")
        self.held: dict[int, HeldSetpoint] = {}
        for i in learners:
            z0 = float(world.uavs[i].initial.position[2])
            self.held[i] = HeldSetpoint(UnicycleSetpoint(speed=0.0, heading_rate=0.0, altitude=z0))
            slots[i].agent.guidance = self.held[i]
        self.log = EventLog()
        self._closed = False
        self.assembly: Assembly = build_assembly(prepared, seeds, self.log)
        try:
            self._check(learners)
        except ValueError:
            self.close()
            raise
        self.tick = 0

    def _check(self, learners: Sequence[int]) -> None:
        asm = self.assembly
        if asm.target_index is None:
            raise ValueError("the world designates no target vehicle to track")
        for i in learners:
            if isinstance(asm.team_of(i), SetFusionTeam):
                raise ValueError(f"UAV {asm.uav_ids[i]} searches with set fusion, whose guidance is the team's "
                                 "decision: it cannot be handed to a learner")

    @property
    def t(self) -> float:
        """Simulated time now (s)."""
        return self.clock.time(self.tick)

    @property
    def finished(self) -> bool:
        """Whether the episode reached its duration."""
        return self.tick >= self.n_ticks

    def advance(self) -> None:
        """Step the run up to and including the learners' next autonomy step, or to the end of the episode."""
        stop = min((self.tick // self.divisor + 1) * self.divisor, self.n_ticks)
        while self.tick < stop:
            self.tick += 1
            self.assembly.step(self.tick)

    def act(self, uav: int, setpoint: Setpoint) -> None:
        """Fly ``setpoint`` on learning UAV ``uav`` from now until its next action."""
        self.held[uav].setpoint = setpoint
        self.assembly.quads.set_command(uav, setpoint)

    def knowledge(self, uav: int) -> Knowledge:
        """What learning UAV ``uav``'s autonomy knew at its last step."""
        k = self.held[uav].knowledge
        if k is None:
            raise RuntimeError("no autonomy step has run yet: call advance() first")
        return k

    def target_truth(self) -> np.ndarray:
        """(3,) true position of the designated target now (m): for rewards and terminations, never observations."""
        return np.asarray(self.assembly.truth.targets().p_W[self.assembly.target_index], dtype=float)

    def uav_truth(self, uav: int) -> np.ndarray:
        """(3,) true position of UAV ``uav`` now (m)."""
        return np.asarray(self.assembly.quads.state.p_W[uav], dtype=float)

    def close(self) -> None:
        """Disconnect the run's PyBullet client, once: a client id freed here may be handed to the next connection,
        which a second disconnect would then close."""
        if not self._closed:
            self._closed = True
            self.assembly.close()
