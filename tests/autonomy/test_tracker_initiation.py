"""Track initiation with a speed prior, and re-initiation of a track that rejects every detection it is shown."""

import numpy as np
import pytest

from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig
from autonomy.sensing.measurement import Detection


def _box(xy, t, sigma=20.0):
    """A position fix with covariance sigma² I (a bounded-error box detection of half-width sigma √3)."""
    b = sigma * np.sqrt(3.0)
    return Detection(z=np.asarray(xy, float), R=np.eye(2) * sigma**2, t_meas=t, t_arrival=t, sensor_id="box",
                     p_sensor_W=np.array([0.0, 0.0, 100.0]), kind="box", bound=np.array([b, b]))


def test_speed_prior_shrinks_a_noisy_two_point_velocity_by_the_bayes_formula():
    sigma, dt, prior = 20.0, 0.5, 15.0
    tr = SingleTargetTracker(TrackerConfig(initial_speed_sigma=prior, max_target_speed=200.0))
    tr.step(0.0, [_box([0.0, 0.0], 0.0, sigma)])
    tr.step(dt, [_box([40.0, 0.0], dt, sigma)])  # a 80 m/s two-point velocity: 1.4σ of its own noise
    assert tr.filter is not None
    pv = 2 * sigma**2 / dt**2  # variance of the two-point velocity per axis
    k = pv / (pv + prior**2)
    assert tr.filter.x[tr._iv] == pytest.approx([80.0 * (1 - k), 0.0])
    assert np.diag(tr.filter.P)[tr._iv] == pytest.approx([pv * (1 - k)] * 2)
    raw = SingleTargetTracker(TrackerConfig(initial_speed_sigma=None, max_target_speed=200.0))
    raw.step(0.0, [_box([0.0, 0.0], 0.0, sigma)])
    raw.step(dt, [_box([40.0, 0.0], dt, sigma)])
    assert raw.filter.x[raw._iv] == pytest.approx([80.0, 0.0])


def test_a_track_that_gates_out_every_scan_is_restarted_from_the_new_fixes():
    tr = SingleTargetTracker(TrackerConfig(max_missed_scans=3, lost_after_s=100.0))
    for k in range(6):  # a track on a target at rest at the origin
        tr.step(0.5 * k, [_box([0.0, 0.0], 0.5 * k, 2.0)])
    assert tr.initiations == 1
    far = np.array([400.0, -300.0])  # the target is really here: every fix is far outside the gate
    for k in range(6, 12):
        tr.step(0.5 * k, [_box(far, 0.5 * k, 2.0)])
    assert tr.dropped_diverged == 1 and tr.initiations == 2
    assert np.linalg.norm(tr.filter.x[tr._ix] - far) < 10.0


def test_bad_settings_are_named():
    with pytest.raises(ValueError, match="max_missed_scans"):
        TrackerConfig(max_missed_scans=0)
    with pytest.raises(ValueError, match="initial_speed_sigma"):
        TrackerConfig(initial_speed_sigma=-1.0)


def test_bearings_on_the_same_line_do_not_keep_a_diverged_track_alive():
    tr = SingleTargetTracker(TrackerConfig(max_missed_scans=3, lost_after_s=100.0))
    for k in range(6):  # a wrong track at (300, 0) on the line of sight from the sensor at the origin
        tr.step(0.5 * k, [_box([300.0, 0.0], 0.5 * k, 2.0)])
    true_xy = np.array([100.0, 0.0])  # the car is on the same line, closer
    for k in range(6, 14):
        t = 0.5 * k
        bearing = Detection(z=np.array([0.0]), R=np.array([[1e-4]]), t_meas=t, t_arrival=t, sensor_id="cam",
                            p_sensor_W=np.array([0.0, 0.0, 0.0]), kind="bearing")
        tr.step(t, [_box(true_xy, t, 2.0), bearing])
    assert tr.dropped_diverged == 1
    assert np.linalg.norm(tr.filter.x[tr._ix] - true_xy) < 10.0


def test_three_fix_confirmation_ignores_false_alarm_pairs_and_confirms_a_consistent_third_fix():
    cfg = TrackerConfig(confirm_fixes=3, max_target_speed=30.0)
    tr = SingleTargetTracker(cfg)
    tr.step(0.0, [_box([500.0, 0.0], 0.0, 3.0)])
    tr.step(0.5, [_box([505.0, 0.0], 0.5, 3.0)])  # a pair two fixes make: enough for confirm_fixes = 2, not here
    assert tr.filter is None
    tr.step(1.0, [_box([900.0, 400.0], 1.0, 3.0)])  # nowhere near where the pair predicts
    assert tr.filter is None
    tr.step(1.5, [_box([515.0, 0.0], 1.5, 3.0)])  # 10 m/s from (505, 0) at t = 0.5: the pair's prediction
    assert tr.filter is not None and tr.initiations == 1
    two = SingleTargetTracker(TrackerConfig(confirm_fixes=2))
    two.step(0.0, [_box([500.0, 0.0], 0.0, 3.0)])
    two.step(0.5, [_box([505.0, 0.0], 0.5, 3.0)])
    assert two.filter is not None
    with pytest.raises(ValueError, match="confirm_fixes"):
        TrackerConfig(confirm_fixes=4)
