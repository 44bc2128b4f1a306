"""The perfect-comms inbox of a large team: every UAV's true state is built once per tick and shared by all the
inboxes of that tick, equal to the states the constructor would build one by one."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from interfaces.state import TeammateState
from interfaces.team_states import TeamStates
from simulator.comms import Comms
from simulator.truth import yaw_of
from worlds.schema import CommsSection

N = 5


class _Quads:
    """A fleet whose state moves with the tick set on it and counts how often it is read."""

    def __init__(self) -> None:
        self.tick = 0
        self.reads = 0

    @property
    def state(self) -> SimpleNamespace:
        self.reads += 1
        k = np.arange(N, dtype=float)[:, None]
        yaw = 0.3 * np.arange(N) - 0.5
        q = np.stack([np.zeros(N), np.zeros(N), np.sin(yaw / 2), np.cos(yaw / 2)], axis=1)
        return SimpleNamespace(p_W=np.hstack([10.0 * k + self.tick, -k, 50.0 + k]),
                               v_W=np.hstack([np.ones((N, 1)), 0.5 * k, np.zeros((N, 1))]), q_WB=q)


def _comms(quads: _Quads) -> Comms:
    return Comms(uav_ids=[f"uav{j}" for j in range(N)], quads=quads, channel=None, comms=CommsSection(), outages=[],
                 scene_query=None, receivers={}, share_estimates=False)


def _one_by_one(quads: _Quads, i: int, t: float) -> list[TeammateState]:
    st = quads.state
    return [TeammateState(id=j, t=t, p_W=st.p_W[j], v_W=st.v_W[j], yaw=yaw_of(st.q_WB[j])) for j in range(N) if j != i]


def _fields(s: TeammateState) -> tuple:
    return (s.id, s.t, s.p_W.tolist(), s.v_W.tolist(), s.yaw, s.phase_slot, s.plan_p_W, s.plan_dt,
            s.p_W.flags.writeable, s.v_W.flags.writeable)


def test_inbox_holds_every_teammate_but_itself_as_the_constructor_builds_them():
    quads = _Quads()
    comms = _comms(quads)
    for i in range(N):
        mates, estimates = comms.inbox(i, 0.25, 60)
        assert [_fields(s) for s in mates] == [_fields(s) for s in _one_by_one(quads, i, 0.25)]
        assert [s.id for s in mates] == [j for j in range(N) if j != i] and estimates == []


def test_team_states_are_built_once_per_tick_and_shared_by_its_inboxes():
    quads = _Quads()
    comms = _comms(quads)
    inboxes = [comms.inbox(i, 0.25, 60)[0] for i in range(N)]
    assert quads.reads == 1  # one read of the fleet for the whole tick, not one per agent
    of_uav1 = {id(m) for box in inboxes for m in box if m.id == 1}
    assert len(of_uav1) == 1  # the same object in every inbox that holds UAV 1
    quads.tick = 24  # the next agent tick: the UAVs moved
    mates = comms.inbox(0, 0.35, 84)[0]
    assert quads.reads == 2
    assert mates[0].t == 0.35 and mates[0].p_W.tolist() == [34.0, -1.0, 51.0]


def test_an_inbox_carries_its_teammates_stacked():
    quads = _Quads()
    mates = _comms(quads).inbox(3, 0.25, 60)[0]
    assert isinstance(mates, TeamStates) and mates.ids.tolist() == [0, 1, 2, 4]
    assert mates.p_W.tolist() == [s.p_W.tolist() for s in mates] and mates.t.tolist() == [0.25] * 4
