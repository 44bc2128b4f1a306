"""A teammate's picture is predicted once for all its receivers, the team's association through k-d trees and
per-component solves makes the pairs of the whole assignment, and the tracks' target probabilities take part in it
(autonomy/fusion/track_sets.py)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from autonomy.fusion.track_association import TeamTrackFusion, associate_positions
from autonomy.fusion.track_sets import ID_COST_SPAN, TrackSet, associate_sets, identity_cost, track_set
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


def _set(rng, xy, var, q=None) -> TrackSet:
    reps = []
    for k, (x, y) in enumerate(xy):
        a, b = rng.uniform(0.3, 1.0, 2) * var
        P = np.diag([a, b, 4.0, 4.0])
        P[0, 1] = P[1, 0] = rng.uniform(-0.5, 0.5) * np.sqrt(a * b)
        est = TargetEstimate(t=9.7, p_W=np.array([x, y]), v_W=rng.normal(0, 5, 2), P=P)
        reps.append(TrackReport(track_id=k + 1, estimate=est, target_probability=0.0 if q is None else q[k]))
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


def test_identity_cost_is_the_likelihood_ratio_of_one_car_against_two():
    # π = 1/4 among 3 tracks: κ = 0.9·0.8·4 + 0.1·0.2·4/3, shifted by the largest κ, 4
    np.testing.assert_allclose(identity_cost(np.array(0.9), np.array(0.8), 3),
                               2 * np.log(4 / (0.72 * 4 + 0.02 * 4 / 3)), rtol=1e-12)
    both, neither, split = identity_cost(np.array([0.99, 0.0, 0.99]), np.array([0.99, 0.0, 0.0]), 20)
    assert 0 <= both < 0.1 < neither < split <= ID_COST_SPAN  # two target tracks are one car before two others
    assert identity_cost(np.array(1.0), np.array(0.0), 1) == identity_cost(np.array(0.0), np.array(1.0), 1)
    # π = 1/2: κ = 4 f (1 − f) at the floor f, against the largest κ, 2
    np.testing.assert_allclose(identity_cost(np.array(1.0), np.array(0.0), 1), ID_COST_SPAN - 2 * np.log(2),
                               rtol=1e-9)


def test_the_association_with_target_probabilities_is_the_whole_assignment_too():
    rng = np.random.default_rng(11)
    for _ in range(400):
        n, m = rng.integers(1, 30, 2)
        cars = rng.uniform(-60.0, 60.0, (max(n, m) + 3, 2))
        qa, qb = (np.where(rng.random(k) < 0.2, rng.random(k), 0.0) for k in (n, m))
        a = _set(rng, cars[rng.choice(len(cars), n, replace=False)] + rng.normal(0, 3, (n, 2)), 100.0, qa)
        b = _set(rng, cars[rng.choice(len(cars), m, replace=False)] + rng.normal(0, 3, (m, 2)), 100.0, qb)
        assert associate_sets(a, b, CHI2_2_999) == sorted(associate_positions(a.xy, a.P, b.xy, b.P, CHI2_2_999,
                                                                              a.p, b.p))


def _report(track_id, xy, sd, q):
    P = np.diag([sd**2, sd**2, 4.0, 4.0])
    return TrackReport(track_id=track_id, estimate=TargetEstimate(t=10.0, p_W=np.array(xy, dtype=float),
                                                                  v_W=np.zeros(2), P=P), target_probability=q)


def test_two_target_tracks_pair_where_the_positions_alone_would_cross_them():
    """One UAV's radar track of the target stayed where the car stood (σ 14 m) and a new track of its took the car
    as it drove off (σ 11 m, not yet the target); the teammate's camera holds the target (σ 0.7 m) and another car
    (σ 2 m). By position alone the least-cost pairs cross (each within the gate); with the target probabilities the
    target tracks pair, and the team's target is the car the camera holds."""
    own = [_report(19, (0.0, 0.0), 14.0, 0.998), _report(22, (-5.0, 27.0), 11.0, 0.0)]
    mate = [_report(18, (-3.0, 8.0), 0.7, 0.997), _report(4, (-26.0, -6.0), 2.0, 0.0)]
    xy = [np.array([r.estimate.p_W for r in rs]) for rs in (own, mate)]
    P = [np.array([r.estimate.P[:2, :2] for r in rs]) for rs in (own, mate)]
    assert sorted(associate_positions(xy[0], P[0], xy[1], P[1], CHI2_2_999)) == [(0, 1), (1, 0)]
    a, b = TrackSet.of(own, 10.0, 1.0), TrackSet.of(mate, 10.0, 1.0)
    assert associate_sets(a, b, CHI2_2_999) == [(0, 0), (1, 1)]
    team = TeamTrackFusion("convex", max_age_s=2.0, q=1.0).fuse(10.0, None, own, 19, [TrackPicture(
        t=10.0, tracks=tuple(mate), target_track_id=18)])
    assert team.own_track_id == 19 and team.fused_with == 1
    assert np.hypot(*(team.estimate.p_W - [-3.0, 8.0])) < 0.5


def test_tracks_of_very_different_sizes_are_searched_each_within_its_own_reach():
    """A few new or coasting tracks with covariances of hundreds of metres among converged ones of a few metres (what
    a teammate's picture of a city holds): each pair is searched within the reach of the larger of its two tracks, and
    the pairs are still those of the whole assignment, the large tracks' distant pairs among them."""
    rng = np.random.default_rng(21)
    compared = wide = 0
    for _ in range(600):
        n, m = rng.integers(1, 60, 2)
        cars = rng.uniform(-400.0, 400.0, (max(n, m) + 5, 2))
        a = _set(rng, cars[rng.choice(len(cars), n, replace=False)] + rng.normal(0, 3, (n, 2)), 9.0)
        b = _set(rng, cars[rng.choice(len(cars), m, replace=False)] + rng.normal(0, 3, (m, 2)), 9.0)
        for s in (a, b):  # a tenth of each set made wide, long along a random axis
            for k in np.flatnonzero(rng.random(len(s.xy)) < 0.1):
                u = rng.normal(size=2)
                u /= np.linalg.norm(u)
                s.P[k] = rng.uniform(200.0, 4000.0) * np.outer(u, u) + rng.uniform(1.0, 9.0) * np.eye(2)
            P = s.P
            s.lam = 0.5 * (P[:, 0, 0] + P[:, 1, 1]) + np.sqrt(0.25 * (P[:, 0, 0] - P[:, 1, 1]) ** 2 + P[:, 0, 1] ** 2)
        want = _whole_assignment(a.xy, a.P, b.xy, b.P, CHI2_2_999)
        assert associate_sets(a, b, CHI2_2_999) == want
        compared += len(want)
        d = np.hypot(*(a.xy[:, None] - b.xy[None]).T).T
        wide += sum(d[i, j] ** 2 > CHI2_2_999 * max(a.lam[i], b.lam[j]) for i, j in want)
    assert compared > 5_000 and wide > 20  # pairs a search within one track's own reach alone would have missed
