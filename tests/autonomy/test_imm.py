"""IMM: reduction to one filter, combination formulas, mode switching after a manoeuvre, paper 003's centralised EKF."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.estimation.factory import make_filter
from autonomy.estimation.imm import IMM
from autonomy.estimation.measurements import Measurement, RadarModel, StackedMeasurement
from autonomy.estimation.models import ConstantVelocity, CoordinatedTurn, CoordinatedTurnEstimated
from autonomy.metrics.errors import euclidean_errors

DT = 0.25
P_SENSOR = np.array([-300.0, -200.0, 60.0])
SIGMA = np.array([2.0, 0.005])


def manoeuvre_truth(omega=0.3, speed=12.0, t_cv=20.0, t_turn=15.0, t_cv2=10.0):
    """CV for t_cv s, coordinated turn at omega for t_turn s, CV again; state (x, vx, y, vy) every DT."""
    x = np.array([0.0, speed, 0.0, 0.0])
    segments = [(t_cv, 0.0), (t_turn, omega), (t_cv2, 0.0)]
    states, modes = [], []
    for duration, w in segments:
        F = CoordinatedTurn(omega=w, q=0.0).matrices(DT)[0]
        for _ in range(int(round(duration / DT))):
            x = F @ x
            states.append(x.copy())
            modes.append(w)
    return np.array(states), np.array(modes)


def radar_measurements(truth, rng, layout=("x", "vx", "y", "vy")):
    radar = RadarModel(layout, P_SENSOR, 3)
    R = np.diag([SIGMA[0] ** 2, SIGMA[1] ** 2, SIGMA[1] ** 2])
    out = []
    for k, x in enumerate(truth):
        z = radar.h(x) + rng.normal(size=3) * [SIGMA[0], SIGMA[1], SIGMA[1]]
        out.append(Measurement(z=z, R=R, t_meas=(k + 1) * DT, p_sensor_W=P_SENSOR))
    return out


def three_mode_imm(kind="ekf"):
    x0, P0 = np.array([0.0, 12.0, 0.0, 0.0]), np.diag([25.0, 4.0, 25.0, 4.0])
    models = [ConstantVelocity(q=0.05), CoordinatedTurn(omega=0.3, q=0.05), CoordinatedTurn(omega=-0.3, q=0.05)]
    Pi = np.full((3, 3), 0.025) + np.eye(3) * 0.925
    return IMM([make_filter(kind, m, x0, P0) for m in models], Pi)


@pytest.mark.parametrize("kind", ["ekf", "ukf", "ckf", "scif"])
def test_imm_with_one_model_is_the_filter(kind):
    rng = np.random.default_rng(0)
    truth, _ = manoeuvre_truth()
    meas = radar_measurements(truth[:60], rng)
    model = ConstantVelocity(q=0.5)
    x0, P0 = np.array([0.0, 12.0, 0.0, 0.0]), np.diag([25.0, 4.0, 25.0, 4.0])
    single = make_filter(kind, model, x0, P0)
    imm = IMM([make_filter(kind, model, x0, P0)], np.ones((1, 1)))
    for m in meas:
        single.update(m)
        imm.update(m)
    np.testing.assert_allclose(imm.x, single.x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(imm.P, single.P, rtol=1e-12, atol=1e-12)
    assert imm.mu == pytest.approx([1.0])


def test_combination_formulas_and_zero_padding():
    cv = make_filter("ekf", ConstantVelocity(q=1.0), np.array([1.0, 2.0, 3.0, 4.0]), np.eye(4))
    ct = make_filter("ekf", CoordinatedTurnEstimated(q=1.0, q_omega=0.01), np.array([3.0, 2.0, 1.0, 4.0, 0.2]),
                     np.eye(5) * 2.0)
    imm = IMM([cv, ct], np.array([[0.9, 0.1], [0.1, 0.9]]), mu0=np.array([0.25, 0.75]))
    assert imm.layout == ("x", "vx", "y", "vy", "omega")
    x1, x2 = np.array([1.0, 2.0, 3.0, 4.0, 0.0]), np.array([3.0, 2.0, 1.0, 4.0, 0.2])
    P1 = np.diag([1.0, 1.0, 1.0, 1.0, 0.0])
    P2 = np.eye(5) * 2.0
    x = 0.25 * x1 + 0.75 * x2
    P = 0.25 * (P1 + np.outer(x1 - x, x1 - x)) + 0.75 * (P2 + np.outer(x2 - x, x2 - x))
    np.testing.assert_allclose(imm.x, x)
    np.testing.assert_allclose(imm.P, P)


def test_mixing_weights_follow_the_transition_matrix():
    """After a predict, the mode probabilities are c̄ = μ Π and each mode restarts from the mixed moments."""
    a = make_filter("ekf", ConstantVelocity(q=0.0), np.array([0.0, 0.0, 0.0, 0.0]), np.eye(4))
    b = make_filter("ekf", ConstantVelocity(q=0.0), np.array([4.0, 0.0, 0.0, 0.0]), np.eye(4))
    Pi = np.array([[0.8, 0.2], [0.4, 0.6]])
    imm = IMM([a, b], Pi, mu0=np.array([0.5, 0.5]))
    imm.predict(1e-3)
    cbar = np.array([0.5 * 0.8 + 0.5 * 0.4, 0.5 * 0.2 + 0.5 * 0.6])
    np.testing.assert_allclose(imm.mu, cbar)
    w_a = np.array([0.5 * 0.8, 0.5 * 0.4]) / cbar[0]  # μ_{i|a}
    assert a.x[0] == pytest.approx(w_a[1] * 4.0)
    assert a.P[0, 0] == pytest.approx(1.0 + w_a[0] * w_a[1] * 16.0, rel=1e-6)


def test_mode_probabilities_switch_after_manoeuvre():
    rng = np.random.default_rng(5)
    truth, modes = manoeuvre_truth()
    imm = three_mode_imm()
    mu = []
    for m in radar_measurements(truth, rng):
        imm.update(m)
        mu.append(imm.mu.copy())
    mu = np.array(mu)
    turn = np.flatnonzero(modes > 0)
    cv1 = np.flatnonzero(modes == 0)
    cv1 = cv1[cv1 < turn[0]]
    settle = 20  # 5 s to recognise a manoeuvre
    after = np.arange(turn[-1] + 1 + settle, len(modes))
    for segment, mode in [(cv1[settle:], 0), (turn[settle:], 1), (after, 0)]:
        assert np.mean(mu[segment].argmax(axis=1) == mode) >= 0.9  # the right model is the most probable
        assert mu[segment, mode].mean() > 0.6
    assert mu[turn[settle:], 2].mean() < 0.15  # the opposite turn is ruled out
    assert mu[turn[:4], 1].mean() < 0.5  # the switch happens after the manoeuvre starts, not before


def test_imm_beats_cv_filter_during_turn_with_mixed_layouts():
    """CV (4 states) + CT with estimated turn rate (5 states): mixing across layouts works and helps in the turn."""
    rng = np.random.default_rng(11)
    truth, modes = manoeuvre_truth(omega=0.35)
    x0, P0 = np.array([0.0, 12.0, 0.0, 0.0]), np.diag([25.0, 4.0, 25.0, 4.0])
    cv = make_filter("ekf", ConstantVelocity(q=0.05), x0, P0)
    imm = IMM([make_filter("ekf", ConstantVelocity(q=0.05), x0, P0),
               make_filter("ukf", CoordinatedTurnEstimated(q=0.05, q_omega=0.01), np.append(x0, 0.0),
                           np.diag([25.0, 4.0, 25.0, 4.0, 0.1]))],
              np.array([[0.95, 0.05], [0.05, 0.95]]))
    err_cv, err_imm, omega = [], [], []
    for m, xt in zip(radar_measurements(truth, rng), truth, strict=True):
        cv.update(m)
        imm.update(m)
        err_cv.append(euclidean_errors(xt[[0, 2]], cv.x[[0, 2]]))
        err_imm.append(euclidean_errors(xt[[0, 2]], imm.x[[0, 2]]))
        omega.append(imm.filters[1].x[4])
    turn = np.flatnonzero(modes > 0)[20:]
    assert np.mean(np.array(err_imm)[turn]) < 0.7 * np.mean(np.array(err_cv)[turn])
    assert np.mean(np.array(omega)[turn]) == pytest.approx(0.35, abs=0.05)
    assert np.mean(imm.mu) == pytest.approx(0.5)  # probabilities stay normalised (two modes)


def test_centralised_augmented_measurement_imm_bearings_only():
    """Paper 003: three bearing sensors stacked into one measurement for an IMM of EKFs tracks a turning car."""
    rng = np.random.default_rng(2)
    truth, modes = manoeuvre_truth(omega=0.35, t_cv=10.0, t_turn=9.0, t_cv2=6.0)
    sensors = [np.array([-60.0, 80.0, 0.0]), np.array([100.0, -60.0, 0.0]), np.array([200.0, 120.0, 0.0])]
    sigma = 0.01
    imm = three_mode_imm("ekf")
    errors = []
    for k, xt in enumerate(truth):
        parts = []
        for i, p in enumerate(sensors):
            az = np.arctan2(xt[2] - p[1], xt[0] - p[0]) + sigma * rng.normal()
            parts.append(Measurement(z=np.array([az]), R=np.array([[sigma**2]]), t_meas=(k + 1) * DT,
                                     kind="bearing", sensor_id=i, p_sensor_W=p))
        inn = imm.update(StackedMeasurement(parts=tuple(parts)))
        assert inn.nu.shape == (3,)
        errors.append(euclidean_errors(xt[[0, 2]], imm.x[[0, 2]]))
    errors = np.array(errors)
    assert errors[20:].mean() < 2.5
    assert errors[-1] < 3.0


def test_transition_validation():
    f = make_filter("ekf", ConstantVelocity(q=1.0), np.zeros(4), np.eye(4))
    with pytest.raises(ValueError, match="transition"):
        IMM([f], np.array([[0.5]]))
    with pytest.raises(ValueError, match="mu0"):
        IMM([f], np.ones((1, 1)), mu0=np.array([0.3]))


def test_batched_imm_equals_generic_imm():
    from autonomy.estimation.imm_batched import BatchedEKFIMM

    rng = np.random.default_rng(9)
    truth, _ = manoeuvre_truth(omega=0.3, t_cv=8.0, t_turn=8.0, t_cv2=4.0)
    x0, P0 = np.array([0.0, 12.0, 0.0, 0.0]), np.diag([25.0, 4.0, 25.0, 4.0])
    models = [ConstantVelocity(q=0.05), CoordinatedTurn(omega=0.3, q=0.05), CoordinatedTurn(omega=-0.3, q=0.05)]
    Pi = np.full((3, 3), 0.025) + np.eye(3) * 0.925
    generic = IMM([make_filter("ekf", m, x0, P0) for m in models], Pi)
    batched = BatchedEKFIMM(models, x0, P0, Pi)
    for m in radar_measurements(truth, rng):
        a, b = generic.update(m), batched.update(m)
        np.testing.assert_allclose(b.nu, a.nu, atol=1e-9)
    np.testing.assert_allclose(batched.x, generic.x, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(batched.P, generic.P, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(batched.mu, generic.mu, atol=1e-9)
    assert [i.nis for i in batched.last_innovations] == pytest.approx([i.nis for i in generic.last_innovations])
    with pytest.raises(ValueError, match="share one layout"):
        BatchedEKFIMM([ConstantVelocity(q=1.0), ConstantVelocity(q=1.0, dim=3)], np.zeros(4), np.eye(4), np.eye(2))
