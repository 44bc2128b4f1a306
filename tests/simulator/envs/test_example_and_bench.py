"""The example script's scripted policy and its printout, and the benchmark's registration with ``skytrack bench``."""

import runpy
import sys
from pathlib import Path

import numpy as np
import pytest

from simulator.bench.runner import discover

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "gym_random_vs_scripted.py"


@pytest.fixture(scope="module")
def example():
    return runpy.run_path(str(EXAMPLE), run_name="example")


def obs(x, y, yaw, target=None):
    t = np.zeros(6, np.float32) if target is None else np.array([1, 0, *target, 0, 0], np.float32)
    return {"own": np.array([x, y, 60, 0, 0, 0, np.cos(yaw), np.sin(yaw)], np.float32), "target": t}


def test_scripted_policy_flies_the_vector_field_around_the_estimate(example):
    scripted = example["scripted"]
    # on the circle, heading along the counter-clockwise tangent: no turn
    np.testing.assert_allclose(scripted(obs(100.0, 0.0, np.pi / 2, (0.0, 0.0)), 100.0, 0.5), [12, 0, 60], atol=1e-6)
    # far out east, facing east: the field points back in (course error about pi), the turn saturates
    a = scripted(obs(10_000.0, 0.0, 0.0, (0.0, 0.0)), 100.0, 0.5)
    assert abs(a[1]) == pytest.approx(0.5)
    # no estimate: straight on
    np.testing.assert_allclose(scripted(obs(0.0, 0.0, 1.0), 100.0, 0.5), [12, 0, 60])


def test_example_prints_both_returns(monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", [str(EXAMPLE), "--world", "demo", "--duration", "1", "--seed", "2"])
    runpy.run_path(str(EXAMPLE), run_name="__main__")
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "demo, 1 s, seed 2, learner uav1 (standoff 100 m)"
    assert [line.split(":")[0].strip() for line in lines[1:]] == ["random", "scripted"]
    assert all("over 9 steps" in line and line.endswith("ended by time") for line in lines[1:])


def test_gym_env_benchmark_is_registered():
    assert discover()["gym_env"].produces == ("gym_env_steps_per_s", "gym_env_steps_per_s_demo", "gym_env_reset_s",
                                               "gym_env_rtf_over_run")
