"""The team-protocol interface: one class per way a team shares information.

At each agent tick the simulator hands every protocol the members due at that tick (in the world's UAV order) and a
narrow :class:`TeamContext` (the clock, the UAVs' own states, the links up at this tick). :meth:`TeamProtocol.step`
does the protocol's team-level work (a consensus, a set fusion, sequential decisions) and returns, for each member, a
:data:`Decide`: the rest of that member's step, to be called with what the UAV knows of its team when its turn comes.
The simulator then walks the due agents in the world's order, reading each one's inbox from the radio just before
its turn and sending its state and estimate just after it, so the radio's messages and random draws keep one order
whatever the protocols. :meth:`TeamProtocol.end_step` runs once all due members have acted (a report to a base
station); :meth:`TeamProtocol.on_scan` sees every scan as the sensors produce it.

What a protocol shares beyond that is declared, not probed: :attr:`TeamProtocol.shares_estimates` (the members'
local estimates go to every teammate) and :attr:`TeamProtocol.takes_detections` (the teammates' detections go to the
members).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, ClassVar, Protocol

import numpy as np

from autonomy.agent import Agent, AgentOutput
from interfaces.state import OwnState, TargetEstimate, TeammateState

__all__ = ["Decide", "TeamContext", "TeamMember", "TeamProtocol"]

Decide = Callable[[OwnState, Sequence[TeammateState], Sequence[TargetEstimate]], AgentOutput]
"""The rest of one member's step: ``decide(own, teammates, shared_estimates) -> AgentOutput``."""


class TeamMember(Protocol):
    """One UAV of a team: its index in the world and its onboard software."""

    @property
    def uav(self) -> int: ...

    @property
    def agent(self) -> Agent: ...


class TeamContext(Protocol):
    """What a protocol may know of the world at a step: the clock, the members' own states, the links up."""

    @property
    def t(self) -> float:
        """Time of the step (s)."""
        ...

    @property
    def tick(self) -> int:
        """Physics tick of the step."""
        ...

    def own_state(self, uav: int) -> OwnState:
        """UAV ``uav``'s own navigation state at the step."""
        ...

    def links_up(self, uavs: Sequence[int]) -> np.ndarray:
        """(n, n) bool: which links between ``uavs`` (indices) are up at this step (one draw per link on a radio)."""
        ...


class TeamProtocol:
    """Base of the team protocols: members that act each on their own (no team-level work).

    Parameters
    ----------
    members : sequence of int
        UAV indices of the team, in the world's order.
    """

    shares_estimates: ClassVar[bool] = False
    takes_detections: ClassVar[bool] = False
    point_estimates: ClassVar[bool] = True
    """Whether the members' estimators give point estimates of the target (scored against truth)."""

    def __init__(self, members: Sequence[int]) -> None:
        self.members = tuple(int(m) for m in members)

    def step(self, members: Sequence[TeamMember], ctx: TeamContext) -> dict[int, Decide]:
        """Team-level work of ``members`` (those due now) and the rest of each one's step, by UAV index."""
        t = ctx.t
        return {m.uav: _own_step(m.agent, t) for m in members}

    def end_step(self, members: Sequence[TeamMember], ctx: TeamContext) -> None:
        """After every due member has acted; nothing by default."""

    def on_scan(self, uav: int, t: float, latency_s: float, extras: Mapping[str, Any]) -> None:
        """A scan of UAV ``uav``'s sensor at ``t`` (s) arriving ``latency_s`` later, with its by-products; ignored by
        default."""

    def summary(self) -> dict[str, Any] | None:
        """The team's figures for ``metrics.json``, or None."""
        return None


def _own_step(agent: Agent, t: float) -> Decide:
    """The agent's whole step: its estimator, its fusion of the ``shared`` estimates if it fuses, its guidance."""
    def decide(own: OwnState, mates: Sequence[TeammateState], shared: Sequence[TargetEstimate]) -> AgentOutput:
        return agent.step(t, own, mates, shared if agent.fusion is not None else ())
    return decide
