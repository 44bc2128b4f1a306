"""The shared states: validation names the type and the field; arrays are read-only float copies."""

import numpy as np
import pytest

from interfaces.state import OwnState, TargetEstimate, TeammateState, teammates_xy


@pytest.mark.parametrize("make, match", [
    (lambda: OwnState(t="0", p_W=[0, 0, 0], v_W=[0, 0, 0], yaw=0.0), "OwnState.t must be a finite number"),
    (lambda: OwnState(t=0.0, p_W=[0, 0], v_W=[0, 0, 0], yaw=0.0), "OwnState.p_W must be a finite array of length 3"),
    (lambda: OwnState(t=0.0, p_W=[0, 0, 0], v_W=[0, 0, 0], yaw=np.inf), "OwnState.yaw"),
    (lambda: TargetEstimate(t=0.0, p_W=[0, 0], v_W=[0, 0, 0]), "TargetEstimate.v_W must be a finite array of length 2"),
    (lambda: TargetEstimate(t=0.0, p_W=[0, 0], v_W=[0, 0], P=np.eye(3)), "TargetEstimate.P"),
    (lambda: TeammateState(id=-1, t=0.0, p_W=[0, 0, 0], v_W=[0, 0, 0]), "TeammateState.id"),
    (lambda: TeammateState(id=0, t=np.nan, p_W=[0, 0, 0], v_W=[0, 0, 0]), "TeammateState.t"),
    (lambda: TeammateState(id=0, t=0.0, p_W=[0, 0, 0], v_W=[0, 0, 0], plan_dt=0.0), "TeammateState.plan_dt"),
])
def test_invalid_states_rejected(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_states_hold_read_only_float_copies():
    p = np.array([1, 2, 3])
    own = OwnState(t=np.float32(1.5), p_W=p, v_W=[3.0, 4.0, 0.0], yaw=0.0)
    p[0] = 7
    assert own.p_W.tolist() == [1.0, 2.0, 3.0] and not own.p_W.flags.writeable and type(own.t) is float
    assert own.speed == 5.0 and own.course(min_speed=0.5) == pytest.approx(np.arctan2(4.0, 3.0))
    est = TargetEstimate(t=0.0, p_W=[0, 0], v_W=[1, 0], P=np.eye(4))
    assert not est.P.flags.writeable and est.predict_xy(np.array([1.0, 2.0])).tolist() == [[1.0, 0.0], [2.0, 0.0]]


def _fields(s: TeammateState) -> tuple:
    plan = None if s.plan_p_W is None else s.plan_p_W.tolist()
    return (s.id, type(s.t), s.t, s.p_W.tolist(), s.v_W.tolist(), type(s.yaw), s.yaw, s.phase_slot, plan, s.plan_dt,
            s.p_W.flags.writeable, s.v_W.flags.writeable)


def test_team_builds_the_states_the_constructor_builds():
    rng = np.random.default_rng(4)
    p, v, yaw = rng.normal(size=(6, 3)), rng.normal(size=(6, 3)), rng.normal(size=6)
    team = TeammateState.team(np.float32(2.5), p, v, list(yaw))
    one_by_one = [TeammateState(id=j, t=np.float32(2.5), p_W=p[j], v_W=v[j], yaw=yaw[j]) for j in range(6)]
    assert [_fields(s) for s in team] == [_fields(s) for s in one_by_one]
    p[0, 0] = 99.0  # the states hold copies
    assert team[0].p_W[0] != 99.0 and team[3].slot == 3


@pytest.mark.parametrize("args, match", [
    ((np.nan, np.zeros((2, 3)), np.zeros((2, 3)), [0, 0]), "TeammateState.t must be a finite number"),
    ((0.0, [[0, 0, np.inf], [0, 0, 0]], np.zeros((2, 3)), [0, 0]),
     r"TeammateState.p_W must be a finite array of length 3 per teammate, got shape \(2, 3\)"),
    ((0.0, np.zeros((2, 3)), np.zeros((2, 2)), [0, 0]),
     r"TeammateState.v_W must be a finite array of length 3 per teammate, got shape \(2, 2\)"),
    ((0.0, np.zeros((2, 3)), np.zeros((2, 3)), [0, np.nan]), "TeammateState.yaw must be a finite number"),
    ((0.0, np.zeros((2, 3)), np.zeros((3, 3)), [0, 0]),
     "TeammateState.team needs one p_W, v_W and yaw per teammate, got 2, 3 and 2"),
])
def test_team_rejects_what_the_constructor_rejects(args, match):
    with pytest.raises(ValueError, match=match):
        TeammateState.team(*args)


def test_teammates_xy_equals_each_prediction_bit_for_bit():
    rng = np.random.default_rng(7)
    mates = []
    for j in range(7):
        plan = rng.normal(scale=50.0, size=(4, 3)) if j % 3 == 1 else None
        mates.append(TeammateState(id=j, t=float(rng.uniform(0, 2)), p_W=rng.normal(scale=100.0, size=3),
                                   v_W=rng.normal(scale=10.0, size=3), plan_p_W=plan, plan_dt=0.7))
    for t in (0.0, 1.3, 2.9, 5.0):
        expected = np.array([m.predict_xy(np.array([t]))[0] for m in mates])
        got = teammates_xy(mates, t)
        assert got.shape == (7, 2) and got.tobytes() == expected.tobytes()
    assert teammates_xy([], 1.0).shape == (0, 2)
