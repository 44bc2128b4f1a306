"""CLEAR-MOT, IDF1 and GOSPA of hand-made track sequences (autonomy.metrics.mot), each value derived by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.metrics.mot import ClearMot

A, B = np.array([0.0, 0.0]), np.array([100.0, 0.0])  # two cars 100 m apart: no track is near both


def _run(steps, radius=20.0) -> ClearMot:
    m = ClearMot(radius)
    for k, (truth_ids, truth_xy, track_ids, track_xy) in enumerate(steps):
        m.add(0.5 * k, truth_ids, truth_xy, track_ids, track_xy)
    return m


def test_one_perfect_track_scores_mota_and_idf1_one():
    # one car, one track 3 m off at each of 5 steps: every step one match at 3 m, nothing else
    s = _run([([0], [A], [7], [A + [3.0, 0.0]])] * 5).summary()
    assert (s.steps, s.truth_instances, s.matches) == (5, 5, 5)
    assert s.mota == 1.0 and s.idf1 == 1.0 and s.motp_m == pytest.approx(3.0)
    assert (s.num_switches, s.false_positives, s.misses, s.mostly_tracked, s.mostly_lost) == (0, 0, 0, 1, 0)
    assert s.gospa_mean_m == pytest.approx(3.0)  # (3²)^(1/2): one pair, none missed or false


def test_a_swap_of_two_tracks_is_two_switches():
    """Tracks 5 and 6 follow cars 0 and 1 for 4 steps, then each other's car for 6 steps.

    At step 4 each car's last track is 100 m away (no longer a candidate), so motmetrics pairs car 0 with 6 and car 1
    with 5: two vehicles matched to another track than their last one, two ID switches. MOTA = 1 − (FN + FP + IDSW)
    / GT = 1 − (0 + 0 + 2) / 20 = 0.9. IDF1 takes the best one-to-one assignment of whole trajectories: 0 ↔ 6 and
    1 ↔ 5 (6 steps each), IDTP = 12, IDFP = IDFN = 20 − 12 = 8, IDF1 = 2·12 / (2·12 + 8 + 8) = 0.6."""
    before = ([0, 1], [A, B], [5, 6], [A + [1.0, 0.0], B + [0.0, 2.0]])
    after = ([0, 1], [A, B], [6, 5], [A + [1.0, 0.0], B + [0.0, 2.0]])
    s = _run([before] * 4 + [after] * 6).summary()
    assert s.num_switches == 2
    assert s.mota == pytest.approx(0.9) and s.idf1 == pytest.approx(0.6)
    assert s.matches == 20 and s.motp_m == pytest.approx(1.5)  # 10 pairs at 1 m, 10 at 2 m
    assert (s.false_positives, s.misses, s.mostly_tracked, s.mostly_lost) == (0, 0, 2, 0)
    assert s.gospa_mean_m == pytest.approx(math.sqrt(1.0 + 4.0))


def test_a_false_track_counts_a_false_positive_at_every_step():
    """Car 0 tracked exactly and a track 50 m away (beyond the 20 m radius) for 5 steps: 5 false positives,
    MOTA = 1 − 5/5 = 0, IDF1 = 2·5 / (2·5 + 5 + 0) = 2/3; GOSPA (c = 20, p = 2) per step = (0 + c²/2)^(1/2)."""
    s = _run([([0], [A], [1, 2], [A, A + [0.0, 50.0]])] * 5).summary()
    assert s.false_positives == 5 and s.misses == 0 and s.num_switches == 0
    assert s.mota == pytest.approx(0.0) and s.idf1 == pytest.approx(2.0 / 3.0) and s.motp_m == pytest.approx(0.0)
    assert s.gospa_mean_m == pytest.approx(math.sqrt(20.0**2 / 2.0))


@pytest.mark.parametrize(("tracked_steps", "mt", "ml"), [(8, 1, 0), (7, 0, 0), (2, 0, 0), (1, 0, 1)],
                         ids=["80%", "70%", "20%", "10%"])
def test_misses_and_the_mostly_tracked_and_mostly_lost_thresholds(tracked_steps, mt, ml):
    # 10 steps of one car, tracked at the first `tracked_steps`: mostly tracked at >= 80 %, mostly lost under 20 %
    steps = [([0], [A], [3], [A])] * tracked_steps + [([0], [A], [], np.zeros((0, 2)))] * (10 - tracked_steps)
    s = _run(steps).summary()
    assert s.misses == 10 - tracked_steps and s.mota == pytest.approx(tracked_steps / 10)
    assert (s.mostly_tracked, s.mostly_lost) == (mt, ml)
    # GOSPA: 0 at a tracked step, (c²/2)^(1/2) at a missed one
    assert s.gospa_mean_m == pytest.approx((10 - tracked_steps) / 10 * math.sqrt(200.0))


def test_a_pair_beyond_the_match_radius_is_a_miss_and_a_false_positive():
    steps = [([0], [A], [4], [A + [25.0, 0.0]])] * 3
    far = _run(steps, radius=20.0).summary()
    assert (far.matches, far.misses, far.false_positives) == (0, 3, 3) and math.isnan(far.motp_m)
    assert far.mota == pytest.approx(1.0 - 6 / 3)
    wide = _run(steps, radius=30.0).summary()
    assert (wide.matches, wide.misses, wide.false_positives) == (3, 0, 0) and wide.motp_m == pytest.approx(25.0)
    assert wide.match_radius_m == 30.0


def test_scoring_as_it_goes_equals_scoring_at_the_end():
    before = ([0, 1], [A, B], [5, 6], [A, B + [0.0, 2.0]])
    after = ([0, 1], [A, B], [6, 5], [A, B])
    steps = [before] * 3 + [after] * 4 + [([0, 1], [A, B], [5], [B])] * 2
    m = ClearMot()
    partial = []
    for k, st in enumerate(steps):
        m.add(0.5 * k, *st)
        if k in (0, 2, 5):
            partial.append(m.summary().steps)
    assert partial == [1, 3, 6]
    assert m.summary() == _run(steps).summary()


def test_no_step_gives_nan_scores_and_zero_counts():
    s = ClearMot().summary()
    assert s.steps == 0 and s.truth_instances == 0 and s.false_positives == 0
    assert math.isnan(s.mota) and math.isnan(s.idf1) and math.isnan(s.gospa_mean_m)
    assert set(s.as_dict()) >= {"mota", "motp_m", "idf1", "num_switches", "mostly_tracked", "mostly_lost",
                                "false_positives", "misses", "gospa_mean_m"}


@pytest.mark.parametrize("radius", [0.0, -1.0, float("nan"), float("inf")])
def test_match_radius_must_be_positive_and_finite(radius):
    with pytest.raises(ValueError, match="match_radius_m"):
        ClearMot(radius)


def test_steps_are_checked():
    m = ClearMot()
    m.add(1.0, [0], [A], [1], [A])
    with pytest.raises(ValueError, match="increase"):
        m.add(1.0, [0], [A], [1], [A])
    with pytest.raises(ValueError, match="unique"):
        m.add(2.0, [0, 0], [A, B], [1], [A])
    with pytest.raises(ValueError, match="track_xy"):
        m.add(2.0, [0], [A], [1, 2], [A])
    with pytest.raises(ValueError, match="truth_xy"):
        m.add(2.0, [0], [[0.0, 0.0, 0.0]], [1], [A])


def _motmetrics_of_everything(steps, radius):
    """The scores motmetrics gives when fed every vehicle and track at every step (the full distance matrices)."""
    import motmetrics as mm
    from scipy.spatial.distance import cdist

    acc = mm.MOTAccumulator(auto_id=False)
    for k, (gt_ids, gt_xy, hyp_ids, hyp_xy) in enumerate(steps):
        d = cdist(gt_xy, hyp_xy) if len(gt_ids) and len(hyp_ids) else np.zeros((len(gt_ids), len(hyp_ids)))
        d[d >= radius] = np.nan
        acc.update(list(gt_ids), list(hyp_ids), d, frameid=k)
    return mm.metrics.create().compute(acc, return_dataframe=False, metrics=[
        "mota", "motp", "idf1", "num_switches", "mostly_tracked", "mostly_lost", "num_false_positives", "num_misses",
        "num_objects", "num_detections"])


@pytest.mark.parametrize("seed", range(6))
def test_feeding_motmetrics_only_the_matchable_gives_its_scores_of_everything(seed):
    """Random crowds (60 cars in 1 km², some leaving and coming back, 25 tracks: noisy followers that jump to
    neighbours, lose their car or are false): every score equals motmetrics' on the full feed (MOTP to rounding: its
    sum runs over the same pairs)."""
    rng = np.random.default_rng(seed)
    n_cars, n_tracks, radius = 60, 25, 20.0
    xy = rng.uniform(0.0, 1000.0, (n_cars, 2))
    v = rng.normal(0.0, 8.0, (n_cars, 2))
    follow = rng.integers(0, n_cars, n_tracks)
    steps = []
    for _ in range(40):
        xy += v
        here = rng.random(n_cars) > 0.1
        jump = rng.random(n_tracks) < 0.05
        follow[jump] = rng.integers(0, n_cars, jump.sum())
        track_xy = xy[follow] + rng.normal(0.0, 6.0, (n_tracks, 2))
        false = rng.random(n_tracks) < 0.15
        track_xy[false] = rng.uniform(0.0, 1000.0, (false.sum(), 2))
        live = rng.random(n_tracks) > 0.1
        gt_ids = np.flatnonzero(here)
        steps.append((gt_ids, xy[gt_ids].copy(), np.flatnonzero(live) + 1000, track_xy[live]))
    ref = _motmetrics_of_everything(steps, radius)
    assert ref["num_switches"] > 0 and ref["mostly_tracked"] > 0 and ref["mostly_lost"] > 0
    m = _run(steps, radius)
    s = m.summary()
    assert m._unfed_truth > 0 and m._unfed_tracks > 0  # the scores rest on the completed counts
    assert (s.num_switches, s.mostly_tracked, s.mostly_lost, s.false_positives, s.misses, s.truth_instances,
            s.matches) == (ref["num_switches"], ref["mostly_tracked"], ref["mostly_lost"], ref["num_false_positives"],
                           ref["num_misses"], ref["num_objects"], ref["num_detections"])
    assert s.mota == ref["mota"] and s.idf1 == ref["idf1"]
    assert s.motp_m == pytest.approx(ref["motp"], rel=1e-12)
