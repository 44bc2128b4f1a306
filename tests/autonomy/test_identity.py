"""Target identity: the belief over which track is the target follows Bayes' rule, computed here by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.estimation.tracking.identity import (IdentityConfig, TargetIdentity, accumulate_readings,
                                                   background_frequencies, track_evidence)
from autonomy.sensing.measurement import ClassMeasurement

# three colours; the target is colour 2; the background is 60 % colour 0, 30 % colour 1, 10 % colour 2
BG = {"colour": np.array([0.6, 0.3, 0.1])}
C = np.array([[0.8, 0.1, 0.1],
              [0.1, 0.8, 0.1],
              [0.05, 0.15, 0.8]])


def _config(**kw) -> IdentityConfig:
    return IdentityConfig(target_classes={"colour": 2}, background=BG, **kw)


def test_class_reading_ratio_is_target_over_background_likelihood():
    reading = ClassMeasurement(attribute="colour", observed=2, confusion=C)
    l_t = C[2, 2]
    l_b = 0.6 * C[0, 2] + 0.3 * C[1, 2] + 0.1 * C[2, 2]
    ell = {"colour": np.log(reading.likelihood())}
    assert track_evidence(ell, _config()) == pytest.approx(math.log(l_t / l_b))
    # an attribute the target has no class for carries no evidence
    assert track_evidence({"length": np.log([0.9, 0.1])}, _config()) == 0.0


def test_belief_after_readings_matches_bayes_by_hand():
    ident = TargetIdentity(_config(background_density=1e-3))
    # no cue: a new track is the target with likelihood ρ, as a background car is, so each birth gives the new
    # hypothesis the weight of H_0: after two, H_1, H_2 and H_0 are equally likely
    ident.confirmed(1, 0.0, np.zeros(2), np.eye(2), evidence=0.0)
    assert ident.probability(1) == pytest.approx(0.5)
    ident.confirmed(2, 0.0, np.ones(2) * 50, np.eye(2), evidence=0.0)
    w1 = w2 = w0 = 1.0 / 3.0
    assert ident.probability(1) == pytest.approx(w1)
    assert ident.probability(2) == pytest.approx(w2)
    assert ident.w_none == pytest.approx(w0)
    # track 2 reads the target's colour twice, track 1 reads colour 0 once; a car's class is drawn once, so the
    # evidence of n readings is log(Π C[c_T, o_i] / Σ_c π(c) Π C[c, o_i])
    ell2 = 2 * np.log(C[:, 2])
    ell1 = np.log(C[:, 0])
    ident.read(2, track_evidence({"colour": ell2}, ident.config))
    ident.read(1, track_evidence({"colour": ell1}, ident.config))
    r2 = C[2, 2] ** 2 / float(BG["colour"] @ C[:, 2] ** 2)
    r1 = C[2, 0] / float(BG["colour"] @ C[:, 0])
    unnorm = {1: w1 * r1, 2: w2 * r2, 0: w0}
    total = sum(unnorm.values())
    assert ident.probability(1) == pytest.approx(unnorm[1] / total, rel=1e-12)
    assert ident.probability(2) == pytest.approx(unnorm[2] / total, rel=1e-12)
    assert ident.w_none == pytest.approx(unnorm[0] / total, rel=1e-12)
    assert ident.target() == 2


def test_a_look_alike_seen_often_gains_at_most_one_over_its_class_frequency():
    """However many readings of the target's class a background car gets, its evidence tends to log(1 / π(c_T))
    (here perfect readings: exactly that)."""
    cfg = _config()
    perfect = np.eye(3)
    for n in (1, 10, 100):
        ell = n * np.log(np.maximum(perfect[:, 2], 1e-300))
        assert track_evidence({"colour": ell}, cfg) == pytest.approx(math.log(1 / 0.1))
    noisy = [track_evidence({"colour": n * np.log(C[:, 2])}, cfg) for n in (1, 5, 50)]
    assert noisy[0] < noisy[1] < noisy[2] <= math.log(1 / 0.1) + 1e-12


def test_cue_makes_the_track_at_the_cued_place_the_target():
    rho = 1e-5
    ident = TargetIdentity(_config(background_density=rho, search_speed=5.0))
    ident.cue(0.0, np.array([100.0, 0.0]), sigma_m=20.0)
    P = np.eye(2) * 25.0
    ident.confirmed(7, 2.0, np.array([110.0, 5.0]), P, evidence=0.0)   # near the cue
    S = np.eye(2) * (400.0 + (5.0 * 2.0) ** 2) + P
    d = np.array([10.0, 5.0])
    dens = math.exp(-0.5 * d @ np.linalg.solve(S, d)) / (2 * math.pi * math.sqrt(np.linalg.det(S)))
    share = (dens / rho) / (1 + dens / rho)
    assert ident.probability(7) == pytest.approx(share, rel=1e-12)
    assert ident.target() == 7
    ident.confirmed(8, 2.0, np.array([600.0, 0.0]), P, evidence=0.0)   # far away: almost certainly background
    assert ident.probability(8) < 1e-6
    assert ident.target() == 7


def test_a_car_showing_up_nearer_the_cue_takes_the_belief_from_an_earlier_one():
    """Bayes over births: under H_1 the second track is background (ρ), under H_0 it is the target (p_T(x_2))."""
    rho = 1e-5
    ident = TargetIdentity(_config(background_density=rho, search_speed=1e-6))
    ident.cue(0.0, np.zeros(2), sigma_m=20.0)
    P = np.eye(2) * 1e-6
    S = np.eye(2) * 400.0
    dens = lambda d: math.exp(-0.5 * d * d / 400.0) / (2 * math.pi * math.sqrt(np.linalg.det(S)))  # noqa: E731
    ident.confirmed(1, 0.0, np.array([50.0, 0.0]), P, evidence=0.0)  # first, but 50 m from the cue
    w1, w0 = dens(50.0) / rho, 1.0
    assert ident.probability(1) == pytest.approx(w1 / (w1 + w0), rel=1e-6)
    ident.confirmed(2, 0.0, np.array([5.0, 0.0]), P, evidence=0.0)   # later, 5 m from it
    w2 = w0 * dens(5.0) / rho
    assert ident.probability(2) == pytest.approx(w2 / (w1 + w2 + w0), rel=1e-6)
    assert ident.target() == 2


def test_lost_target_moves_the_search_centre_and_is_reacquired_nearby():
    ident = TargetIdentity(_config(background_density=1e-5, search_speed=5.0))
    ident.cue(0.0, np.zeros(2), sigma_m=10.0)
    ident.confirmed(1, 0.0, np.zeros(2), np.eye(2), evidence=0.0)
    assert ident.target() == 1
    ident.deleted(1, 10.0, np.array([100.0, 0.0]), np.array([10.0, 0.0]), np.eye(2) * 4.0)
    assert ident.target() is None and ident.w_none == pytest.approx(1.0)
    mean, S = ident.search_estimate(12.0)
    np.testing.assert_allclose(mean, [120.0, 0.0])
    np.testing.assert_allclose(S, np.eye(2) * (4.0 + 100.0))
    ident.confirmed(2, 12.0, np.array([118.0, 3.0]), np.eye(2), evidence=0.0)
    ident.confirmed(3, 12.0, np.array([-300.0, 0.0]), np.eye(2), evidence=0.0)
    assert ident.target() == 2


def test_teammates_evidence_is_applied_without_being_stored():
    ident = TargetIdentity(_config(background_density=1e-3))
    ident.confirmed(1, 0.0, np.zeros(2), np.eye(2), evidence=0.0)
    ident.confirmed(2, 0.0, np.ones(2), np.eye(2), evidence=0.0)
    before = dict(ident.weights)
    p = ident.teammates({2: math.log(9.0)})
    total = before[1] + 9.0 * before[2] + ident.w_none
    assert p[2] == pytest.approx(9.0 * before[2] / total)
    assert ident.weights == before


def test_background_frequencies_count_with_one_pseudo_count():
    f = background_frequencies([{"colour": 0}, {"colour": 0}, {"colour": 1}], {"colour": 3})
    np.testing.assert_allclose(f["colour"], np.array([3, 2, 1]) / 6)


def test_bad_config_is_refused():
    with pytest.raises(ValueError, match="background_density"):
        _config(background_density=0.0)
    with pytest.raises(ValueError, match="sum"):
        IdentityConfig(target_classes={}, background={"colour": np.array([0.5, 0.4])})


def test_discounted_readings_equal_the_forward_recursion_by_enumeration():
    """With swap probability ε the accumulated log-likelihood is log P(o₁…o_t | the current car is of class c) of the
    Markov chain c₁ → … → c_t (stay with 1 − ε, else a car drawn from π), computed here over every class sequence."""
    import itertools

    pi = np.array([0.5, 0.3, 0.2])
    C = np.array([[0.8, 0.1, 0.1], [0.15, 0.7, 0.15], [0.1, 0.2, 0.7]])
    eps = 0.1
    T = (1 - eps) * np.eye(3) + eps * np.outer(np.ones(3), pi)  # T[a, b] = P(c_{k+1} = b | c_k = a)
    obs = [0, 0, 2, 1]
    ell = None
    for o in obs:
        ell = accumulate_readings(ell, np.log(C[:, o]), pi, eps)
    for c in range(3):
        total = 0.0
        for seq in itertools.product(range(3), repeat=len(obs) - 1):
            path = (*seq, c)
            p = pi[path[0]] * math.prod(T[a, b] for a, b in itertools.pairwise(path))
            total += p * math.prod(C[k, o] for k, o in zip(path, obs, strict=True))
        assert ell[c] == pytest.approx(math.log(total / pi[c]), rel=1e-12)
    plain = None
    for o in obs:
        plain = accumulate_readings(plain, np.log(C[:, o]), pi, 0.0)
    np.testing.assert_allclose(plain, np.log(C[:, obs]).sum(axis=1), rtol=1e-12)


@pytest.mark.parametrize("eps,most", [(0.02, 3), (0.0, 45)])
def test_a_track_that_swapped_onto_another_colour_loses_its_evidence(eps, most):
    """40 readings of the target's colour, then the track carries a car of another colour: with ε = 0.02 its
    evidence turns negative within 3 readings; without discounting it takes about as many readings as it had."""
    cfg = IdentityConfig(target_classes={"colour": 1}, background={"colour": np.array([0.7, 0.1, 0.2])},
                         swap_probability=eps)
    C = np.array([[0.9, 0.05, 0.05], [0.05, 0.9, 0.05], [0.05, 0.05, 0.9]])
    ell = None
    for _ in range(40):
        ell = accumulate_readings(ell, np.log(C[:, 1]), cfg.background["colour"], eps)
    assert track_evidence({"colour": ell}, cfg) > 1.0
    turned = None
    for k in range(1, 60):
        ell = accumulate_readings(ell, np.log(C[:, 2]), cfg.background["colour"], eps)
        if track_evidence({"colour": ell}, cfg) < 0:
            turned = k
            break
    assert turned is not None and turned <= most
    if eps == 0.0:
        assert turned >= 35


def test_a_target_track_whose_readings_turn_moves_the_search_centre_to_it():
    """The target's track reads another car's class (it swapped): once it is less likely the target than "in no
    track", the target is searched for from where that track is, not from the old cue."""
    ident = TargetIdentity(_config(background_density=1e-5, search_speed=5.0))
    ident.cue(0.0, np.zeros(2), sigma_m=10.0)
    ident.confirmed(1, 0.0, np.zeros(2), np.eye(2), evidence=0.0)
    where = (20.0, np.array([150.0, 40.0]), np.array([0.0, 0.0]), np.eye(2) * 9.0)
    ident.read(1, 1.0, where=lambda: where)
    np.testing.assert_allclose(ident.search_estimate(20.0)[0], [0.0, 0.0])  # still likelier: the cue stays
    ident.read(1, -8.0, where=lambda: where)
    assert ident.probability(1) < ident.w_none
    mean, S = ident.search_estimate(20.0)
    np.testing.assert_allclose(mean, [150.0, 40.0])
    np.testing.assert_allclose(S, np.eye(2) * 9.0)


