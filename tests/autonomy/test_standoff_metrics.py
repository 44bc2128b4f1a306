"""Standoff and phase-keeping errors against closed-form geometry."""

import numpy as np
import pytest

from autonomy.metrics.standoff import phase_errors, standoff_errors


def _ring(angles, radius, centre=(0.0, 0.0)):
    a = np.asarray(angles, dtype=float)
    return np.c_[centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)][None]


def test_two_uavs_opposite_have_no_phase_error_and_a_known_gap_otherwise():
    target = np.array([[50.0, -20.0]])
    assert phase_errors(_ring([0.3, 0.3 + np.pi], 150.0, target[0]), target) == pytest.approx([0.0], abs=1e-12)
    # 120 degrees apart: the gaps are 120 and 240 degrees, each 60 degrees off 180
    assert phase_errors(_ring([0.0, 2 * np.pi / 3], 150.0, target[0]), target) == pytest.approx([np.pi / 3])


def test_three_uavs_evenly_spread_and_bunched():
    target = np.zeros((1, 2))
    assert phase_errors(_ring([0.1, 0.1 + 2 * np.pi / 3, 0.1 - 2 * np.pi / 3], 80.0), target)[0] == pytest.approx(0.0,
                                                                                                                 abs=1e-12)
    # all three at one bearing: gaps 0, 0, 360 degrees -> (120 + 120 + 240) / 3 = 160 degrees
    assert np.degrees(phase_errors(_ring([1.0, 1.0, 1.0], 80.0), target)[0]) == pytest.approx(160.0)


def test_standoff_error_is_the_radial_distance_to_the_circle():
    target = np.array([[0.0, 0.0], [10.0, 0.0]])
    uav = np.array([[[150.0, 0.0], [0.0, -100.0]], [[10.0, 200.0], [10.0, 150.0]]])
    assert standoff_errors(uav, target, 150.0) == pytest.approx(np.array([[0.0, 50.0], [50.0, 0.0]]))
    assert standoff_errors(uav, target, np.array([150.0, 100.0])) == pytest.approx(np.array([[0.0, 0.0], [50.0, 50.0]]))


def test_one_uav_has_no_phase():
    with pytest.raises(ValueError, match="at least two"):
        phase_errors(np.zeros((3, 1, 2)), np.zeros((3, 2)))
