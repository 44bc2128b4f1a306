"""Fixtures for whole-run tests: short runs of the demo world."""

import numpy as np
import pytest

from simulator.api import run


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    """A 6-second demo run, shared by the tests of one module."""
    return run("demo", duration=6.0, seed=5, out_dir=tmp_path_factory.mktemp("demo"))


def assert_records_equal(a, b):
    assert sorted(a.record.streams) == sorted(b.record.streams)
    for name, cols in a.record.streams.items():
        for col, values in cols.items():
            other = b.record.streams[name][col]
            assert values.shape == other.shape, f"{name}.{col}"
            assert np.array_equal(values, other, equal_nan=values.dtype.kind == "f"), f"{name}.{col} differs"