def test_scans_that_start_nothing_where_the_target_is_searched_make_no_track_less_likely():
    """Each position-fixing scan with no unassigned fix in the search region's 99 % ellipse scales the odds of
    "in no track" against every track by 1 − q exactly; an unassigned fix inside the ellipse (perhaps the target's)
    leaves them."""
    q = 0.3
    ident = TargetIdentity(_config(background_density=1e-4, search_detection_probability=q, swap_probability=0.0))
    ident.cue(0.0, np.zeros(2), sigma_m=10.0)
    ident.confirmed(1, 0.0, np.array([25.0, 0.0]), np.eye(2), evidence=0.0)
    ident.confirmed(2, 0.0, np.array([0.0, 20.0]), np.eye(2), evidence=1.0)
    odds = ident.w_none / ident.probability(1)
    ratio = ident.probability(2) / ident.probability(1)
    ident.scanned(0.5, [np.array([500.0, 500.0])])  # far from the cue
    assert ident.w_none / ident.probability(1) == pytest.approx(odds * (1 - q), rel=1e-12)
    assert ident.probability(2) / ident.probability(1) == pytest.approx(ratio, rel=1e-12)
    before = ident.w_none
    ident.scanned(1.0, [np.array([500.0, 500.0]), np.array([12.0, -8.0])])  # a new fix near the cue
    assert ident.w_none == pytest.approx(before, rel=1e-12)
    for k in range(30):
        ident.scanned(1.5 + 0.5 * k, [])
    assert ident.w_none < 1e-3 and ident.target() == 2
    off = TargetIdentity(_config(background_density=1e-4, swap_probability=0.0))
    off.confirmed(1, 0.0, np.array([200.0, 0.0]), np.eye(2), evidence=0.0)
    w0 = off.w_none
    off.scanned(0.5, [])
    assert off.w_none == w0


