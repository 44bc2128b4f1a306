"""Fixtures for whole-run tests: short runs of the demo world."""

import signal

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


@pytest.fixture
def sigint_raises():
    """SIGINT raising KeyboardInterrupt, as in a terminal, whatever the test process inherited (a job started in the
    background of a non-interactive shell starts with SIGINT ignored, which the run rightly leaves alone)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


def sigint_as_in_a_terminal() -> None:
    """``preexec_fn`` of a child ``skytrack``: SIGINT to its default disposition, so Python raises KeyboardInterrupt
    on it (as started from a terminal) even when this test process inherited it ignored."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
