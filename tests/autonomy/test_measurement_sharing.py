"""Shared bearings in the tracker (paper 003's centralised augmented measurement): crossing bearings of one time start
a track at their intersection, each scan time becomes one stacked update of every sensor's bearing, copies arriving
after their scan are dropped, and the IMM runs inside the tracker."""

import numpy as np
import pytest

from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig
from autonomy.fusion.measurement_sharing import relayed
from autonomy.sensing.measurement import Detection

SIGMA = 0.02  # rad
SENSORS = {"a/bearing0": (0.0, 0.0), "b/bearing0": (200.0, 0.0), "c/bearing0": (100.0, -150.0)}


def truth(t: float) -> np.ndarray:
    return np.array([100.0 + 8.0 * t, 100.0])


def bearings(t: float, rng: np.random.Generator | None, delay: float = 0.0) -> list[Detection]:
    out = []
    for sid, p in SENSORS.items():
        d = truth(t) - np.array(p)
        az = np.arctan2(d[1], d[0]) + (0.0 if rng is None else SIGMA * rng.normal())
        out.append(Detection(z=np.array([az]), R=np.array([[SIGMA**2]]), t_meas=t, t_arrival=t + delay, sensor_id=sid,
                             p_sensor_W=np.array([p[0], p[1], 50.0]), kind="bearing"))
    return out


def tracker(**kw) -> SingleTargetTracker:
    return SingleTargetTracker(TrackerConfig(filter="imm", model="cv", q=0.05, stack_scans=True, **kw))


def test_crossing_bearings_start_a_track_at_their_intersection():
    trk = tracker()
    assert trk.step(0.0, bearings(0.0, None)) is None  # one fix: tentative
    est = trk.step(0.1, bearings(0.1, None))
    assert est is not None and trk.initiations == 1
    np.testing.assert_allclose(est.p_W, truth(0.1), atol=1e-6)  # noiseless lines meet at the target
    # the covariance is the inverse bearing FIM at ranges 100-250 m: metres, not zero and not kilometres
    assert 0.5 < np.sqrt(est.P[0, 0]) < 10.0


def test_a_lone_bearing_never_starts_a_track():
    trk = tracker()
    for k in range(5):
        assert trk.step(0.1 * k, bearings(0.1 * k, None)[:1]) is None
    assert trk.initiations == 0


def test_parallel_bearings_do_not_fix_a_position():
    trk = tracker()
    lines = [Detection(z=np.array([0.0]), R=np.array([[SIGMA**2]]), t_meas=t, t_arrival=t, sensor_id=f"s{j}",
                       p_sensor_W=np.array([0.0, 5.0 * j, 50.0]), kind="bearing") for t in (0.0, 0.1) for j in range(2)]
    assert trk.step(0.1, lines) is None and trk.initiations == 0


def test_each_scan_is_one_stacked_update_of_every_sensor_and_the_imm_converges():
    rng = np.random.default_rng(3)
    trk = tracker()
    errs = []
    for k in range(200):
        t = 0.1 * k
        est = trk.step(t, bearings(t, rng))
        if est is not None and t >= 10.0:
            errs.append(np.linalg.norm(est.p_W - truth(t)))
    assert type(trk.filter).__name__ == "IMM"
    assert trk.updates == 198  # scans 2 .. 199: one update per scan time, not one per bearing
    # every sensor's bearing in (nearly) every update: the 99.9 % gate may refuse one now and then
    assert sorted(trk.used_by_sensor) == sorted(SENSORS) and min(trk.used_by_sensor.values()) >= 195
    # one scan fixes the target to about σ·r ≈ 0.02 · 150 m = 3 m per axis; 10 Hz filtering brings it well below
    assert np.mean(errs) < 1.5


def test_a_copy_arriving_after_a_newer_scan_is_dropped():
    trk = tracker()
    trk.step(0.0, bearings(0.0, None))
    trk.step(0.1, bearings(0.1, None))  # starts the track (no update)
    a2, *mates2 = bearings(0.2, None)
    a3, *mates3 = bearings(0.3, None)
    trk.step(0.2, [a2])
    trk.step(0.3, [a3])
    late = relayed(mates2, 0.15)
    assert all(d.t_arrival == pytest.approx(0.35) for d in late)
    trk.step(0.35, late)  # older than the track (at 0.3 s): dropped
    assert trk.used_by_sensor == {"a/bearing0": 2} and trk.updates == 2
    trk.step(0.4, relayed(mates3, 0.05))  # the step at 0.35 s predicted the track past 0.3 s: dropped too
    assert trk.used_by_sensor == {"a/bearing0": 2} and trk.updates == 2


def test_imm_needs_the_cv_layout_and_valid_mode_settings():
    with pytest.raises(ValueError, match="model must be cv"):
        TrackerConfig(filter="imm", model="singer")
    with pytest.raises(ValueError, match="imm_p_stay"):
        TrackerConfig(filter="imm", imm_p_stay=1.0)
    with pytest.raises(ValueError, match="delay_s"):
        relayed([], -1.0)
