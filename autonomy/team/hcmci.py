"""HCMCI consensus (paper 000): the members' information trackers fuse over the links up, then each plans alone.

At a step every due member's tracker absorbs its detections; the members that hold a track run
:class:`autonomy.fusion.hcmci_team.HcmciTeam` over the links up at this step (:meth:`TeamContext.links_up`) and take
their consensus posteriors; each member then fuses nothing more and plans on its posterior. The protocol counts, per
UAV, the steps at which it had a link up to another node with a track (:attr:`HcmciConsensusTeam.linked_steps`),
and per step the links up between such nodes (:attr:`HcmciConsensusTeam.active_links`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from autonomy.agent import Agent, AgentOutput, TargetEstimator
from autonomy.estimation.tracker import SingleTargetTracker
from autonomy.fusion.hcmci_team import HcmciConfig, HcmciTeam
from interfaces.state import OwnState, TargetEstimate, TeammateState
from autonomy.team.base import Decide, TeamContext, TeamMember, TeamProtocol

__all__ = ["HcmciConsensusTeam", "is_information_tracker"]


def is_information_tracker(estimator: TargetEstimator) -> bool:
    """Whether ``estimator`` is the built-in tracker with the information filter (``scif``), as HCMCI and
    base-station fusion need."""
    return isinstance(estimator, SingleTargetTracker) and estimator.config.filter == "scif"


class HcmciConsensusTeam(TeamProtocol):
    """HCMCI consensus over the links up (module docstring).

    Parameters
    ----------
    members : sequence of int
        UAV indices of the team.
    config : HcmciConfig
        Rounds and gain, one for the team.
    """

    def __init__(self, members: Sequence[int], config: HcmciConfig) -> None:
        super().__init__(members)
        self.fusion = HcmciTeam(config)
        self.linked_steps: dict[int, int] = {}
        self.active_links: list[int] = []

    @property
    def steps(self) -> int:
        """Team steps so far."""
        return self.fusion.steps

    def step(self, members: Sequence[TeamMember], ctx: TeamContext) -> dict[int, Decide]:
        if not members:
            return {}
        t = ctx.t
        uavs = [m.uav for m in members]
        ready = [m.agent.take_ready(t) for m in members]
        trackers = [m.agent.estimator for m in members]
        estimates, fused = self.fusion.step(t, trackers, ready, ctx.links_up(uavs))  # type: ignore[arg-type]
        for j, degree in zip(uavs, fused.adjacency.sum(axis=1), strict=True):  # a cut-off node fuses only itself
            self.linked_steps[j] = self.linked_steps.get(j, 0) + bool(degree > 0)
        self.active_links.append(fused.active_links)
        return {m.uav: _act(m.agent, t, est, len(r)) for m, est, r in zip(members, estimates, ready, strict=True)}

    def summary(self) -> dict[str, Any]:
        """``team_steps`` and ``active_links_mean`` (links up between nodes with a track, mean over the steps)."""
        return {"team_steps": self.steps,
                "active_links_mean": float(np.mean(self.active_links)) if self.active_links else None}


def _act(agent: Agent, t: float, estimate: TargetEstimate | None, used: int) -> Decide:
    def decide(own: OwnState, mates: Sequence[TeammateState], shared: Sequence[TargetEstimate]) -> AgentOutput:
        return agent.act(t, own, mates, estimate, used)
    return decide
