"""The recorded-number checks used by the golden records and the tracker sequence (:mod:`tests.numeric_record`)."""

import numpy as np

from tests.numeric_record import RTOL, close, differences, flatten, machine_key, summarise


def test_summary_holds_sums_extremes_and_samples():
    a = np.array([[1.0, -2.0], [np.nan, 4.0]])
    s = summarise(a)
    assert s[:6] == [4.0, 1.0, 3.0, 7.0, -2.0, 4.0]
    assert len(s) > 6 and s[6] == 1.0 and s[-1] == 4.0  # samples from the first to the last entry
    assert summarise(np.array(["a", "b"]))[0] == "digest"
    assert summarise(np.array(["a", "b"])) != summarise(np.array(["a", "c"]))


def test_rounding_passes_and_a_real_change_fails():
    rng = np.random.default_rng(3)
    x = rng.normal(size=500) * 300.0
    base = summarise(x)
    assert close(base, summarise(x * (1.0 + 1e-12)))  # what another machine's rounding moves
    assert not close(base, summarise(x * (1.0 + 1e-4)))  # what a change of arithmetic moves
    y = x.copy()
    y[250] += 1.0  # one value changed in the middle
    assert not close(base, summarise(y))
    assert not close(base, summarise(x[:-1]))  # one row fewer
    assert close([float("nan")], [float("nan")]) and not close([float("nan")], [0.0])
    assert abs(RTOL - 1e-6) < 1e-18


def test_differences_name_changed_missing_and_extra_keys():
    want = {"a": summarise(np.arange(5.0)), "b": summarise(np.ones(3)), "c": ["digest", "x"]}
    got = {"a": summarise(np.arange(5.0)), "b": summarise(np.ones(4)), "d": ["digest", "x"]}
    assert differences(want, got) == ["b", "c", "d"]


def test_flatten_keeps_paths_and_leaves():
    flat = flatten({"m": {"x": 1, "y": [2.5, "s", None, True]}})
    assert flat == {"m.x": 1.0, "m.y[0]": 2.5, "m.y[1]": "s", "m.y[2]": None, "m.y[3]": True}


def test_machine_key_is_stable_here():
    assert machine_key() == machine_key() and len(machine_key()) == 16
