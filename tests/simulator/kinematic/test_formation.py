"""Paper 003's closed loop: exact target manoeuvres, and the formation reaching the det F bound in closed loop."""

import numpy as np
import pytest

from simulator.kinematic.formation import CASES, FormationLoopConfig, Segment, manoeuvre_truth, run_formation_loop


def test_turn_keeps_speed_and_turns_by_omega_t():
    v0 = np.array([12.0, 0.0])
    x = manoeuvre_truth((Segment(5.0, omega=0.3),), np.zeros(2), v0, 0.1)
    assert len(x) == 51
    speed = np.hypot(x[:, 1], x[:, 3])
    assert np.allclose(speed, 12.0)
    assert np.arctan2(x[-1, 3], x[-1, 1]) == pytest.approx(1.5)
    # on the circle of radius v / omega around (0, 40)
    assert np.allclose(np.hypot(x[:, 0], x[:, 2] - 40.0), 40.0)


def test_constant_acceleration_matches_closed_form():
    x = manoeuvre_truth((Segment(4.0, accel=(0.5, -0.25)),), np.array([1.0, 2.0]), np.array([3.0, 4.0]), 0.1)
    t = 4.0
    assert x[-1, [0, 2]] == pytest.approx([1 + 3 * t + 0.25 * t**2, 2 + 4 * t - 0.125 * t**2])
    assert x[-1, [1, 3]] == pytest.approx([3 + 0.5 * t, 4 - 0.25 * t])


def test_case_4_is_the_papers_turn_sequence():
    omegas = [s.omega for s in CASES[4]]
    assert omegas == [0.0, 0.35, 0.0, -0.35, 0.0]


def test_optimal_formation_reaches_the_bound_and_trailing_one_does_not():
    def gap(formation):
        r = run_formation_loop(FormationLoopConfig(case=1, formation=formation, max_duration=12.0),
                               np.random.default_rng(3))
        late = r.t >= 6.0
        return float(np.mean((r.max_log_det_fim - r.log_det_fim)[late])), float(np.mean(r.error[late]))

    g_opt, e_opt = gap("optimal")
    g_trail, e_trail = gap("trail")
    assert g_opt < 0.05  # det F within 5 % of (½ Σ c_i²)²
    assert g_trail > 1.0  # nearly parallel bearing lines
    assert e_opt < e_trail


def test_bad_configuration_is_named():
    with pytest.raises(ValueError, match="formation must be"):
        FormationLoopConfig(formation="circle")
    with pytest.raises(ValueError, match="case must be one of"):
        FormationLoopConfig(case=9)


@pytest.mark.parametrize("formation", ["optimal", "fixed", "trail"])
def test_every_formation_flies_the_common_range(formation):
    r = run_formation_loop(FormationLoopConfig(case=1, formation=formation, ranges=(95.0,) * 3, max_duration=15.0),
                           np.random.default_rng(3))
    late = r.t >= 10.0
    ranges = np.linalg.norm(r.agents[late] - r.truth[late][:, None, [0, 2]], axis=2)
    assert np.mean(ranges, axis=0) == pytest.approx([95.0] * 3, abs=6.0)


def test_fixed_bearings_set_the_fixed_formations_directions():
    theta = (0.0, 2.0, 4.0)
    r = run_formation_loop(FormationLoopConfig(case=1, formation="fixed", ranges=(95.0,) * 3, fixed_bearings=theta,
                                               max_duration=15.0), np.random.default_rng(3))
    rel = r.agents[-1] - r.truth[-1][[0, 2]]
    off = np.angle(np.exp(1j * (np.arctan2(rel[:, 1], rel[:, 0]) - np.array(theta))))
    assert off == pytest.approx([0.0] * 3, abs=0.1)


def test_bad_ranges_and_bearings_are_named():
    with pytest.raises(ValueError, match="ranges must be 3 values > 0 m"):
        FormationLoopConfig(ranges=(95.0, -1.0, 95.0))
    with pytest.raises(ValueError, match="fixed_bearings needs ranges and 3 angles"):
        FormationLoopConfig(fixed_bearings=(0.0, 1.0, 2.0))
