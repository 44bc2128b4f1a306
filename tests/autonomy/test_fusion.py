"""Fusion: convex fusion, covariance intersection, HCMCI consensus, base-station fusion with lost packets."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from autonomy.estimation.factory import make_filter
from autonomy.estimation.linalg import tria
from autonomy.estimation.measurements import Measurement, NadirRadarModel, RadarModel
from autonomy.estimation.models import ConstantVelocity, Singer
from autonomy.estimation.scif import SCIF, SqrtInformation
from autonomy.fusion.base_station import BaseStationFusion, information_contribution, sample_received
from autonomy.fusion.consensus import hcmci, hcmci_step, metropolis_weights, ring_adjacency, without_links
from autonomy.fusion.convex import covariance_intersection, state_vector_fusion
from autonomy.metrics.errors import chi2_band, nees
from autonomy.metrics.team import consensus_disagreement


def spd(rng, n, scale=1.0):
    A = rng.normal(size=(n, n))
    return scale * (A @ A.T + n * np.eye(n))


# --- convex fusion and covariance intersection ------------------------------------------------------------------------
def test_state_vector_fusion_equals_information_form_for_independent_estimates():
    rng = np.random.default_rng(0)
    x_a, x_b = rng.normal(size=4), rng.normal(size=4)
    P_a, P_b = spd(rng, 4), spd(rng, 4, 3.0)
    f = state_vector_fusion(x_a, P_a, x_b, P_b)
    P = np.linalg.inv(np.linalg.inv(P_a) + np.linalg.inv(P_b))
    np.testing.assert_allclose(f.P, P, rtol=1e-10)
    np.testing.assert_allclose(f.x, P @ (np.linalg.solve(P_a, x_a) + np.linalg.solve(P_b, x_b)), rtol=1e-10)


@pytest.mark.parametrize("criterion", ["trace", "det"])
def test_ci_closed_forms(criterion):
    # symmetric inputs: ω = ½, P = (½ P_a⁻¹ + ½ P_b⁻¹)⁻¹ = 1.6 I
    f = covariance_intersection([np.zeros(2), np.ones(2)], [np.diag([1.0, 4.0]), np.diag([4.0, 1.0])], criterion)
    np.testing.assert_allclose(f.weights, [0.5, 0.5], atol=1e-12)
    np.testing.assert_allclose(f.P, 1.6 * np.eye(2), atol=1e-12)
    np.testing.assert_allclose(f.x, [0.2, 0.8], atol=1e-12)  # P (½ P_a⁻¹ 0 + ½ P_b⁻¹ 1)
    # nested inputs: all weight on the better estimate
    g = covariance_intersection([np.zeros(2), np.ones(2)], [np.eye(2), 4.0 * np.eye(2)], criterion)
    np.testing.assert_allclose(g.weights, [1.0, 0.0], atol=0.0)
    np.testing.assert_allclose(g.P, np.eye(2), atol=1e-12)
    np.testing.assert_allclose(g.x, np.zeros(2), atol=1e-12)


def test_ci_three_inputs_not_worse_than_best_input():
    rng = np.random.default_rng(4)
    Ps = [spd(rng, 3) for _ in range(3)]
    f = covariance_intersection([rng.normal(size=3) for _ in range(3)], Ps, "trace")
    assert np.trace(f.P) <= min(np.trace(P) for P in Ps) + 1e-9
    assert f.weights.sum() == pytest.approx(1.0) and np.all(f.weights >= 0)


def test_ci_consistent_for_correlated_inputs_where_convex_fusion_is_not():
    rng = np.random.default_rng(1)
    n_samples = 20000
    P_a, P_b = np.diag([4.0, 1.0]), np.diag([1.0, 4.0])
    # errors share a common component carrying 80 % of each variance
    common = rng.normal(size=(n_samples, 2)) * np.sqrt(0.8)
    e_a = (common + rng.normal(size=(n_samples, 2)) * np.sqrt(0.2)) * np.sqrt(np.diag(P_a))
    e_b = (common + rng.normal(size=(n_samples, 2)) * np.sqrt(0.2)) * np.sqrt(np.diag(P_b))
    ci = covariance_intersection([np.zeros(2), np.zeros(2)], [P_a, P_b], "trace")
    Ya, Yb = np.linalg.inv(P_a), np.linalg.inv(P_b)
    Ka, Kb = ci.P @ (ci.weights[0] * Ya), ci.P @ (ci.weights[1] * Yb)
    e_ci = e_a @ Ka.T + e_b @ Kb.T
    assert np.linalg.eigvalsh(ci.P - np.cov(e_ci.T)).min() > -0.02  # P_CI ⪰ actual error covariance
    cv = state_vector_fusion(np.zeros(2), P_a, np.zeros(2), P_b)
    K = P_a @ np.linalg.inv(P_a + P_b)
    e_cv = e_a + (e_b - e_a) @ K.T
    assert np.linalg.eigvalsh(cv.P - np.cov(e_cv.T)).min() < -0.3  # convex fusion is overconfident here


# --- HCMCI ------------------------------------------------------------------------------------------------------
def test_metropolis_weights():
    A = ring_adjacency((0, 2, 1, 3))
    W = metropolis_weights(A)
    np.testing.assert_allclose(W.sum(axis=1), 1.0)
    np.testing.assert_allclose(W, W.T)
    assert W[0, 2] == pytest.approx(1 / 3) and W[0, 1] == 0.0 and W[0, 0] == pytest.approx(1 / 3)
    cut = without_links(A, [(0, 2), (0, 3)])
    W2 = metropolis_weights(cut)
    assert W2[0, 0] == 1.0 and W2[1, 2] == pytest.approx(1 / 3) and W2[2, 2] == pytest.approx(2 / 3)
    with pytest.raises(ValueError, match="symmetric"):
        metropolis_weights(np.triu(np.ones((3, 3), dtype=bool), 1))


def _random_infos(rng, N, n, same_prior):
    S0 = np.linalg.cholesky(np.linalg.inv(spd(rng, n)))
    priors, contributions = [], []
    for _ in range(N):
        S = S0 if same_prior else np.linalg.cholesky(np.linalg.inv(spd(rng, n)))
        priors.append(SqrtInformation(S, S @ S.T @ rng.normal(size=n)))
        if same_prior:
            priors[-1] = SqrtInformation(S0, priors[0].h)
        H = rng.normal(size=(2, n))
        contributions.append(SqrtInformation(H.T * 0.7, H.T @ rng.normal(size=2)))
    return priors, contributions


def test_hcmci_with_many_iterations_equals_centralised_fusion():
    rng = np.random.default_rng(2)
    N, n = 4, 4
    priors, contributions = _random_infos(rng, N, n, same_prior=True)
    out = hcmci(priors, contributions, ring_adjacency((0, 2, 1, 3)), L=80, b="safe")
    Y_c = priors[0].Y + sum(c.Y for c in contributions)
    h_c = priors[0].h + sum(c.h for c in contributions)
    for o in out:
        np.testing.assert_allclose(o.Y, Y_c, rtol=1e-8)
        np.testing.assert_allclose(o.h, h_c, rtol=1e-8, atol=1e-10)
    # b = N gives the same at convergence
    out_n = hcmci(priors, contributions, ring_adjacency((0, 2, 1, 3)), L=80, b=N)
    np.testing.assert_allclose(out_n[2].Y, Y_c, rtol=1e-8)


def test_hcmci_averages_information_not_square_roots():
    n = 2
    S = np.array([[2.0, 0.0], [1.0, 1.0]])
    priors = [SqrtInformation(S, np.zeros(n)), SqrtInformation(-S, np.zeros(n))]  # same information, opposite roots
    out = hcmci(priors, [None, None], np.array([[False, True], [True, False]]), L=3)
    for o in out:
        np.testing.assert_allclose(o.Y, S @ S.T, rtol=1e-12)


def test_hcmci_disagreement_shrinks_as_iterations_grow():
    rng = np.random.default_rng(3)
    priors, contributions = _random_infos(rng, 4, 4, same_prior=False)
    A = ring_adjacency((0, 2, 1, 3))
    spread = []
    for L in (0, 1, 2, 4, 8, 16):
        out = hcmci(priors, contributions, A, L=L)
        xs = np.array([np.linalg.solve(o.Y, o.h) for o in out])
        spread.append(consensus_disagreement(xs).max())
    assert all(b < a for a, b in zip(spread, spread[1:], strict=False))
    assert spread[-1] < 1e-3 * spread[0]
    # L = 0 is the local update
    out0 = hcmci(priors, contributions, A, L=0)
    np.testing.assert_allclose(out0[1].Y, priors[1].Y + contributions[1].Y * 1.0, rtol=1e-10)


def _team_run(rng, links_down, b, n_steps=50, L=2):
    """Four SCIF nodes with radars track a Singer target, fusing with HCMCI over ring 1–3–2–4–1."""
    model = Singer(alpha=0.6, sigma_a=0.66)
    dt = 0.5
    F, Q = model.matrices(dt)
    S_Q = np.linalg.cholesky(Q)
    x = np.array([0.0, 5.0, 0.0, 0.0, 3.0, 0.0])
    P0 = np.diag([100.0, 4.0, 0.5, 100.0, 4.0, 0.5])
    sensors = [np.array([p[0], p[1], h]) for p, h in zip([(-300, 0), (300, 50), (0, -300), (50, 300)],
                                                         (100.0, 100.0, 110.0, 110.0), strict=True)]
    sig = np.array([3.0, 0.01, 0.01])
    R = np.diag(sig**2)
    nodes = [SCIF(model, x + np.linalg.cholesky(P0) @ rng.normal(size=6), P0) for _ in range(4)]
    ring = ring_adjacency((0, 2, 1, 3))
    out = np.empty((n_steps, 4))
    for k in range(n_steps):
        x = F @ x + S_Q @ rng.normal(size=6)
        t = (k + 1) * dt
        meas = []
        for p in sensors:
            z = RadarModel(model.layout, p, 3).h(x) + sig * rng.normal(size=3)
            meas.append(Measurement(z=z, R=R, t_meas=t, p_sensor_W=p))
        if k % 7 == 3:
            meas[1] = None  # a missed detection: that node brings only its prior
        A = without_links(ring, links_down) if k >= 10 else ring
        hcmci_step(nodes, meas, A, L=L, b=b, t=t)
        out[k] = [nees(x, nd.x, nd.P) for nd in nodes]
    return out


def test_hcmci_nodes_stay_consistent_with_links_cut():
    """Paper 000 case 2 topology: links 1–3 and 1–4 down isolates UAV 1; every node's NEES stays below the band."""
    rng = np.random.default_rng(8)
    n_runs = 20
    runs = np.array([_team_run(rng, [(0, 2), (0, 3)], b="safe") for _ in range(n_runs)])
    avg = runs.mean(axis=0)  # (steps, nodes)
    band = chi2_band(dof=6, n_runs=n_runs)
    for j in range(4):
        assert np.mean(avg[:, j] <= band.upper) >= 0.9, (j, avg[:, j].max(), band)
    # with b = N the isolated node counts its own radar N times: overconfident
    rng = np.random.default_rng(8)
    runs_n = np.array([_team_run(rng, [(0, 2), (0, 3)], b=4.0) for _ in range(n_runs)])
    assert np.mean(runs_n.mean(axis=0)[10:, 0] > band.upper) > 0.5


