"""A teammate's picture is predicted once for all its receivers, and the team's association through k-d trees and
per-component solves makes the pairs of the whole assignment (autonomy/fusion/track_sets.py)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from autonomy.fusion.track_association import TeamTrackFusion, associate_positions
from autonomy.fusion.track_sets import TrackSet, associate_sets, track_set
from interfaces.state import TargetEstimate, TrackPicture, TrackReport

CHI2_2_999 = 13.815510557964274


def _whole_assignment(pa, Pa, pb, Pb, threshold):
    """The assignment over every pair at once, ``10·threshold + 1`` outside the gate (the reference)."""
    d = pa[:, None, :] - pb[None, :, :]
    S = Pa[:, None] + Pb[None, :]
    maha = np.einsum("nmi,nmij,nmj->nm", d, np.linalg.inv(S), d)
    cost = np.where(maha <= threshold, maha, threshold * 10.0 + 1.0)
    r, c = linear_sum_assignment(cost)
    return sorted((int(i), int(j)) for i, j in zip(r, c, strict=True) if cost[i, j] <= threshold)


def _set(rng, xy, var) -> TrackSet:
    reps = []
    for k, (x, y) in enumerate(xy):
        a, b = rng.uniform(0.3, 1.0, 2) * var
        P = np.diag([a, b, 4.0, 4.0])
        P[0, 1] = P[1, 0] = rng.uniform(-0.5, 0.5) * np.sqrt(a * b)
        est = TargetEstimate(t=9.7, p_W=np.array([x, y]), v_W=rng.normal(0, 5, 2), P=P)
        reps.append(TrackReport(track_id=k + 1, estimate=est, target_probability=0.0))
    return TrackSet.of(reps, 10.0, 1.0)


def test_the_tree_gated_association_makes_the_pairs_of_the_whole_assignment():
    rng = np.random.default_rng(1)
    compared = multi = 0
    for _ in range(1200):
        n, m = rng.integers(1, 80, 2)
        extent, var = rng.choice([30.0, 200.0, 1000.0]), rng.choice([4.0, 25.0, 400.0])  # crowded to sparse
        cars = rng.uniform(-extent, extent, (max(n, m) + 5, 2))
        a = _set(rng, cars[rng.choice(len(cars), n, replace=False)] + rng.normal(0, 3, (n, 2)), var)
        b = _set(rng, cars[rng.choice(len(cars), m, replace=False)] + rng.normal(0, 3, (m, 2)), var)
        want = _whole_assignment(a.xy, a.P, b.xy, b.P, CHI2_2_999)
        assert associate_sets(a, b, CHI2_2_999) == want
        assert sorted(associate_positions(a.xy, a.P, b.xy, b.P, CHI2_2_999)) == want
        compared += len(want)
        d = a.xy[:, None] - b.xy[None]
        gated = np.einsum("nmi,nmij,nmj->nm", d, np.linalg.inv(a.P[:, None] + b.P[None]), d) <= CHI2_2_999
        multi += bool((gated.sum(axis=1) > 1).any())
    assert compared > 10_000 and multi > 300  # many pairs, and many scenes where a component held a choice


def _picture(rng, n=30):
    reps = []
    for k in range(n):
        P = np.diag([25.0, 25.0, 4.0, 4.0])
        est = TargetEstimate(t=9.8, p_W=rng.uniform(-300, 300, 2), v_W=rng.normal(0, 5, 2), P=P)
        reps.append(TrackReport(track_id=k + 1, estimate=est, target_probability=0.9 if k == 3 else 0.0))
    return reps


def test_a_picture_is_predicted_once_for_every_receiver_at_one_time():
    rng = np.random.default_rng(5)
    reps = _picture(rng)
    pic = TrackPicture(t=9.8, tracks=tuple(reps))
    first = track_set(pic, 10.0, 1.0)
    assert track_set(pic, 10.0, 1.0) is first  # another receiver at the same tick
    assert track_set(pic, 10.0, 2.0) is not first  # another q
    twin = TrackPicture(t=9.8, tracks=tuple(reps))
    assert track_set(twin, 10.0, 1.0) is not first  # another picture
    fresh = TrackSet.of(reps, 10.0, 1.0)
    np.testing.assert_array_equal(first.xy, fresh.xy)
    np.testing.assert_array_equal(first.P, fresh.P)
    later = track_set(pic, 10.5, 1.0)  # the next fusion time lets the last go
    assert later is not first and track_set(pic, 10.5, 1.0) is later


def test_receivers_of_one_picture_choose_and_fuse_the_same():
    rng = np.random.default_rng(7)
    mate = _picture(rng)
    own = [TrackReport(track_id=100 + r.track_id, estimate=TargetEstimate(
        t=9.9, p_W=r.estimate.p_W + rng.normal(0, 2, 2), v_W=r.estimate.v_W, P=r.estimate.P),
        target_probability=0.8 if r.track_id == 4 else 0.0) for r in mate]
    pic = TrackPicture(t=9.8, tracks=tuple(mate), target_track_id=4)
    outs = [TeamTrackFusion("convex", max_age_s=2.0, q=1.0).fuse(10.0, None, own, 104, [pic]) for _ in range(3)]
    assert all(o.own_track_id == 104 and o.fused_with == 1 for o in outs)
    assert outs[0].probability == outs[2].probability == (0.8 + 0.9) / 2
    np.testing.assert_array_equal(outs[0].estimate.p_W, outs[2].estimate.p_W)