def test_two_tracks_a_scan_could_not_tell_apart_share_their_continuity_but_keep_their_evidence():
    """Track 1 inherited the belief; track 2, born later, reads the target's class. While the two are unresolved
    each scan moves their continuity parts c_k = w_k e^{-E_k} towards each other by δ: after n scans the sum is
    kept and the difference is (1 − 2δ)^n times the first, "in no track" keeping c_0, while p_k ∝ c_k e^{E_k}; so
    track 2 takes the belief. Scans that resolve them change nothing."""
    delta = 0.05
    ident = TargetIdentity(_config(background_density=1e-4, swap_probability=delta))
    ident.cue(0.0, np.zeros(2), sigma_m=10.0)
    ident.confirmed(1, 0.0, np.zeros(2), np.eye(2), evidence=0.0)
    ident.confirmed(2, 1.0, np.array([400.0, 0.0]), np.eye(2), evidence=0.0)
    assert ident.probability(2) < 1e-6
    ident.read(1, -2.0)
    ident.read(2, 2.0)
    before = (ident.probability(1), ident.probability(2), ident.w_none)
    ident.scanned(1.5, [])  # resolved: nothing changes
    assert (ident.probability(1), ident.probability(2), ident.w_none) == pytest.approx(before, rel=1e-12)
    E = {1: -2.0, 2: 2.0}
    c0 = {k: ident.probability(k) * math.exp(-E[k]) for k in (1, 2)} | {0: ident.w_none}
    n = 30
    for k in range(n):
        ident.scanned(2.0 + 0.5 * k, [], unresolved=[(1, 2)])
    mean, diff = (c0[1] + c0[2]) / 2, (c0[1] - c0[2]) / 2 * (1 - 2 * delta) ** n
    c = {0: c0[0], 1: mean + diff, 2: mean - diff}
    z = c[0] + c[1] * math.exp(E[1]) + c[2] * math.exp(E[2])
    assert ident.probability(2) == pytest.approx(c[2] * math.exp(E[2]) / z, rel=1e-9)
    assert ident.probability(1) == pytest.approx(c[1] * math.exp(E[1]) / z, rel=1e-9)
    assert ident.target() == 2


