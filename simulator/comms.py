"""What the UAVs of a run say to each other: the inbox, estimate and detection sharing, state broadcasts, links up.

Two regimes, as the world's ``comms`` section says:

- perfect comms (no radio): a UAV knows its teammates' true states and their latest local estimates at once, and a
  shared detection reaches each teammate that ``comms.links`` joins to the sender without an outage at that tick;
- a radio (:class:`~autonomy.sensing.channel.Channel`): every message (state, estimate, detections) goes through the
  channel with its losses and delays, and a UAV knows the last of each that got through.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from autonomy.agent import Agent
from autonomy.diagnostics import PlansPath
from autonomy.fusion.measurement_sharing import DetectionMessage, relayed
from interfaces.state import TargetEstimate, TeammateState, TrackPicture
from interfaces.team_states import TeamStates
from autonomy.sensing.channel import Channel, scheduled_links
from autonomy.sensing.measurement import Detection
from autonomy.sensing.messages import EstimateMessage, StateMessage, TrackListMessage
from autonomy.sensing.scene import SceneQuery
from simulator.truth import UavFleet, yaw_of
from worlds.schema import CommsSection

__all__ = ["Comms", "Outage"]

Outage = tuple[str, str, int, int]
"""A scheduled link outage: the two nodes, the first and the last tick."""


class Comms:
    """The team's messages (module docstring).

    Parameters
    ----------
    uav_ids : sequence of str
        Every UAV of the world, in order.
    quads : UavFleet
        The UAVs (where the radio sends from and to; their true states under perfect comms).
    channel : Channel | None
        The radio; None for perfect comms.
    comms : CommsSection
        The world's ``comms`` section (``links``, ``block_by_buildings``).
    outages : list of Outage
        Scheduled link outages in ticks.
    scene_query : SceneQuery
        Line of sight between UAVs (``comms.block_by_buildings`` under perfect comms).
    receivers : mapping of int to Agent
        The agents that take their teammates' detections, by UAV index.
    share_estimates : bool
        Whether the UAVs share their local estimates.
    """

    def __init__(self, *, uav_ids: Sequence[str], quads: UavFleet | None, channel: Channel | None, comms: CommsSection,
                 outages: list[Outage], scene_query: SceneQuery, receivers: Mapping[int, Agent],
                 share_estimates: bool) -> None:
        self.uav_ids = list(uav_ids)
        self.quads = quads
        self.channel = channel
        self.spec = comms
        self.outages = outages
        self.scene_query = scene_query
        self.receivers = dict(receivers)
        self.share_estimates = share_estimates
        self.shared_received: dict[int, int] = {}  # per UAV: teammates' detections delivered to it
        self._heard: dict[int, dict[int, TeammateState]] = {}
        self._shared: dict[int, dict[int, TargetEstimate | TrackPicture]] = {}
        self._local: dict[int, TargetEstimate | TrackPicture | None] = {}
        self._team: TeamStates | None = None  # every UAV's true state at self._team_tick (perfect comms)
        self._team_tick: tuple[int, float] | None = None

    def positions(self) -> dict[str, np.ndarray]:
        """Every UAV's position by id: where the radio sends from and to."""
        st = self.quads.state
        return {u: st.p_W[k] for k, u in enumerate(self.uav_ids)}

    def inbox(self, i: int, t: float,
              tick: int) -> tuple[Sequence[TeammateState], list[TargetEstimate | TrackPicture]]:
        """What UAV ``i`` knows of its team at ``t`` (s): states and shared target estimates.

        Perfect comms: the teammates' true states and their latest local estimates. Radio: the last of each that got
        through the channel (the detections among the messages go to the agent at once).
        """
        shared = self._shared.setdefault(i, {})
        if self.channel is None:
            mates = self._true_states(t, tick).without(i)
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
            elif isinstance(msg, TrackListMessage):
                shared[j] = msg.picture
            elif isinstance(msg, DetectionMessage):
                self._deliver_detections(i, relayed(msg.detections, env.t_arrival - msg.t_sent))
        return [known[j] for j in sorted(known)], [shared[j] for j in sorted(shared)]

    def _true_states(self, t: float, tick: int) -> TeamStates:
        """Every UAV's true state at ``tick`` (perfect comms), built once per tick and shared by every inbox of that
        tick: the states do not change between the agents' turns (the physics steps before them), so each agent's
        inbox is a view of them without itself instead of N − 1 new states, and a UAV's cost does not grow with N."""
        if self._team is None or self._team_tick != (tick, t):
            st = self.quads.state
            self._team = TeamStates.of(t, st.p_W, st.v_W, [yaw_of(q) for q in st.q_WB])
            self._team_tick = (tick, t)
        return self._team

    def share_estimate(self, i: int, est: TargetEstimate | None, t: float, tick: int,
                       picture: TrackPicture | None = None) -> None:
        """UAV ``i``'s local estimate, for its teammates (when the team shares estimates); a UAV with many tracks
        shares its track ``picture`` instead."""
        if not self.share_estimates:
            return
        if self.channel is None:
            self._local[i] = picture if picture is not None else est
            return
        if picture is not None:
            self.channel.send(TrackListMessage(sender=self.uav_ids[i], receiver=None, t_sent=t, picture=picture),
                              self.positions(), tick)
            return
        if est is None or est.P is None:
            return
        msg = EstimateMessage(sender=self.uav_ids[i], receiver=None, t_sent=t, target_id=0,
                              x=np.concatenate([est.p_W, est.v_W]), P=est.P, t_estimate=est.t)
        self.channel.send(msg, self.positions(), tick)

    def share_detections(self, i: int, detections: Sequence[Detection], t: float, tick: int) -> None:
        """Send UAV ``i``'s ``detections`` to the teammates that take them: over the radio (loss and delay; they
        arrive in :meth:`inbox`), or under perfect comms at once to the takers that ``comms.links`` joins to ``i``
        without an outage at ``tick``."""
        takers = [j for j in self.receivers if j != i]
        if not detections or not takers:
            return
        if self.channel is None:
            up = scheduled_links(self.uav_ids, self.spec.links, self.outages, tick)
            for j in takers:
                if up[i, j]:
                    self._deliver_detections(j, relayed(detections, 0.0))
            return
        positions = self.positions()
        for j in takers:
            self.channel.send(DetectionMessage(sender=self.uav_ids[i], receiver=self.uav_ids[j], t_sent=t,
                                               detections=tuple(detections)), positions, tick)

    def _deliver_detections(self, j: int, detections: list[Detection]) -> None:
        agent = self.receivers.get(j)
        if agent is not None:
            agent.receive(detections)
            self.shared_received[j] = self.shared_received.get(j, 0) + len(detections)

    def broadcast_state(self, i: int, guidance: object, t: float, tick: int) -> None:
        """UAV ``i``'s state and, if its ``guidance`` plans a path, the plan (radio only)."""
        if self.channel is None:
            return
        st = self.quads.state
        plans = isinstance(guidance, PlansPath)
        msg = StateMessage(sender=self.uav_ids[i], receiver=None, t_sent=t, p_W=st.p_W[i].copy(),
                           v_W=st.v_W[i].copy(), yaw=yaw_of(st.q_WB[i]),
                           plan_p_W=guidance.planned_path() if plans else None,
                           plan_dt=float(guidance.plan_step_s()) if plans else 1.0)
        self.channel.send(msg, self.positions(), tick)

    def links_up(self, uavs: Sequence[int], tick: int) -> np.ndarray:
        """(n, n) bool: which links between ``uavs`` (indices) are up at ``tick``. Radio: one erasure draw per link
        (fixed topology, range, blockage and outages included); perfect comms: the pairs of ``comms.links`` (every
        pair without it) less the scheduled outages, and less the pairs a building stands between when
        ``comms.block_by_buildings``."""
        ids = [self.uav_ids[j] for j in uavs]
        if self.channel is not None:
            st = self.quads.state
            return self.channel.sample_links(ids, {u: st.p_W[j] for u, j in zip(ids, uavs, strict=True)}, tick)
        up = scheduled_links(ids, self.spec.links, self.outages, tick)
        if self.spec.block_by_buildings and len(uavs) > 1:
            p_W = self.quads.state.p_W[uavs]
            iu, ju = np.triu_indices(len(uavs), k=1)
            clear = np.asarray(self.scene_query.line_of_sight(p_W[iu], p_W[ju]), dtype=bool)
            up[iu[~clear], ju[~clear]] = up[ju[~clear], iu[~clear]] = False
        return up
