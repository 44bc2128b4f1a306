"""Statistical consistency: Monte Carlo average NEES and NIS inside their 95 % χ² bands (matched models, radar)."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.estimation.factory import make_filter
from autonomy.estimation.linalg import psd_sqrt
from autonomy.estimation.measurements import Measurement, RadarModel
from autonomy.estimation.models import ConstantVelocity, Singer
from autonomy.metrics.errors import chi2_band, fraction_inside, nees

N_RUNS, N_STEPS, DT = 50, 100, 0.5
P_SENSOR = np.array([-1500.0, -1000.0, 0.0])
SIGMA = np.array([5.0, 0.004])  # range (m), azimuth (rad): ≈ 7 m cross-range at 1.8 km
KINDS = ["ekf", "ukf", "ckf", "scif"]


def simulate_truth(model, x0, rng):
    F, Q = model.matrices(DT)
    S_Q = psd_sqrt(Q)
    X = np.empty((N_STEPS, len(x0)))
    x = x0
    for k in range(N_STEPS):
        x = F @ x + S_Q @ rng.normal(size=len(x0))
        X[k] = x
    return X


def run_monte_carlo(kind, model, x_init, P0, seed):
    rng = np.random.default_rng(seed)
    R = np.diag(SIGMA**2)
    n = len(x_init)
    nees_all = np.empty((N_RUNS, N_STEPS))
    nis_all = np.empty((N_RUNS, N_STEPS))
    S_P0 = np.linalg.cholesky(P0)
    for r in range(N_RUNS):
        truth = simulate_truth(model, x_init, rng)
        x0_true = x_init
        f = make_filter(kind, model, x0_true + S_P0 @ rng.normal(size=n), P0, t0=0.0)
        radar = RadarModel(model.layout, P_SENSOR, 2)
        for k in range(N_STEPS):
            z = radar.h(truth[k]) + SIGMA * rng.normal(size=2)
            inn = f.update(Measurement(z=z, R=R, t_meas=(k + 1) * DT, p_sensor_W=P_SENSOR), radar)
            nees_all[r, k] = nees(truth[k], f.x, f.P)
            nis_all[r, k] = inn.nis
    return nees_all.mean(axis=0), nis_all.mean(axis=0), n


@pytest.mark.parametrize("kind", KINDS, ids=KINDS)
@pytest.mark.parametrize(
    "model,x_init,P0",
    [
        (ConstantVelocity(q=0.5), np.array([200.0, 8.0, 300.0, -5.0]), np.diag([100.0, 4.0, 100.0, 4.0])),
        (Singer(alpha=0.6, sigma_a=0.66), np.array([200.0, 8.0, 0.0, 300.0, -5.0, 0.0]),
         np.diag([100.0, 4.0, 0.5, 100.0, 4.0, 0.5])),
    ],
    ids=["cv", "singer"],
)
def test_average_nees_and_nis_inside_chi2_band(kind, model, x_init, P0):
    avg_nees, avg_nis, n = run_monte_carlo(kind, model, x_init, P0, seed=7)
    nees_band = chi2_band(dof=n, n_runs=N_RUNS, confidence=0.95)
    nis_band = chi2_band(dof=2, n_runs=N_RUNS, confidence=0.95)
    assert fraction_inside(avg_nees, nees_band) >= 0.90, (avg_nees.min(), avg_nees.max(), nees_band)
    assert fraction_inside(avg_nis, nis_band) >= 0.90, (avg_nis.min(), avg_nis.max(), nis_band)


def test_mismatched_model_fails_the_band():
    """The test has power: a filter with 100× too little process noise is inconsistent on a Singer target."""
    truth_model = Singer(alpha=0.6, sigma_a=0.66)
    x_init = np.array([200.0, 8.0, 0.0, 300.0, -5.0, 0.0])
    P0 = np.diag([100.0, 4.0, 0.5, 100.0, 4.0, 0.5])
    rng = np.random.default_rng(3)
    wrong = Singer(alpha=0.6, sigma_a=0.066)
    R = np.diag(SIGMA**2)
    nees_all = np.empty((20, N_STEPS))
    radar = RadarModel(truth_model.layout, P_SENSOR, 2)
    for r in range(20):
        truth = simulate_truth(truth_model, x_init, rng)
        f = make_filter("ekf", wrong, x_init + np.linalg.cholesky(P0) @ rng.normal(size=6), P0)
        for k in range(N_STEPS):
            z = radar.h(truth[k]) + SIGMA * rng.normal(size=2)
            f.update(Measurement(z=z, R=R, t_meas=(k + 1) * DT, p_sensor_W=P_SENSOR), radar)
            nees_all[r, k] = nees(truth[k], f.x, f.P)
    assert fraction_inside(nees_all.mean(axis=0), chi2_band(dof=6, n_runs=20)) < 0.5