def test_unresolved_pairs_mix_at_once_whatever_their_order():
    """Three tracks in a chain of unresolved pairs (1–2, 2–3): the result does not depend on the pairs' order, and
    equals c_i + δ Σ_j (c_j − c_i) from the scan's parts."""
    results = []
    for order in ([(1, 2), (2, 3)], [(2, 3), (1, 2)]):
        ident = TargetIdentity(_config(background_density=1e-4, swap_probability=0.1))
        ident.cue(0.0, np.zeros(2), sigma_m=10.0)
        for k, x in ((1, 0.0), (2, 5.0), (3, 30.0)):
            ident.confirmed(k, 0.0, np.array([x, 0.0]), np.eye(2), evidence=0.0)
        c = {k: ident.probability(k) for k in (1, 2, 3)}
        ident.scanned(1.0, [], unresolved=order)
        results.append({k: ident.probability(k) for k in (1, 2, 3)})
    assert results[0] == pytest.approx(results[1], rel=1e-12)
    expected = {1: c[1] + 0.1 * (c[2] - c[1]), 2: c[2] + 0.1 * (c[1] + c[3] - 2 * c[2]), 3: c[3] + 0.1 * (c[2] - c[3])}
    for k in (1, 2, 3):  # total continuity kept, so the probabilities are the parts themselves
        assert results[0][k] == pytest.approx(expected[k], rel=1e-9)


