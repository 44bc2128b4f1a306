"""The base station of paper 001 as a run component: routes to it, the packets over them, and its information filter.

At every tick at which UAVs that fuse at the base (fusion method ``base_station``) have stepped, after their agents:

1. routes: the minimum spanning tree of the radio's link probabilities at this tick over the base (node ``base`` at
   ``comms.base_station``) and every UAV (:meth:`Channel.routing_tree`), or with ``comms.routing: chain`` the fixed
   relay chain in the order of the world's UAVs (uavs[k] relays through uavs[k−1], uavs[0] sends to the base);
2. packets: each of those UAVs that took a scan contribution at this step
   (:attr:`~autonomy.fusion.base_station.InformationReporter.contribution`) sends it as an
   :class:`~autonomy.sensing.messages.InformationMessage` along its route (:meth:`Channel.send_routed`: one erasure
   draw per hop with that hop's probability, ``latency_s`` per hop);
3. fusion: the base takes the packets that have arrived (:meth:`Channel.receive`) and adds them, oldest measurement
   time first, to its information filter (:class:`~autonomy.fusion.base_station.BaseStationFusion` with the UAVs'
   motion model and no prior: the base knows nothing until packets arrive). A packet whose measurement is older than
   the information the base already holds cannot be added exactly (it is information about an earlier state) and is
   dropped as late; without latency none is;
4. record: a ``base_station`` row (the base's estimate predicted to now, its information, the packets fused, lost and
   late at this step) and a ``routing`` row per UAV that fuses at the base (next hop: a UAV index, −1 the base, −2 cut
   off; hop count; route probability β; whether it sent a packet and whether the packet survived its route).

The route probability β of a UAV is the product of its hops' delivery probabilities under the channel model at this
tick (fading, range, blockage and outages), the probability its packet arrives; a UAV is a relay at a step when
another UAV's next hop is that UAV.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from autonomy.estimation.base import TIME_TOLERANCE
from autonomy.estimation.tracker import make_motion_model
from autonomy.fusion.base_station import BaseStationFusion, InformationReporter
from interfaces.state import TargetEstimate
from autonomy.sensing.channel import Channel, RoutingTree
from autonomy.sensing.messages import InformationMessage
from simulator.record import RunRecorder
from worlds.schema import World

if TYPE_CHECKING:
    from simulator.slots import AgentSlot

__all__ = ["BASE_NODE", "BaseStation", "BaseStationLink", "build_base_station", "route_parents"]

BASE_NODE = "base"
"""Radio node name of the base station (also in ``comms.outages`` and ``comms.links``)."""


def route_parents(tree: RoutingTree, uav_ids: Sequence[str]) -> np.ndarray:
    """(N,) next hop of each UAV of ``uav_ids`` in ``tree``: a UAV index, −1 for the base, −2 if cut off."""
    out = np.full(len(uav_ids), -2)
    for k, uid in enumerate(uav_ids):
        nxt = tree.parent.get(uid)
        if nxt is not None and tree.path(uid):
            out[k] = -1 if nxt == tree.root else uav_ids.index(nxt)
    return out


class BaseStation:
    """Routes, packets and fusion at the base station (module docstring).

    Parameters
    ----------
    position_W : np.ndarray
        (3,) base station position (m).
    uav_ids : sequence of str
        Every UAV of the world, in order (all of them relay).
    reporters : mapping of int to InformationReporter
        The estimators of the UAVs that fuse at the base, by UAV index.
    fusion : BaseStationFusion
        The base's information filter.
    channel : Channel
        The run's radio.
    recorder : RunRecorder
        The run recorder.
    chain : bool
        Fixed relay chain instead of the minimum spanning tree.
    """

    def __init__(self, *, position_W: np.ndarray, uav_ids: Sequence[str], reporters: Mapping[int, InformationReporter],
                 fusion: BaseStationFusion, channel: Channel, recorder: RunRecorder, chain: bool = False) -> None:
        self.position_W = np.asarray(position_W, dtype=float).reshape(3)
        self.uav_ids = list(uav_ids)
        self.reporters = dict(reporters)
        self.fusion = fusion
        self.channel = channel
        self.recorder = recorder
        self.chain = chain
        self.nodes = (BASE_NODE, *self.uav_ids)
        self.estimate: TargetEstimate | None = None
        self.last_tick = -1
        self.steps = 0
        self.late = 0
        n = len(self.uav_ids)
        self._beta_sum, self._hops_sum, self._route_steps = np.zeros(n), np.zeros(n), np.zeros(n, dtype=int)
        self._sent, self._delivered = np.zeros(n, dtype=int), np.zeros(n, dtype=int)
        self._relay_steps = np.zeros(n, dtype=int)

    def step(self, tick: int, t: float, uav_positions: Mapping[str, np.ndarray], due: Sequence[int]) -> None:
        """Route, send, fuse and record at ``tick`` (time ``t``, s) for the agents ``due`` (UAV indices) that stepped;
        ``uav_positions`` holds every UAV's position (3,) by id (m)."""
        members = [i for i in due if i in self.reporters]
        if not members:
            return
        positions = {BASE_NODE: self.position_W, **uav_positions}
        tree = self.channel.routing_tree(self.nodes, positions, BASE_NODE, tick, chain=self.chain)
        parents = route_parents(tree, self.uav_ids)
        lost_now = 0
        for i in members:
            uid = self.uav_ids[i]
            beta, hops = tree.route_probability(uid), tree.hops(uid)
            c = self.reporters[i].contribution
            sent = c is not None and abs(c.t_meas - t) <= TIME_TOLERANCE
            delivered = False
            if sent:
                msg = InformationMessage(sender=uid, receiver=BASE_NODE, t_sent=t, target_id=0,
                                         info_vector=c.info_vector, info_matrix=c.info_matrix, t_info=c.t_meas)
                delivered = self.channel.send_routed(msg, tree, tick)
                self._sent[i] += 1
                self._delivered[i] += delivered
                lost_now += not delivered
            self._beta_sum[i] += beta
            self._hops_sum[i] += max(hops, 0)
            self._route_steps[i] += 1
            self._relay_steps[i] += bool(np.any(parents == i))
            self.recorder.append("routing", tick=tick, t=t, uav=i, parent=int(parents[i]), hops=int(hops),
                                 beta=float(beta), sent=bool(sent), delivered=bool(delivered))
        fused, late = self._fuse(tick)
        self.estimate = self.fusion.estimate(t)
        self.last_tick = tick
        self.steps += 1
        self._record(tick, t, fused, lost_now, late)

    def _fuse(self, tick: int) -> tuple[int, int]:
        """Add the packets that have arrived, grouped by measurement time; returns (fused, late)."""
        packets = [e.message for e in self.channel.receive(BASE_NODE, tick)
                   if isinstance(e.message, InformationMessage)]
        fused = late = 0
        have_information = bool(np.any(self.fusion.Y))
        for t_info in sorted({m.t_info for m in packets}):
            group = [m for m in packets if m.t_info == t_info]
            if have_information and t_info < self.fusion.t - TIME_TOLERANCE:
                late += len(group)
                continue
            fused += self.fusion.fuse(group)
            have_information = True
        self.late += late
        return fused, late

    def _record(self, tick: int, t: float, fused: int, lost: int, late: int) -> None:
        est = self.estimate
        row = {"tick": tick, "t": t, "valid": est is not None, "x": np.nan, "y": np.nan, "vx": np.nan, "vy": np.nan,
               "pxx": np.nan, "pxy": np.nan, "pyy": np.nan, "pvxvx": np.nan, "pvyvy": np.nan,
               "info_trace": float(np.trace(self.fusion.Y)), "received": fused, "lost": lost, "late": late,
               "received_total": self.fusion.n_received, "lost_total": int(self._sent.sum() - self._delivered.sum())}
        if est is not None:
            row.update(x=est.p_W[0], y=est.p_W[1], vx=est.v_W[0], vy=est.v_W[1], pxx=est.P[0, 0], pxy=est.P[0, 1],
                       pyy=est.P[1, 1], pvxvx=est.P[2, 2], pvyvy=est.P[3, 3])
        self.recorder.append("base_station", **row)

    def summary(self) -> dict[str, Any]:
        """Packet and route figures of the run so far for ``metrics.json`` (``base_station`` section)."""
        sent, delivered = int(self._sent.sum()), int(self._delivered.sum())
        uavs = {}
        for i in sorted(self.reporters):
            n = max(int(self._route_steps[i]), 1)
            uavs[self.uav_ids[i]] = {
                "beta_mean": float(self._beta_sum[i] / n), "hops_mean": float(self._hops_sum[i] / n),
                "packets_sent": int(self._sent[i]), "packets_delivered": int(self._delivered[i]),
                "delivery_ratio": float(self._delivered[i] / self._sent[i]) if self._sent[i] else None,
                "relay_steps": int(self._relay_steps[i])}
        return {"steps": self.steps, "routing": "chain" if self.chain else "mst", "packets_sent": sent,
                "packets_delivered": delivered, "packets_lost": sent - delivered, "packets_late": self.late,
                "packets_fused": self.fusion.n_received,
                "delivery_ratio": delivered / sent if sent else None, "uavs": uavs}


