"""Set fusion (paper 004): a team of set-membership searchers that fuse their sets and decide one after another.

When its members are due (they share one rate, :mod:`worlds.checks`):

1. each member's :class:`~autonomy.estimation.setmem.tracker.SetMembershipTracker` applies the scans that have
   arrived: the observed regions handed over by :meth:`SetFusionTeam.on_scan` as the sensors measure, and the box
   detections from the agent's queue;
2. the members that fuse (fusion method ``sets``) fuse over the links up at this step
   (:meth:`~autonomy.team.base.TeamContext.links_up`), :func:`autonomy.fusion.set_team.fuse_team_sets`, and every
   member's sets are brought to the step's time;
3. the members decide one after another in :func:`~autonomy.guidance.search.planner.decision_order` over those links,
   each seeing the plans of the linked teammates that decided before it in this step (a
   :class:`~interfaces.state.TeammateState` with ``plan_p_W``, stamped now), as the paper's sequential MPC;
4. an observer (:class:`SetTeamObserver`, the simulator's record of the search against truth) sees the step.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import numpy as np

from autonomy.agent import AgentOutput
from autonomy.diagnostics import PlansPath
from autonomy.estimation.setmem.tracker import ObservedRegion, SetMembershipTracker
from autonomy.fusion.set_team import fuse_team_sets
from autonomy.guidance.search.planner import decision_order
from interfaces.state import OwnState, TargetEstimate, TeammateState
from autonomy.team.base import Decide, TeamContext, TeamMember, TeamProtocol

__all__ = ["SetFusionTeam", "SetTeamObserver"]


class SetTeamObserver(Protocol):
    """Sees each step of a set-fusion team once its members have decided."""

    def on_team_step(self, tick: int, t: float, members: Sequence[TeamMember], fused: np.ndarray,
                     links: np.ndarray) -> None:
        """``fused``: (n,) neighbours' sets each member fused; ``links``: (n, n) the links the team used."""
        ...


class SetFusionTeam(TeamProtocol):
    """The search team of the module docstring.

    Parameters
    ----------
    trackers : mapping of int to SetMembershipTracker
        Each member's tracker (its agent's estimator), by UAV index.
    fusing : set of int
        Members that fuse their sets with their linked teammates'.
    """

    point_estimates = False

    def __init__(self, trackers: Mapping[int, SetMembershipTracker], fusing: set[int]) -> None:
        super().__init__(sorted(trackers))
        self.trackers = dict(trackers)
        self.fusing = set(fusing)
        self.observer: SetTeamObserver | None = None

    def on_scan(self, uav: int, t: float, latency_s: float, extras: Mapping[str, Any]) -> None:
        """Hand the region a member's box sensor observed at ``t`` (s; ``extras["observed_region"]``), arriving
        ``latency_s`` later, to its tracker."""
        region = extras.get("observed_region")
        if region is None or uav not in self.trackers:
            return
        self.trackers[uav].observe(ObservedRegion(t_meas=t, t_arrival=t + latency_s, region=region))

    def step(self, members: Sequence[TeamMember], ctx: TeamContext) -> dict[int, Decide]:
        if not members:
            return {}
        t = ctx.t
        uavs = [m.uav for m in members]
        trackers = [self.trackers[u] for u in uavs]
        used = {}
        for m, trk in zip(members, trackers, strict=True):
            ready = m.agent.take_ready(t)
            trk.step(t, ready)
            used[m.uav] = len(ready)
        links = ctx.links_up(uavs)
        fuse = np.array([u in self.fusing for u in uavs])
        links &= fuse[:, None] & fuse[None, :]
        fused = fuse_team_sets([trk.estimator for trk in trackers], links)
        for trk in trackers:  # a fusion at the scans' time is brought to the step's
            trk.estimator.predict(t)
        out: dict[int, AgentOutput] = {}
        plans: dict[int, TeammateState] = {}
        for k in decision_order(links):
            m = members[k]
            own = ctx.own_state(m.uav)
            mates = [plans[uavs[j]] for j in np.flatnonzero(links[k]) if uavs[j] in plans]
            out[m.uav] = m.agent.act(t, own, mates, None, used[m.uav])
            law = m.agent.guidance
            path = law.planned_path() if isinstance(law, PlansPath) else None
            if path is not None:
                plans[m.uav] = TeammateState(id=m.uav, t=t, p_W=own.p_W, v_W=own.v_W, yaw=own.yaw, plan_p_W=path,
                                             plan_dt=law.plan_step_s())
        if self.observer is not None:
            self.observer.on_team_step(ctx.tick, t, members, fused, links)
        return {u: _done(out[u]) for u in uavs}

    def late_scans(self) -> int:
        """Scans that arrived after their tracker had moved past their time, over the team."""
        return int(sum(trk.late_scans for trk in self.trackers.values()))


def _done(output: AgentOutput) -> Decide:
    def decide(own: OwnState, mates: Sequence[TeammateState], shared: Sequence[TargetEstimate]) -> AgentOutput:
        return output
    return decide