def test_equally_probable_tracks_give_the_smallest_id_and_the_belief_says_what_it_holds():
    ident = TargetIdentity(_config(background_density=1e-3, min_probability=0.1))
    for k in (7, 3, 5):  # no cue: each new track takes H_0's weight, so all four hypotheses end at 1/4
        ident.confirmed(k, 0.0, np.zeros(2), np.eye(2), evidence=0.0)
    ident.deleted(7, 1.0, np.zeros(2), np.zeros(2), np.eye(2))
    assert ident.held == 2 and ident.holds(3) and ident.holds(5) and not ident.holds(7)
    assert ident.probability(3) == ident.probability(5) and ident.target() == 3
    assert list(ident.weights) == [3, 5]  # in the order the tracks were taken
    snapshot = ident.weights
    snapshot[3] = 1.0
    assert ident.probability(3) != 1.0  # a copy
    assert ident.probability(7) == 0.0
    assert sum(ident.weights.values()) + ident.w_none == pytest.approx(1.0, abs=1e-15)


def test_a_scan_s_reads_at_once_are_the_reads_one_by_one_to_the_bit():
    """read_many (one compiled loop) does the floating-point operations of reading each track in turn and
    renormalising after each (written out here with numpy, as the belief did): the same weights to the bit, and the
    search centre at the last track whose readings turned."""
    rng = np.random.default_rng(3)
    ident = TargetIdentity(_config(background_density=1e-5))
    ident.cue(0.0, np.zeros(2), sigma_m=30.0)
    for k in range(300):
        ident.confirmed(k + 1, 0.0, rng.normal(0, 40, 2), np.eye(2) * 4.0, evidence=float(rng.normal(0, 2)))
    ids = [int(k) for k in rng.choice(np.arange(1, 320), 200, replace=False)]  # some not held
    top = sorted(ident.weights, key=ident.weights.get)[-3:]
    ids[50], ids[120], ids[150] = top  # likelier than H_0 before, turned by their readings
    evidence = rng.normal(0, 3, len(ids))
    evidence[[50, 120, 150]] = -40.0
    evidence[7] = 80.0  # beyond the ±50 clip
    w, w_none = ident._w.copy(), ident.w_none
    ev, at, last = dict(ident.evidence), ident._at, None
    for k, (track_id, e) in enumerate(zip(ids, evidence.tolist(), strict=True)):
        if track_id not in at:
            continue
        new = max(min(e, 50.0), -50.0)
        change, ev[track_id] = new - ev.get(track_id, 0.0), new
        if change != 0.0:
            i = at[track_id]
            was = w[i] > w_none
            w[i] *= math.exp(change)
            total = float(np.cumsum(w)[-1]) + w_none
            w, w_none = w / total, w_none / total
            last = k if was and w[i] <= w_none else last
    assert last is not None and last >= 150
    ident.read_many(ids, evidence.tolist(), where=lambda k: (1.0, np.array([k, 0.0]), np.zeros(2), np.eye(2)))
    assert np.array_equal(ident._w, w) and ident.w_none == w_none and ident.evidence == ev
    np.testing.assert_array_equal(ident.centre.p, [last, 0.0])