def test_paper_000_case_1_shape():
    """Four SCIF UAVs (nadir-angle radars, paper 000's R_j and altitudes, Euler Singer) over the ring with HCMCI, L = 5:
    position error well under 10 m and consensus error under 0.05 m, as the paper reports."""
    d2r = np.pi / 180
    Rs = [np.diag([1.0, 0.5 * d2r, 0.5 * d2r]), np.diag([2.5, 0.3 * d2r, 0.6 * d2r]),
          np.diag([1.5, 0.1 * d2r, 0.5 * d2r]), np.diag([1.0, 0.1 * d2r, 0.5 * d2r])]
    alts, offsets = [100.0, 100.0, 110.0, 110.0], [10.0, -10.0, 9.0, -9.0]
    rng = np.random.default_rng(0)
    truth_model = Singer(alpha=0.6, sigma_a=0.67)
    model = Singer(alpha=0.6, sigma_a=0.67, discretisation="euler")
    F, Q = truth_model.matrices(0.5)
    S_Q = np.linalg.cholesky(Q)
    x = np.array([4500.0, 2.0, 0.0, -8.0, 0.0, 0.0])
    P0 = np.diag([25.0, 4.0, 1.0, 25.0, 4.0, 1.0])
    nodes = [SCIF(model, x + np.sqrt(np.diag(P0)) * rng.normal(size=6), P0) for _ in range(4)]
    ring = ring_adjacency((0, 2, 1, 3))
    errors, spread = [], []
    for k in range(200):
        x = F @ x + S_Q @ rng.normal(size=6)
        meas, models = [], []
        for R, h, dx in zip(Rs, alts, offsets, strict=True):
            p = np.array([x[0] + dx, x[3], h])  # the UAVs fly over the target
            mm = NadirRadarModel(model.layout, p)
            meas.append(Measurement(z=mm.h(x) + np.linalg.cholesky(R) @ rng.normal(size=3), R=R, t_meas=(k + 1) * 0.5,
                                    p_sensor_W=p))
            models.append(mm)
        hcmci_step(nodes, meas, ring, L=5, models=models)
        est = np.array([nd.x[[0, 3]] for nd in nodes])
        errors.append(np.linalg.norm(est - x[[0, 3]], axis=1))
        spread.append(consensus_disagreement(est))
    errors, spread = np.array(errors)[20:], np.array(spread)[20:]
    assert np.all(errors.mean(axis=0) < 7.0)
    assert spread.mean() < 0.05


