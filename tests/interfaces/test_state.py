"""The shared states: validation names the type and the field; arrays are read-only float copies."""

import numpy as np
import pytest

from interfaces._checks import all_finite
from interfaces.state import OwnState, TargetEstimate, TeammateState


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


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_all_finite_finds_one_bad_entry_anywhere(bad):
    for shape in [(1,), (4,), (4, 4), (6, 6), (40,)]:  # small ones as a list of floats, larger ones by numpy
        arr = np.full(shape, 3.0)
        assert all_finite(arr)
        for k in range(arr.size):
            a = arr.copy().reshape(-1)
            a[k] = bad
            assert not all_finite(a.reshape(shape))
    huge = np.array([1e200, -1e300, 1.7e308])
    assert all_finite(huge)
    assert not all_finite(np.r_[huge, bad])
    assert all_finite(np.zeros(0))
    with pytest.raises(ValueError, match="P must be a finite"):
        TargetEstimate(t=0.0, p_W=np.zeros(2), v_W=np.zeros(2), P=np.diag([1.0, 1.0, 1.0, bad]))
    assert TargetEstimate(t=0.0, p_W=np.array([1e200, 0.0]), v_W=np.zeros(2)).p_W[0] == 1e200


def test_estimate_of_arrays_equals_the_constructors_and_takes_the_arrays_read_only():
    p, v, P = np.array([1.0, -2.0]), np.array([0.5, 3.0]), np.arange(16.0).reshape(4, 4)
    made = TargetEstimate.of_arrays(2.5, p, v, P)
    ref = TargetEstimate(t=2.5, p_W=[1.0, -2.0], v_W=[0.5, 3.0], P=np.arange(16.0).reshape(4, 4))
    assert made.t == ref.t and type(made.t) is float
    for a, b in ((made.p_W, ref.p_W), (made.v_W, ref.v_W), (made.P, ref.P)):
        assert a.dtype == b.dtype and np.array_equal(a, b) and not a.flags.writeable
    assert made.p_W is p  # handed over, not copied
    assert TargetEstimate.of_arrays(1.0, np.zeros(3), np.zeros(3), None).P is None


@pytest.mark.parametrize("p, v, P, match", [
    (np.array([np.nan, 0.0]), np.zeros(2), np.eye(4), "p_W"),
    (np.zeros(2), np.array([0.0, np.inf]), np.eye(4), "v_W"),
    (np.zeros(2), np.zeros(2), np.full((4, 4), np.nan), "P"),
    (np.zeros(2), np.zeros(2), np.eye(6), "P"),
    (np.zeros(4), np.zeros(4), None, "p_W"),
    (np.zeros(2), np.zeros(3), None, "v_W"),
])
def test_estimate_of_arrays_refuses_what_the_constructor_refuses(p, v, P, match):
    with pytest.raises(ValueError, match=match):
        TargetEstimate.of_arrays(0.0, p, v, P)
    with pytest.raises(ValueError, match="t"):
        TargetEstimate.of_arrays(float("nan"), np.zeros(2), np.zeros(2), None)


def test_estimate_of_arrays_converts_other_arrays_as_the_constructor_does():
    made = TargetEstimate.of_arrays(1, np.array([1, 2]), np.array([0, 0], dtype=np.float32), None)
    assert made.t == 1.0 and made.p_W.dtype == np.float64 and made.v_W.dtype == np.float64


def test_estimate_rows_of_equals_of_arrays_row_by_row_with_read_only_views():
    rng = np.random.default_rng(3)
    t, p, v = [0.5, 1.0, np.float64(2.0)], rng.normal(size=(3, 2)), rng.normal(size=(3, 2))
    P = rng.normal(size=(3, 4, 4))
    made = TargetEstimate.rows_of(t, p, v, P)
    for k, est in enumerate(made):
        ref = TargetEstimate.of_arrays(float(t[k]), p[k].copy(), v[k].copy(), P[k].copy())
        assert est.t == ref.t and type(est.t) is float
        for a, b in ((est.p_W, ref.p_W), (est.v_W, ref.v_W), (est.P, ref.P)):
            assert a.shape == b.shape and np.array_equal(a, b) and not a.flags.writeable
        with pytest.raises(ValueError):
            est.p_W[0] = 1.0
    assert np.shares_memory(made[1].P, P)  # handed over, not copied


@pytest.mark.parametrize("row", [0, 2])
def test_estimate_rows_of_refuses_a_bad_row_as_of_arrays_does(row):
    p, v, P = np.zeros((3, 2)), np.zeros((3, 2)), np.tile(np.eye(4), (3, 1, 1))
    p[row, 1] = np.nan
    with pytest.raises(ValueError, match="p_W"):
        TargetEstimate.rows_of([0.0, 1.0, 2.0], p, v, P)
    with pytest.raises(ValueError, match="t"):
        TargetEstimate.rows_of([0.0, float("inf"), 2.0], np.zeros((3, 2)), v, P)
