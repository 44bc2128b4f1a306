"""Identity metrics of a UAV's target estimate among traffic (autonomy.metrics.identity) on constructed sequences."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.metrics.identity import cars_on, identity_metrics

CARS = np.array([[0.0, 0.0], [100.0, 0.0], [0.0, 100.0]])  # cars 0, 1, 2, 100 m apart


def _sequence(on: list[int | None], dt: float = 0.5, offset: float = 5.0):
    """Times, estimates 5 m from the car named at each step (None: no estimate; -1: 50 m from every car) and the
    (still) cars."""
    est = [None if c is None else np.array([50.0, 50.0]) if c == -1 else CARS[c] + [offset, 0.0]
           for c in on]
    t = 2.0 + dt * np.arange(len(on))
    return t, est, np.repeat(CARS[None], len(on), axis=0)


def test_the_car_an_estimate_is_on_is_the_nearest_within_the_radius():
    est = np.array([[3.0, 4.0], [60.0, 0.0], [90.0, 0.0], [np.nan, np.nan], [0.0, 20.0], [0.0, 20.01]])
    truth = np.repeat(CARS[None], len(est), axis=0)
    # 5 m from car 0; 40 m from car 1 (nearest, too far); 10 m from car 1; none; exactly at the radius; just beyond
    assert cars_on(est, truth, 20.0).tolist() == [0, -1, 1, -1, 0, -1]
    assert cars_on(est, truth, 45.0).tolist() == [0, 1, 1, -1, 0, 0]


def test_always_on_target():
    s = identity_metrics(*_sequence([0] * 6), target=0)
    assert (s.steps, s.identity_fraction, s.id_switches, s.time_to_acquire_s, s.losses) == (6, 1.0, 0, 0.0, 0)
    assert math.isnan(s.time_to_reacquire_mean_s) and s.unrecovered_losses == 0


def test_acquisition_losses_and_reacquisitions():
    """Steps (dt 0.5 s): none, none, 1, 0, 0, none, 0, 2, -, 2, 0, 0, none.

    On target at steps 3, 4, 6, 10, 11: fraction 5/13; acquired at step 3 (1.5 s); losses at steps 5 (back at 6:
    0.5 s) and 7 (back at 10: 1.5 s) and 12 (never back); cars seen without the none steps: 1 0 0 0 2 2 0 0 → 3
    switches."""
    on = [None, None, 1, 0, 0, None, 0, 2, -1, 2, 0, 0, None]
    s = identity_metrics(*_sequence(on), target=0)
    assert s.steps == 13 and s.identity_fraction == pytest.approx(5 / 13)
    assert s.id_switches == 3
    assert s.time_to_acquire_s == pytest.approx(1.5)
    assert s.losses == 3 and s.unrecovered_losses == 1
    assert s.time_to_reacquire_mean_s == pytest.approx(1.0) and s.time_to_reacquire_max_s == pytest.approx(1.5)


def test_on_another_car_all_along():
    s = identity_metrics(*_sequence([1, 1, 2, None, 2]), target=0)
    assert s.identity_fraction == 0.0 and s.id_switches == 1 and s.losses == 0
    assert math.isnan(s.time_to_acquire_s) and math.isnan(s.time_to_reacquire_max_s)


def test_a_lost_target_ends_unrecovered():
    s = identity_metrics(*_sequence([0, 0, 1, 1]), target=0)
    assert (s.losses, s.unrecovered_losses, s.id_switches) == (1, 1, 1)
    assert math.isnan(s.time_to_reacquire_mean_s)


def test_moving_cars_are_matched_at_each_step():
    # car 0 drives east 10 m a step; the estimate stays at x = 0: on it at steps 0 and 1 only (0, 10 m; then 20.5 m)
    t = np.arange(4.0)
    truth = np.stack([[[10.0 * k + 0.5, 0.0], [500.0, 0.0]] for k in range(4)])
    s = identity_metrics(t, [np.zeros(3)] * 4, truth, target=0)  # a 3-D estimate: x, y used
    assert s.identity_fraction == 0.5 and s.losses == 1 and s.unrecovered_losses == 1


def test_no_steps():
    s = identity_metrics(np.zeros(0), [], np.zeros((0, 2, 2)), target=1)
    assert s.steps == 0 and math.isnan(s.identity_fraction) and s.losses == 0


def test_inputs_are_checked():
    t, est, truth = _sequence([0, 0])
    with pytest.raises(ValueError, match="target"):
        identity_metrics(t, est, truth, target=3)
    with pytest.raises(ValueError, match="one entry per step"):
        identity_metrics(t, est[:1], truth, target=0)
    with pytest.raises(ValueError, match="truth_xy"):
        identity_metrics(t, est, truth[:1], target=0)
    with pytest.raises(ValueError, match="increase"):
        identity_metrics(t[::-1], est, truth, target=0)
    with pytest.raises(ValueError, match="match_radius_m"):
        identity_metrics(t, est, truth, target=0, match_radius_m=0.0)