def build_base_station(world: World, agents: Sequence[AgentSlot], channel: Channel | None, recorder: RunRecorder
                       ) -> BaseStation | None:
    """The base station of ``world`` when UAVs fuse at it (their agents' estimators are
    :class:`InformationReporter`), else None. Its filter predicts with the first fusing UAV's motion model
    (``worlds.checks`` makes them agree)."""
    reporters = {a.uav: a.agent.estimator for a in agents if isinstance(a.agent.estimator, InformationReporter)}
    if not reporters:
        return None
    if channel is None or world.comms.base_station is None:  # worlds.checks refuses such worlds before this
        raise ValueError("fusion at the base station needs a radio model and comms.base_station")
    model = make_motion_model(reporters[min(reporters)].tracker.config)
    return BaseStation(position_W=np.asarray(world.comms.base_station, dtype=float), uav_ids=[u.id for u in world.uavs],
                       reporters=reporters, fusion=BaseStationFusion(model), channel=channel, recorder=recorder,
                       chain=world.comms.routing == "chain")


class BaseStationLink:
    """The base station as its team protocol sees it (:class:`autonomy.team.base_station.BaseLink`): the UAVs'
    positions come from ``positions`` at each step.

    Parameters
    ----------
    station : BaseStation
        The base.
    positions : callable
        ``positions() -> {uav id: (3,) position (m)}`` of every UAV now.
    """

    def __init__(self, station: BaseStation, positions: Callable[[], Mapping[str, np.ndarray]]) -> None:
        self.station = station
        self.positions = positions

    def step(self, tick: int, t: float, due: Sequence[int]) -> None:
        """Route, send, fuse and record at ``tick`` for the members ``due`` (UAV indices)."""
        self.station.step(tick, t, self.positions(), due)