# --- base station -----------------------------------------------------------------------------------------------
def _linear_packets(rng, x_true, t, n):
    return [Measurement(z=x_true[[0, 2]] + rng.normal(size=2) * (1.0 + j), R=np.eye(2) * (1.0 + j) ** 2, t_meas=t,
                        kind="box", sensor_id=j) for j in range(n)]


def test_base_station_fusion_with_lost_packets_equals_kf_on_received():
    rng = np.random.default_rng(5)
    model = ConstantVelocity(q=0.3)
    x0, P0 = np.array([0.0, 1.0, 0.0, 2.0]), np.eye(4) * 10.0
    base = BaseStationFusion(model, x0, P0)
    kf = make_filter("ekf", model, x0, P0)
    kf_all = make_filter("ekf", model, x0, P0)
    x_true = x0.copy()
    beta = np.array([0.9, 0.5, 0.2])
    lost = 0
    for k in range(40):
        t = (k + 1) * 0.5
        x_true = model.matrices(0.5)[0] @ x_true
        packets = _linear_packets(rng, x_true, t, 3)
        kf.predict(t)
        contributions = [information_contribution(kf.x, m, model.layout) for m in packets]
        received = sample_received(beta, rng)
        lost += int((~received).sum())
        base.fuse(contributions, received)
        for m, ok in zip(packets, received, strict=True):
            kf_all.update(m)
            if ok:
                kf.update(m)
        np.testing.assert_allclose(base.x, kf.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(base.P, kf.P, rtol=1e-9, atol=1e-9)
    assert lost > 0 and base.n_lost == lost and base.n_received == 120 - lost
    assert np.trace(base.P) > np.trace(kf_all.P)  # losing packets costs information


def test_information_contribution_matches_ekf_update_for_radar():
    model = ConstantVelocity(q=0.3)
    x0, P0 = np.array([200.0, 3.0, 100.0, -2.0]), np.diag([50.0, 4.0, 50.0, 4.0])
    meas = Measurement(z=np.array([260.0, 0.45, -0.3]), R=np.diag([4.0, 1e-4, 1e-4]), t_meas=1.0,
                       p_sensor_W=np.array([0.0, 0.0, 80.0]))
    ekf = make_filter("ekf", model, x0, P0)
    base = BaseStationFusion(model, x0, P0)
    ekf.predict(1.0)
    base.fuse([information_contribution(ekf.x, meas, model.layout)])
    ekf.update(meas)
    np.testing.assert_allclose(base.x, ekf.x, rtol=1e-9)
    np.testing.assert_allclose(base.P, ekf.P, rtol=1e-8)


def test_tria_returns_lower_triangular_root():
    rng = np.random.default_rng(6)
    A = rng.normal(size=(4, 9))
    S = tria(A)
    np.testing.assert_allclose(S @ S.T, A @ A.T, rtol=1e-12)
    assert np.allclose(np.triu(S, 1), 0.0)


@pytest.mark.parametrize("criterion", ["trace", "det"])
def test_ci_three_inputs_reach_the_global_optimum_of_a_simplex_grid(criterion):
    """Both costs are convex in the weights: the solver's weights beat every point of a 0.01 grid on the simplex."""
    rng = np.random.default_rng(7)
    Ps = [spd(rng, 3) for _ in range(3)]
    f = covariance_intersection([rng.normal(size=3) for _ in range(3)], Ps, criterion)
    Ys = [np.linalg.inv(P) for P in Ps]

    def cost(w):
        P = np.linalg.inv(sum(wi * Y for wi, Y in zip(w, Ys, strict=True)))
        return np.trace(P) if criterion == "trace" else np.linalg.slogdet(P)[1]

    grid = [(a, b, 1.0 - a - b) for a in np.arange(0, 1.0001, 0.01) for b in np.arange(0, 1.0001 - a, 0.01)]
    best = min(cost(w) for w in grid)
    assert cost(f.weights) <= best + 1e-9
    assert np.isfinite(cost(f.weights)) and np.all(f.weights >= 0) and f.weights.sum() == pytest.approx(1.0)
    fused_information = sum(w * Y for w, Y in zip(f.weights, Ys, strict=True))
    np.testing.assert_allclose(np.linalg.inv(f.P), fused_information, rtol=1e-9, atol=1e-9)


# --- two-input covariance intersection: exact weights -----------------------------------------------------------------
def _spd_with_condition(rng, n, cond):
    """Random SPD matrix with condition number ``cond`` (log-uniform spectrum) and a random overall scale."""
    Q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    ev = np.exp(rng.uniform(0.0, np.log(cond), n))
    ev[0], ev[-1] = 1.0, cond
    return (Q * ev) @ Q.T * np.exp(rng.normal())


def _ci2_cost(w, Ys, criterion):
    """Dense reference: tr P or log det P with P = (ω Y_1 + (1 − ω) Y_2)⁻¹."""
    P = np.linalg.inv(w * Ys[0] + (1.0 - w) * Ys[1])
    return np.trace(P) if criterion == "trace" else np.linalg.slogdet(P)[1]


def _ci2_cost_slack(cost, criterion):
    """1e-9 relative on tr P and on det P (the latter is 1e-9 absolute on log det P)."""
    return 1e-9 * abs(cost) if criterion == "trace" else 1e-9


def _random_pair(rng, max_log10_cond):
    n = int(rng.integers(2, 7))
    P1 = _spd_with_condition(rng, n, 10.0 ** rng.uniform(0.0, max_log10_cond))
    P2 = _spd_with_condition(rng, n, 10.0 ** rng.uniform(0.0, max_log10_cond)) * 10.0 ** rng.uniform(-2.0, 2.0)
    return P1, P2


@pytest.mark.parametrize("criterion", ["trace", "det"])
def test_ci_two_inputs_beat_the_bounded_scalar_search_and_a_dense_grid(criterion):
    """Many random pairs, n = 2…6, condition numbers up to 1e8, scales 1e±2: the weights' cost (evaluated densely) is
    never above the former bounded search (xatol 1e-6) nor the best of a 1001-point grid on [0, 1], within 1e-9
    relative; both interior optima and optima at ω = 0 or 1 occur."""
    rng = np.random.default_rng(11)
    interior = ends = 0
    for _ in range(120):
        P1, P2 = _random_pair(rng, 8.0)
        Ys = [np.linalg.inv(P1), np.linalg.inv(P2)]
        f = covariance_intersection([np.zeros(len(P1))] * 2, [P1, P2], criterion)
        w = f.weights[0]
        assert 0.0 <= w <= 1.0 and f.weights[1] == 1.0 - w
        bounded = minimize_scalar(lambda a, Ys=Ys: _ci2_cost(a, Ys, criterion), bounds=(0.0, 1.0), method="bounded",
                                  options={"xatol": 1e-6})
        grid = min(_ci2_cost(a, Ys, criterion) for a in np.linspace(0.0, 1.0, 1001))
        reference = min(bounded.fun, grid)
        assert _ci2_cost(w, Ys, criterion) <= reference + _ci2_cost_slack(reference, criterion)
        interior += 0.0 < w < 1.0
        ends += w in (0.0, 1.0)
    assert interior >= 30 and ends >= 15


def _fused_random_pair(rng, max_log10_cond, criterion):
    """((x_1, P_1), (x_2, P_2), their CI) for a random pair (:func:`_random_pair`) and random states."""
    P1, P2 = _random_pair(rng, max_log10_cond)
    x1, x2 = rng.normal(size=len(P1)), rng.normal(size=len(P1))
    return (x1, P1), (x2, P2), covariance_intersection([x1, x2], [P1, P2], criterion)


@pytest.mark.parametrize("criterion", ["trace", "det"])
def test_ci_two_inputs_are_stationary_and_use_the_ci_formulas(criterion):
    """Well-conditioned pairs: P = (ω Y_1 + (1 − ω) Y_2)⁻¹ and x = P (ω Y_1 x_1 + (1 − ω) Y_2 x_2) to 1e-10, and the
    cost's derivative (−tr(P ΔY P) or −tr(P ΔY), ΔY = Y_1 − Y_2) vanishes at an interior ω to 1e-9 of its scale (a
    1e-6 search tolerance leaves ≈ 1e-6) and points outwards at an end point."""
    rng = np.random.default_rng(12)
    for _ in range(200):
        (x1, P1), (x2, P2), f = _fused_random_pair(rng, 3.0, criterion)
        w = f.weights[0]
        Y1, Y2 = np.linalg.inv(P1), np.linalg.inv(P2)
        P = np.linalg.inv(w * Y1 + (1.0 - w) * Y2)
        np.testing.assert_allclose(f.P, P, rtol=1e-10, atol=1e-10 * np.abs(P).max())
        np.testing.assert_allclose(f.x, P @ (w * Y1 @ x1 + (1.0 - w) * Y2 @ x2), rtol=1e-10,
                                   atol=1e-10 * np.abs(f.x).max())
        if criterion == "trace":
            A, B = np.trace(P @ Y1 @ P), np.trace(P @ Y2 @ P)
        else:
            A, B = np.trace(P @ Y1), np.trace(P @ Y2)
        dcost = B - A  # d cost / dω
        if 0.0 < w < 1.0:
            assert abs(dcost) <= 1e-9 * (A + B)
        elif w == 0.0:
            assert dcost >= -1e-9 * (A + B)
        else:
            assert dcost <= 1e-9 * (A + B)


@pytest.mark.parametrize("criterion", ["trace", "det"])
def test_ci_two_loewner_ordered_inputs_keep_the_smaller_one(criterion):
    """P_1 ⪯ P_2 (also P_2 = P_1 + a rank-one term, equal in all other directions): ω = 1 exactly, P = P_1, x = x_1;
    and ω = 0 with the inputs swapped."""
    rng = np.random.default_rng(13)
    for n in range(2, 7):
        for extra in (spd(rng, n, 0.1), np.outer(*(2 * [rng.normal(size=n)]))):
            P1 = _spd_with_condition(rng, n, 10.0 ** rng.uniform(0.0, 6.0))
            P2 = P1 + extra * np.abs(P1).max()
            x1, x2 = rng.normal(size=n), rng.normal(size=n)
            f = covariance_intersection([x1, x2], [P1, P2], criterion)
            assert f.weights.tolist() == [1.0, 0.0]
            np.testing.assert_allclose(f.P, P1, rtol=1e-9, atol=1e-12 * np.abs(P1).max())
            np.testing.assert_allclose(f.x, x1, rtol=1e-6, atol=1e-9)
            g = covariance_intersection([x2, x1], [P2, P1], criterion)
            assert g.weights.tolist() == [0.0, 1.0]
            np.testing.assert_allclose(g.P, f.P, rtol=1e-9, atol=1e-12 * np.abs(P1).max())


@pytest.mark.parametrize("criterion", ["trace", "det"])
def test_ci_two_inputs_order_asymmetry_and_near_singular_inputs(criterion):
    rng = np.random.default_rng(14)
    for _ in range(50):
        (x1, P1), (x2, P2), f = _fused_random_pair(rng, 4.0, criterion)
        n = len(P1)
        # order of the inputs: weights swap, the same fused estimate
        g = covariance_intersection([x2, x1], [P2, P1], criterion)
        np.testing.assert_allclose(g.weights, f.weights[::-1], atol=1e-9)
        np.testing.assert_allclose(g.P, f.P, rtol=1e-8, atol=1e-10 * np.abs(f.P).max())
        np.testing.assert_allclose(g.x, f.x, rtol=1e-8, atol=1e-10 * np.abs(f.x).max())
        # slightly asymmetric inputs are read as their symmetric part
        K = rng.normal(size=(n, n))
        h = covariance_intersection([x1, x2], [P1 + 1e-12 * np.abs(P1).max() * (K - K.T), P2], criterion)
        np.testing.assert_allclose(h.weights, f.weights, atol=1e-9)
        np.testing.assert_allclose(h.P, f.P, rtol=1e-8, atol=1e-10 * np.abs(f.P).max())
    # nearly singular input (condition number 1e13): finite, PD, no worse than either input
    for _ in range(20):
        n = int(rng.integers(2, 7))
        P1, P2 = _spd_with_condition(rng, n, 1e13), _spd_with_condition(rng, n, 10.0)
        f = covariance_intersection([rng.normal(size=n), rng.normal(size=n)], [P1, P2], criterion)
        assert np.all(np.isfinite(f.x)) and np.all(np.isfinite(f.P)) and 0.0 <= f.weights[0] <= 1.0
        assert np.linalg.eigvalsh(f.P).min() > 0.0
        if criterion == "trace":
            assert np.trace(f.P) <= min(np.trace(P1), np.trace(P2)) * (1.0 + 1e-9)
    # identical covariances: every ω is optimal; the symmetric one averages the states
    P = spd(rng, 4)
    f = covariance_intersection([np.zeros(4), np.ones(4)], [P, P.copy()], criterion)
    np.testing.assert_allclose(f.weights, [0.5, 0.5])
    np.testing.assert_allclose(f.x, 0.5 * np.ones(4), rtol=1e-12)
    np.testing.assert_allclose(f.P, P, rtol=1e-12)
