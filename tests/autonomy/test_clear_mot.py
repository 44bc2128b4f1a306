"""The CLEAR-MOT matcher (autonomy.metrics.clear_mot) against py-motmetrics 1.4, the reference it follows: the same
steps give the same counts, the same MOTP to the bit and the same IDTP."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.metrics.clear_mot import ClearMotMatcher, identity_true_positives


def _crowd(seed: int, n_cars: int, n_tracks: int, steps: int, radius: float, area: float):
    """Random steps of (vehicle ids, track ids, distances with NaN beyond ``radius``): cars moving about, tracks
    following noisy, jumping to other cars, false, and coming and going; ids shuffled at each step."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0.0, area, (n_cars, 2))
    v = rng.normal(0.0, 5.0, (n_cars, 2))
    follow = rng.integers(0, n_cars, n_tracks)
    out = []
    for _ in range(steps):
        xy += v
        jump = rng.random(n_tracks) < 0.08
        follow[jump] = rng.integers(0, n_cars, jump.sum())
        track_xy = xy[follow] + rng.normal(0.0, 0.4 * radius, (n_tracks, 2))
        false = rng.random(n_tracks) < 0.1
        track_xy[false] = rng.uniform(0.0, area, (false.sum(), 2))
        cars = rng.permutation(np.flatnonzero(rng.random(n_cars) > 0.15))
        tracks = rng.permutation(np.flatnonzero(rng.random(n_tracks) > 0.15))
        d = np.linalg.norm(xy[cars][:, None] - track_xy[tracks][None], axis=-1)
        d[d > radius] = np.nan
        out.append((cars.astype(np.int64), tracks.astype(np.int64) + 500, d))
    return out


def _pairs(d):
    i, j = np.nonzero(np.isfinite(d))
    return i, j, d[i, j]


def _reference(steps):
    import motmetrics as mm

    acc = mm.MOTAccumulator(auto_id=False)
    for k, (oids, hids, d) in enumerate(steps):
        acc.update(oids.tolist(), hids.tolist(), d, frameid=k)
    s = mm.metrics.create().compute(acc, return_dataframe=False, metrics=[
        "num_matches", "num_switches", "num_misses", "num_false_positives", "motp", "idtp", "num_detections"])
    ev = acc.mot_events
    tracked = ev[ev.Type.isin(["MATCH", "SWITCH"])]["OId"].value_counts()
    return s, {int(k): int(v) for k, v in tracked.items()}


@pytest.mark.parametrize(("seed", "n_cars", "n_tracks", "area"),
                         [(0, 30, 25, 400.0), (1, 60, 50, 400.0), (2, 12, 30, 150.0), (3, 40, 10, 300.0),
                          (4, 80, 80, 600.0)],
                         ids=["balanced", "dense", "more-tracks", "few-tracks", "large"])
def test_the_matcher_counts_and_sums_as_motmetrics_does(seed, n_cars, n_tracks, area):
    steps = _crowd(seed, n_cars, n_tracks, 60, 20.0, area)
    ref, ref_tracked = _reference(steps)
    m = ClearMotMatcher()
    for k, (oids, hids, d) in enumerate(steps):
        m.update(oids, hids, *_pairs(d))
        if k in (0, 19, 40):  # asked as it goes (a run asks at every flush): the counts fold in, nothing changes
            m.identity_true_positives(), m.distance_sum()
    assert ref["num_switches"] > 0 and ref["num_misses"] > 0 and ref["num_false_positives"] > 0
    assert (m.matches, m.switches, m.misses, m.false_positives, m.detections) == (
        ref["num_matches"], ref["num_switches"], ref["num_misses"], ref["num_false_positives"],
        ref["num_detections"])
    assert m.tracked == ref_tracked
    assert m.distance_sum() / m.detections == ref["motp"]  # the same sum in the same order: equal bits
    assert m.identity_true_positives() == ref["idtp"]


def test_a_vehicle_keeps_its_track_unless_another_vehicle_took_it_first_or_it_is_beyond_the_radius():
    """Vehicles 1 and 2 have each been matched to track 9 (2 while 1 was away); when both are back beside it, 1 (given
    first) keeps it and 2 gets track 8 by the assignment: a switch for 2. Then 9 moves beyond 1's radius: 1 takes 8,
    which 2 held: a switch for 1."""
    nan = np.nan
    m = ClearMotMatcher()
    m.update(np.array([1]), np.array([9]), *_pairs(np.array([[1.0]])))  # 1 - 9
    m.update(np.array([2]), np.array([9]), *_pairs(np.array([[2.0]])))  # 2 - 9 (1 away)
    assert (m.matches, m.switches) == (2, 0)
    m.update(np.array([1, 2]), np.array([8, 9]), *_pairs(np.array([[3.0, 1.5], [4.0, 0.5]])))  # 1 keeps 9; 2 -> 8
    assert (m.matches, m.switches) == (3, 1)
    m.update(np.array([1, 2]), np.array([8, 9]), *_pairs(np.array([[3.0, nan], [nan, nan]])))  # 1 -> 8; 2 missed
    assert (m.matches, m.switches, m.misses, m.false_positives) == (3, 2, 1, 1)
    assert m.tracked == {1: 3, 2: 2}
    assert m.distance_sum() == pytest.approx(1.0 + 2.0 + 1.5 + 4.0 + 3.0)


def test_identity_true_positives_is_the_best_one_to_one_total():
    """Vehicle 1 met track 10 on 5 steps and track 11 on 4; vehicle 2 met track 10 on 4 steps only: the best
    assignment is 1-11, 2-10 (8), not the greedy 1-10 (5). A lone pair (3, 12) adds its 2 steps."""
    pairs = [(1, 10)] * 5 + [(1, 11)] * 4 + [(2, 10)] * 4 + [(3, 12)] * 2
    assert identity_true_positives(np.array(pairs)) == 10
    assert identity_true_positives(np.zeros((0, 2), dtype=np.int64)) == 0
