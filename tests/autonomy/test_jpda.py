"""JPDA marginal association probabilities (hand-computed joint events, brute-force enumeration, the cheap-JPDA
fallback) and the PDA update (closed-form Kalman PDA, one-hot β equal to the plain update)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from autonomy.estimation.factory import make_filter
from autonomy.estimation.measurements import Measurement, PositionDetectionModel
from autonomy.estimation.models import ConstantVelocity
from autonomy.estimation.tracking.gate import ChiSquareGate, PredictedNis
from autonomy.estimation.tracking.jpda import JointProbabilisticAssociator, cluster_marginals, pda_update
from autonomy.estimation.tracking.track import Track

MODEL = ConstantVelocity(q=0.5)
BOX = PositionDetectionModel(dim=2)


def box(z, t=0.0, r=1.0, sensor_id=0) -> Measurement:
    return Measurement(z=np.asarray(z, dtype=float), R=r * np.eye(2), t_meas=t, model=BOX, sensor_id=sensor_id)


def track_at(x, y, sp2=4.0, kind="ekf") -> Track:
    return Track(make_filter(kind, MODEL, np.array([x, 0.0, y, 0.0]), np.diag([sp2, 1.0, sp2, 1.0])), 0.0)


def test_two_tracks_two_detections_by_hand():
    """Tracks at (0, 0) and (6, 0), detections (2, 1) and (4, −1), S = (4 + 1) I for every pair (no prediction):
    all four pairs are gated, and the seven feasible joint events are written out."""
    pd, pg, lam = 0.8, 0.9999, 1e-3
    tracks = [track_at(0.0, 0.0), track_at(6.0, 0.0)]
    dets = [box([2.0, 1.0]), box([4.0, -1.0])]
    jpda = JointProbabilisticAssociator(ChiSquareGate(pg), PredictedNis(MODEL, 0.0), pd, lam)
    a = jpda.assign(tracks, dets)

    s = 5.0

    def N(track_xy, z):  # N(ν; 0, s I) in the plane
        nu = np.subtract(z, track_xy)
        return math.exp(-0.5 * float(nu @ nu) / s) / (2.0 * math.pi * s)

    L = {(i, j): pd * N(t, z) / lam for i, t in enumerate([(0.0, 0.0), (6.0, 0.0)])
         for j, z in enumerate([(2.0, 1.0), (4.0, -1.0)])}
    m = 1.0 - pd * pg
    events = {  # {track: detection} → weight
        (): m * m,
        ((0, 0),): L[0, 0] * m, ((0, 1),): L[0, 1] * m, ((1, 0),): m * L[1, 0], ((1, 1),): m * L[1, 1],
        ((0, 0), (1, 1)): L[0, 0] * L[1, 1], ((0, 1), (1, 0)): L[0, 1] * L[1, 0],
    }
    total = sum(events.values())
    expected = np.zeros((2, 3))
    for pairs, w in events.items():
        got = dict(pairs)
        for i in range(2):
            expected[i, got[i] + 1 if i in got else 0] += w / total
    np.testing.assert_allclose(a.weights, expected, rtol=0.0, atol=1e-12)
    assert a.pairs == ((0, 0), (0, 1), (1, 0), (1, 1))
    assert a.unused == () and a.gated_out == ()
    assert jpda.approximated == 0


def brute_marginals(log_L: np.ndarray, log_miss: float) -> np.ndarray:
    k, n = log_L.shape
    beta = np.zeros((k, n + 1))
    total = 0.0
    for choice in itertools.product(range(-1, n), repeat=k):
        taken = [j for j in choice if j >= 0]
        if len(taken) != len(set(taken)) or any(j >= 0 and not np.isfinite(log_L[i, j]) for i, j in enumerate(choice)):
            continue
        w = math.exp(sum(log_L[i, j] if j >= 0 else log_miss for i, j in enumerate(choice)))
        total += w
        for i, j in enumerate(choice):
            beta[i, j + 1] += w
    return beta / total


@pytest.mark.parametrize("seed", range(10))
def test_enumeration_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    k, n = int(rng.integers(2, 5)), int(rng.integers(2, 5))
    log_L = rng.normal(0.0, 3.0, (k, n)) + 40.0 * (seed % 2)  # large ratios: the per-track scaling must hold
    log_L[rng.uniform(size=(k, n)) < 0.3] = -np.inf
    log_miss = math.log(1.0 - 0.9 * 0.99)
    beta, exact = cluster_marginals(log_L, log_miss, 10_000)
    assert exact
    np.testing.assert_allclose(beta, brute_marginals(log_L, log_miss), rtol=1e-12, atol=1e-14)


def scene(n: int, seed: int) -> tuple[list[Track], list[Measurement]]:
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0.0, 60.0 * math.sqrt(n), (n, 2))
    tracks = [track_at(x, y, sp2=9.0) for x, y in xy]
    dets = [box(p + rng.normal(0.0, 3.0, 2), t=0.5, r=4.0) for p in xy[rng.uniform(size=n) < 0.9]]
    dets += [box(p, t=0.5, r=4.0) for p in rng.uniform(0.0, 60.0 * math.sqrt(n), (5, 2))]
    return tracks, dets


@pytest.mark.parametrize("seed", range(5))
def test_weights_are_probabilities(seed):
    tracks, dets = scene(40, seed)
    jpda = JointProbabilisticAssociator(ChiSquareGate(0.99), PredictedNis(MODEL, 0.0), 0.9, 1e-4)
    a = jpda.assign(tracks, dets)
    assert a.weights.shape == (len(tracks), len(dets) + 1)
    assert np.all(a.weights >= 0.0)
    np.testing.assert_allclose(a.weights.sum(axis=1), 1.0, rtol=0.0, atol=1e-12)
    gated = np.isfinite(a.costs.nis)
    assert np.all(a.weights[:, 1:][~gated] == 0.0)  # no weight outside the gate
    assert set(a.pairs) == set(zip(*np.nonzero(gated), strict=True))
    assert set(a.unused) == set(a.gated_out) == {j for j in range(len(dets)) if not gated[:, j].any()}


def test_fallback_counts_and_keeps_lone_tracks_exact():
    tracks, dets = scene(60, 11)
    exact = JointProbabilisticAssociator(ChiSquareGate(0.999), PredictedNis(MODEL, 0.0), 0.9, 1e-4)
    cheap = JointProbabilisticAssociator(ChiSquareGate(0.999), PredictedNis(MODEL, 0.0), 0.9, 1e-4,
                                         max_cluster_events=1)
    a, b = exact.assign(tracks, dets), cheap.assign(tracks, dets)
    assert exact.approximated == 0 and cheap.approximated > 0
    np.testing.assert_allclose(b.weights.sum(axis=1), 1.0, atol=1e-12)
    # a component of one track is the plain PDA either way: the cheap form is exact there
    gated = np.isfinite(a.costs.nis)
    lone = [i for i in range(len(tracks)) if gated[i].any() and np.all(gated[:, gated[i]].sum(axis=0) == 1)]
    assert lone
    np.testing.assert_allclose(b.weights[lone], a.weights[lone], rtol=1e-12, atol=1e-15)


def test_jpda_refuses_a_scan_of_several_sensors():
    jpda = JointProbabilisticAssociator(ChiSquareGate(0.99), PredictedNis(MODEL, 0.0), 0.9, 1e-4)
    with pytest.raises(ValueError, match="one sensor"):
        jpda.assign([track_at(0.0, 0.0)], [box([0.0, 0.0]), box([1.0, 0.0], sensor_id=1)])
    assert len(jpda.assign_groups([track_at(0.0, 0.0)], [box([0.0, 0.0]), box([1.0, 0.0], sensor_id=1)])) == 2


@pytest.mark.parametrize("bad", [dict(detection_probability=0.0), dict(clutter_density=0.0),
                                 dict(max_cluster_events=0)])
def test_jpda_config_is_checked(bad):
    kw = dict(detection_probability=0.9, clutter_density=1e-4) | bad
    with pytest.raises(ValueError, match=next(iter(bad))):
        JointProbabilisticAssociator(ChiSquareGate(0.99), PredictedNis(MODEL, 0.0), **kw)


# --- PDA update -----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["ekf", "ukf", "ckf", "scif"])
def test_pda_with_one_sure_detection_is_the_plain_update(kind):
    a, b = track_at(1.0, 2.0, kind=kind).filter, track_at(1.0, 2.0, kind=kind).filter
    dets = [box([5.0, 5.0], t=0.5), box([1.5, 2.5], t=0.5)]
    pda_update(a, dets, [0.0, 0.0, 1.0])
    b.update(dets[1])
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.P, b.P)
    c, d = track_at(1.0, 2.0, kind=kind).filter, track_at(1.0, 2.0, kind=kind).filter
    pda_update(c, dets, [1.0, 0.0, 0.0])
    d.predict(0.5)
    np.testing.assert_array_equal(c.x, d.x)
    np.testing.assert_array_equal(c.P, d.P)
    assert c.t == d.t == 0.5


def test_pda_update_is_the_kalman_pda():
    """Linear Kalman filter: x = x⁻ + K ν̄, P = β₀ P⁻ + (1 − β₀) (I − K H) P⁻ + K (Σ βⱼ νⱼ νⱼᵀ − ν̄ ν̄ᵀ) Kᵀ, with
    ν̄ = Σ βⱼ νⱼ (Bar-Shalom and Tse 1975)."""
    f = track_at(1.0, 2.0).filter
    dets = [box([2.0, 1.0], t=0.5, r=2.0), box([0.0, 3.5], t=0.5, r=2.0)]
    betas = np.array([0.2, 0.5, 0.3])
    g = track_at(1.0, 2.0).filter
    g.predict(0.5)
    x_, P_ = g.x.copy(), g.P.copy()
    H = np.zeros((2, 4))
    H[0, 0] = H[1, 2] = 1.0
    S = H @ P_ @ H.T + 2.0 * np.eye(2)
    K = P_ @ H.T @ np.linalg.inv(S)
    nus = [d.z - H @ x_ for d in dets]
    nu_bar = sum(b * n for b, n in zip(betas[1:], nus, strict=True))
    spread = sum(b * np.outer(n, n) for b, n in zip(betas[1:], nus, strict=True)) - np.outer(nu_bar, nu_bar)
    P_exp = betas[0] * P_ + (1.0 - betas[0]) * (np.eye(4) - K @ H) @ P_ + K @ spread @ K.T
    pda_update(f, dets, betas)
    np.testing.assert_allclose(f.x, x_ + K @ nu_bar, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(f.P, P_exp, rtol=1e-10, atol=1e-12)
    assert f.t == 0.5


@pytest.mark.parametrize("betas", [[0.5, 0.6], [0.5, 0.5, 0.2], [-0.1, 1.1]])
def test_pda_update_checks_betas(betas):
    with pytest.raises(ValueError, match="betas"):
        pda_update(track_at(0.0, 0.0).filter, [box([0.0, 0.0])] * (len(betas) - 1), betas)


def test_pda_update_on_an_imm_moment_matches_the_updated_copies():
    """Any filter: two IMMs (CV and CT modes) updated on deep copies, their moments combined and set back."""
    from autonomy.estimation.imm import IMM
    from autonomy.estimation.models import CoordinatedTurn

    def imm() -> IMM:
        x0, P0 = np.array([1.0, 2.0, 2.0, -1.0]), np.diag([4.0, 1.0, 4.0, 1.0])
        return IMM([make_filter("ekf", MODEL, x0, P0), make_filter("ekf", CoordinatedTurn(omega=0.2, q=0.5), x0, P0)],
                   np.array([[0.9, 0.1], [0.1, 0.9]]))

    dets = [box([2.0, 1.0], t=0.5, r=2.0), box([1.0, 3.0], t=0.5, r=2.0)]
    betas = np.array([0.1, 0.6, 0.3])
    f = imm()
    parts = []
    for j in range(3):
        g = imm()
        if j:
            g.update(dets[j - 1])
        else:
            g.predict(0.5)
        parts.append((g.x, g.P))
    x = sum(b * xj for b, (xj, _) in zip(betas, parts, strict=True))
    P = sum(b * (Pj + np.outer(xj - x, xj - x)) for b, (xj, Pj) in zip(betas, parts, strict=True))
    pda_update(f, dets, betas)
    np.testing.assert_allclose(f.x, x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(f.P, P, rtol=1e-10, atol=1e-12)
    assert f.t == 0.5
