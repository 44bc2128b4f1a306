"""A team's states built at once: the same states as the constructor builds one by one, the same refusals, and the
stacked arrays a guidance law reads giving the per-teammate predictions bit for bit."""

import numpy as np
import pytest

from interfaces.state import TeammateState
from interfaces.team_states import TeamStates, teammate_slots, teammates_xy


def _fields(s: TeammateState) -> tuple:
    plan = None if s.plan_p_W is None else s.plan_p_W.tolist()
    return (s.id, type(s.t), s.t, s.p_W.tolist(), s.v_W.tolist(), type(s.yaw), s.yaw, s.phase_slot, plan, s.plan_dt,
            s.p_W.flags.writeable, s.v_W.flags.writeable)


def _team(n: int = 6, seed: int = 4) -> tuple[TeamStates, np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    p, v, yaw = rng.normal(scale=100.0, size=(n, 3)), rng.normal(scale=10.0, size=(n, 3)), rng.normal(size=n)
    return TeamStates.of(np.float32(2.5), p, v, list(yaw)), p, v, yaw


def test_of_builds_the_states_the_constructor_builds():
    team, p, v, yaw = _team()
    one_by_one = [TeammateState(id=j, t=np.float32(2.5), p_W=p[j], v_W=v[j], yaw=yaw[j]) for j in range(6)]
    assert isinstance(team, tuple) and [_fields(s) for s in team] == [_fields(s) for s in one_by_one]
    p[0, 0] = 99.0  # the states hold copies
    assert team[0].p_W[0] != 99.0 and team[3].slot == 3
    assert team.p_W.tolist() == [s.p_W.tolist() for s in team] and not team.p_W.flags.writeable


def test_without_is_the_team_less_one_member_sharing_its_states():
    team, *_ = _team()
    mates = team.without(2)
    assert [s.id for s in mates] == [0, 1, 3, 4, 5]
    assert all(a is b for a, b in zip(mates, team[:2] + team[3:], strict=True))
    assert mates.ids.tolist() == [0, 1, 3, 4, 5] and mates.p_W.tolist() == [s.p_W.tolist() for s in mates]
    assert mates.v_W.tolist() == [s.v_W.tolist() for s in mates] and mates.t.tolist() == [2.5] * 5
    assert [s.id for s in team.without(0)] == [1, 2, 3, 4, 5] and [s.id for s in team.without(5)] == [0, 1, 2, 3, 4]


@pytest.mark.parametrize("args, match", [
    ((np.nan, np.zeros((2, 3)), np.zeros((2, 3)), [0, 0]), "TeammateState.t must be a finite number"),
    ((0.0, [[0, 0, np.inf], [0, 0, 0]], np.zeros((2, 3)), [0, 0]),
     r"TeammateState.p_W must be a finite array of length 3 per member, got shape \(2, 3\)"),
    ((0.0, np.zeros((2, 3)), np.zeros((2, 2)), [0, 0]),
     r"TeammateState.v_W must be a finite array of length 3 per member, got shape \(2, 2\)"),
    ((0.0, np.zeros((2, 3)), np.zeros((2, 3)), [0, np.nan]), "TeammateState.yaw must be a finite number"),
    ((0.0, np.zeros((2, 3)), np.zeros((3, 3)), [0, 0]),
     "TeamStates.of needs one p_W, v_W and yaw per member, got 2, 3 and 2"),
])
def test_of_rejects_what_the_constructor_rejects(args, match):
    with pytest.raises(ValueError, match=match):
        TeamStates.of(*args)


def test_teammates_xy_equals_each_prediction_bit_for_bit():
    rng = np.random.default_rng(7)
    mates = []
    for j in range(7):
        plan = rng.normal(scale=50.0, size=(4, 3)) if j % 3 == 1 else None
        mates.append(TeammateState(id=j, t=float(rng.uniform(0, 2)), p_W=rng.normal(scale=100.0, size=3),
                                   v_W=rng.normal(scale=10.0, size=3), plan_p_W=plan, plan_dt=0.7,
                                   phase_slot=(3 * j) % 7 if j % 2 else None))
    team = _team(9)[0].without(4)
    for t in (0.0, 1.3, 2.9, 5.0):
        for states in (mates, team, list(team)):  # a plain list takes the per-teammate path, the view its arrays
            expected = np.array([m.predict_xy(np.array([t]))[0] for m in states])
            got = teammates_xy(states, t)
            assert got.shape == (len(states), 2) and got.tobytes() == expected.tobytes()
    assert teammates_xy([], 1.0).shape == (0, 2)
    assert teammate_slots(mates).tolist() == [m.slot for m in mates] == [0, 3, 2, 2, 4, 1, 6]
    assert teammate_slots(team).tolist() == [0, 1, 2, 3, 5, 6, 7, 8]


def test_a_team_pickles_and_copies_with_its_arrays():
    import copy
    import pickle

    team = _team()[0].without(1)
    values = lambda states: [_fields(s)[:-2] for s in states]  # noqa: E731 - a copy of an array is writeable
    for clone in (pickle.loads(pickle.dumps(team)), copy.deepcopy(team), copy.copy(team)):
        assert type(clone) is TeamStates and values(clone) == values(team)
        assert clone.ids.tolist() == [0, 2, 3, 4, 5] and clone.p_W.tobytes() == team.p_W.tobytes()
