"""Metrics: errors, NEES/NIS bands, OSPA/GOSPA, team metrics and the bearing FIM of paper 003."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom, chi2

from autonomy.metrics.errors import (
    chi2_band,
    euclidean_errors,
    fraction_inside,
    mean_euclidean_error,
    nees,
    nis,
    rmse,
    state_errors,
)
from autonomy.metrics.fim import bearing_fim, bearing_fim_from_directions, max_det_bearing_fim, optimal_bearing_geometry
from autonomy.metrics.multi_target import gospa, ospa
from autonomy.metrics.team import average_information_trace, consensus_disagreement, max_consensus_disagreement

EX1_SENSORS = np.array([[-10.0, 0.0], [0.0, 0.0], [0.0, 10.0]])
EX1_TARGET = np.array([5.0, 5.0])


def test_mean_error_and_rmse_closed_form():
    truth = np.zeros((4, 2))
    est = np.array([[3.0, 4.0], [0.0, 1.0], [0.0, 0.0], [6.0, 8.0]])  # errors 5, 1, 0, 10
    np.testing.assert_allclose(euclidean_errors(truth, est), [5, 1, 0, 10])
    assert mean_euclidean_error(truth, est) == pytest.approx(4.0)
    assert rmse(truth, est) == pytest.approx(np.sqrt((25 + 1 + 0 + 100) / 4))


def test_state_errors_by_layout():
    layout = ("x", "vx", "ax", "y", "vy", "ay")
    truth = np.array([[0.0, 10.0, 0.0, 0.0, 0.0, 0.0], [0.0, 10.0, 0.0, 0.0, 0.0, 0.0]])
    est = np.array([[3.0, 0.0, 9.0, 4.0, 10.0, 9.0], [0.0, 10.0, 0.0, 0.0, 0.0, 0.0]])  # 90° heading error, same speed
    e = state_errors(truth, est, layout)
    assert e.mean_position == pytest.approx(2.5) and e.rmse_position == pytest.approx(np.sqrt(12.5))
    assert e.mean_velocity == pytest.approx(np.sqrt(200) / 2)
    assert e.mean_speed == pytest.approx(0.0)
    assert e.mean_heading == pytest.approx(np.pi / 4)


def test_nees_and_nis_closed_form_and_broadcasting():
    P = np.diag([4.0, 9.0])
    assert nees(np.zeros(2), np.array([2.0, 3.0]), P) == pytest.approx(2.0)
    e = np.array([[2.0, 0.0], [0.0, 6.0]])
    np.testing.assert_allclose(nees(np.zeros((2, 2)), e, np.stack([P, P])), [1.0, 4.0])
    assert nis(np.array([1.0]), np.array([[0.25]])) == pytest.approx(4.0)


def test_chi2_band_values():
    band = chi2_band(dof=2, n_runs=50)
    assert band.lower == pytest.approx(chi2.ppf(0.025, 100) / 50)
    assert band.upper == pytest.approx(chi2.ppf(0.975, 100) / 50)
    assert band.lower == pytest.approx(1.4844, abs=1e-3) and band.upper == pytest.approx(2.5911, abs=1e-3)
    with pytest.raises(ValueError, match="dof"):
        chi2_band(dof=0)


def test_nees_of_consistent_samples_hits_band_at_its_confidence():
    rng = np.random.default_rng(0)
    n_samples = 4000
    P = np.array([[4.0, 1.0], [1.0, 2.0]])
    e = rng.normal(size=(n_samples, 2)) @ np.linalg.cholesky(P).T
    inside = fraction_inside(nees(np.zeros(2), e, P), chi2_band(dof=2))
    lo, hi = binom.ppf([0.0005, 0.9995], n_samples, 0.95) / n_samples
    assert lo <= inside <= hi


def test_ospa_closed_forms():
    X = np.array([[0.0, 0.0], [10.0, 0.0]])
    assert ospa(X, X, c=5.0) == 0.0
    assert ospa(X, X + [3.0, 4.0], c=100.0, p=1) == pytest.approx(5.0)
    # one missed target: ((0 + c^p) / 2)^{1/p}
    assert ospa(X, X[:1], c=20.0, p=2) == pytest.approx(np.sqrt(20.0**2 / 2))
    assert ospa(np.empty((0, 2)), np.empty((0, 2)), c=1.0) == 0.0
    # swapped order: assignment, not index matching
    assert ospa(X, X[::-1], c=5.0) == 0.0


def test_gospa_decomposition():
    truth = np.array([[0.0, 0.0], [100.0, 0.0]])
    est = np.array([[3.0, 4.0], [500.0, 500.0], [600.0, 600.0]])
    g = gospa(truth, est, c=20.0, p=2)
    assert (g.missed, g.false) == (1, 2)
    assert g.localisation == pytest.approx(25.0)
    assert g.distance == pytest.approx(np.sqrt(25.0 + 20.0**2 / 2 * 3))
    empty = gospa(truth, np.empty((0, 2)), c=10.0, p=1)
    assert empty.distance == pytest.approx(10.0) and empty.missed == 2



def _gospa_by_enumeration(X: np.ndarray, Y: np.ndarray, c: float, p: float) -> float:
    """GOSPA (α = 2) by its definition: the least cost over every partial one-to-one assignment, pairs charged
    min(d, c)^p and each point left out c^p / 2."""
    from itertools import permutations

    m, n = len(X), len(Y)
    best = np.inf
    for perm in permutations(range(n + m), m):  # truth i -> estimate perm[i], or unassigned when perm[i] >= n
        pairs = [(i, j) for i, j in enumerate(perm) if j < n]
        cost = sum(min(np.linalg.norm(X[i] - Y[j]), c) ** p for i, j in pairs)
        best = min(best, cost + c**p / 2 * (m + n - 2 * len(pairs)))
    return best ** (1.0 / p)


def test_gospa_is_the_least_cost_over_every_assignment():
    rng = np.random.default_rng(11)
    for trial in range(150):
        m, n = int(rng.integers(0, 5)), int(rng.integers(0, 5))
        X, Y = rng.uniform(0, 40, size=(m, 2)), rng.uniform(0, 40, size=(n, 2))
        c, p = float(rng.choice([3.0, 10.0, 30.0])), float(rng.choice([1.0, 2.0]))
        g = gospa(X, Y, c=c, p=p)
        assert g.distance == pytest.approx(_gospa_by_enumeration(X, Y, c, p), rel=1e-12, abs=1e-12), trial
        assert g.distance == pytest.approx((g.localisation + c**p / 2 * (g.missed + g.false)) ** (1 / p))
        assert g.missed - g.false == m - n

def test_gospa_of_crowds_is_the_dense_assignment():
    """Hundreds of points in clusters (many pairs in reach of each other) and scattered ones: the cluster-by-cluster
    solution costs what one assignment over all points does."""
    from scipy.optimize import linear_sum_assignment

    rng = np.random.default_rng(12)
    for trial in range(20):
        centres = rng.uniform(0, 2000, size=(40, 2))
        X = np.vstack([centres[rng.integers(40, size=150)] + rng.normal(0, 15, (150, 2)),
                       rng.uniform(0, 2000, (50, 2))])
        Y = np.vstack([X[rng.random(len(X)) < 0.7], rng.uniform(0, 2000, (30, 2))])
        Y = Y + rng.normal(0, 6, Y.shape)
        c, p = 20.0, 2.0
        g = gospa(X, Y, c=c, p=p)
        D = np.minimum(np.linalg.norm(X[:, None] - Y[None], axis=-1) ** p, c**p)
        r, col = linear_sum_assignment(D - c**p)
        k = int((D[r, col] < c**p).sum())
        loc = float(D[r, col][D[r, col] < c**p].sum())
        dense = (loc + c**p / 2 * (len(X) + len(Y) - 2 * k)) ** (1 / p)
        assert g.distance == pytest.approx(dense, rel=1e-12), trial
        assert 0 < g.missed < len(X) and g.false > 0


def test_team_metrics():
    est = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 3.0], [1.0, -3.0]])  # mean (1, 0)
    np.testing.assert_allclose(consensus_disagreement(est), [1.0, 1.0, 3.0, 3.0])
    assert max_consensus_disagreement(est[None]) == 3.0
    Y = np.stack([np.eye(3), 2 * np.eye(3)])
    assert average_information_trace(Y) == pytest.approx(4.5)


def test_bearing_fim_example_1_start_and_optimum():
    """Paper 003, Example 1: det F = 4.800 at the start, optimum (½ Σ c²)² = 4.84."""
    F = bearing_fim(EX1_TARGET, EX1_SENSORS, sigma=0.1)
    assert np.linalg.det(F) == pytest.approx(4.800, abs=1e-9)
    ranges = np.linalg.norm(EX1_SENSORS - EX1_TARGET, axis=1)
    c2 = 1.0 / (0.1 * ranges) ** 2
    np.testing.assert_allclose(c2, [0.4, 2.0, 2.0])
    assert max_det_bearing_fim(c2) == pytest.approx(4.84)
    geo = optimal_bearing_geometry(EX1_TARGET, ranges, sigma=0.1)
    assert geo.det_fim == pytest.approx(4.84, abs=1e-9)
    assert np.linalg.det(bearing_fim(EX1_TARGET, geo.positions, 0.1)) == pytest.approx(4.84, abs=1e-9)
    np.testing.assert_allclose(np.linalg.norm(geo.positions - EX1_TARGET, axis=1), ranges)
    # the paper's printed φ = π/2 geometry only reaches the start's value
    theta_printed = np.array([0.0, 0.5 * (np.pi + np.pi / 2), 0.5 * (np.pi - np.pi / 2)])
    assert np.linalg.det(bearing_fim_from_directions(c2, theta_printed)) == pytest.approx(4.800, abs=1e-9)


def test_bearing_fim_grid_search_agrees_with_optimum():
    c2 = np.array([0.4, 2.0, 2.0])
    grid = np.deg2rad(np.arange(0, 360))
    t1, t3 = np.meshgrid(grid, grid, indexing="ij")
    # det F over directions, sensor 2 fixed at 0 rad (common rotations keep det F)
    s = lambda t: np.sin(2 * t)  # noqa: E731
    c = lambda t: np.cos(2 * t)  # noqa: E731
    tot = c2.sum()
    vec_s = c2[0] * s(t1) + c2[1] * s(0.0) + c2[2] * s(t3)
    vec_c = c2[0] * c(t1) + c2[1] * c(0.0) + c2[2] * c(t3)
    det = (tot**2 - vec_s**2 - vec_c**2) / 4.0  # det F = ¼[(Σc²)² − ‖Σ c² (sin 2θ, cos 2θ)‖²]
    assert det.max() == pytest.approx(4.8399, abs=1e-4)
    assert det.max() <= max_det_bearing_fim(c2) + 1e-12
    i, j = np.unravel_index(det.argmax(), det.shape)
    assert np.linalg.det(bearing_fim_from_directions(c2, np.array([grid[i], 0.0, grid[j]]))) == pytest.approx(det.max())


def test_dominant_sensor_bound():
    c2 = np.array([10.0, 1.0, 1.0])
    assert max_det_bearing_fim(c2) == pytest.approx(20.0)
    geo = optimal_bearing_geometry(np.zeros(2), 1.0 / (0.1 * np.sqrt(c2)), sigma=0.1)
    assert geo.det_fim == pytest.approx(20.0)
