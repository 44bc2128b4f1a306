"""The move–stop IMM: the stopped model's matrices, the switching chain's closed form, and a radar-tracked car that
drives, stops and drives again, against the moving model's EKF alone."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.estimation.factory import make_filter
from autonomy.estimation.imm import MoveStopSwitching, move_stop_imm
from autonomy.estimation.measurements import Measurement, RadarModel
from autonomy.estimation.models import CV_2D, SINGER, ConstantVelocity, Singer, Stopped
from autonomy.estimation.tracker import ConfiguredFilters, TrackerConfig, make_motion_model

DT = 0.5
SIGMA_RANGE, SIGMA_AZ = 20.0, np.radians(7.0)  # the flagship traffic world's radar


def test_stopped_model_holds_the_position_and_zeroes_every_derivative():
    cv = Stopped(layout_of=CV_2D, q=0.04, sigma_rate=0.1)
    F, Q = cv.matrices(2.0)
    np.testing.assert_array_equal(F, np.diag([1.0, 0.0, 1.0, 0.0]))
    np.testing.assert_allclose(Q, np.diag([0.08, 0.01, 0.08, 0.01]), rtol=1e-15)
    sg = Stopped(layout_of=SINGER, q=0.0)
    F, Q = sg.matrices(0.5)
    np.testing.assert_array_equal(F, np.diag([1.0, 0, 0, 1.0, 0, 0]))
    np.testing.assert_allclose(np.diag(Q), [0.0, 0.0025, 0.0025, 0.0, 0.0025, 0.0025], rtol=1e-15)
    x = np.array([3.0, 9.0, 1.0, -4.0, 2.0, -1.0])
    np.testing.assert_array_equal(sg.propagate(x, 0.5), [3.0, 0, 0, -4.0, 0, 0])
    assert sg.layout == SINGER
    with pytest.raises(ValueError, match="layout_of"):
        Stopped(layout_of=("x", "vx", "y", "vy", "omega"))
    with pytest.raises(ValueError, match="sigma_rate"):
        Stopped(layout_of=CV_2D, sigma_rate=0.0)


def test_switching_is_the_two_state_markov_chain():
    sw = MoveStopSwitching(mean_moving_s=30.0, mean_stopped_s=10.0)
    a, b = 1 / 30, 1 / 10
    for dt in (0.01, 0.5, 3.0, 40.0):
        Pi = sw(dt)
        np.testing.assert_allclose(Pi.sum(axis=1), 1.0, rtol=0, atol=1e-15)
        e = (1 - np.exp(-(a + b) * dt)) / (a + b)
        np.testing.assert_allclose(Pi, [[1 - a * e, a * e], [b * e, 1 - b * e]], rtol=1e-12)  # e by expm1 there
    np.testing.assert_allclose(sw(0.3) @ sw(1.2), sw(1.5), rtol=1e-13)  # Chapman–Kolmogorov
    np.testing.assert_allclose(sw(1e-6)[0, 1] / 1e-6, a, rtol=1e-5)  # the rate out of "moving"
    np.testing.assert_allclose(sw.stationary, [0.75, 0.25], rtol=1e-15)
    np.testing.assert_allclose(sw.stationary @ sw(2.0), sw.stationary, rtol=1e-14)
    np.testing.assert_allclose(sw(1e4), np.tile(sw.stationary, (2, 1)), rtol=1e-12)
    with pytest.raises(ValueError, match="mean_stopped_s"):
        MoveStopSwitching(30.0, 0.0)


def _drive_stop_drive() -> tuple[np.ndarray, np.ndarray]:
    """A car on x: 5 s accelerating to 10 m/s, 15 s at speed, 5 s braking, 30 s stopped, 5 s accelerating, 15 s at
    speed; Singer-layout states every DT and whether the car is stopped."""
    segments = [(5, 2.0, False), (15, 0.0, False), (5, -2.0, False), (30, 0.0, True), (5, 2.0, False),
                (15, 0.0, False)]
    x, states, stopped = np.zeros(6), [], []
    for duration, accel, stop in segments:
        for _ in range(int(duration / DT)):
            x[2] = accel
            x[0] += x[1] * DT + 0.5 * accel * DT * DT
            x[1] += accel * DT
            states.append(x.copy())
            stopped.append(stop)
    return np.array(states), np.array(stopped)


def _radar(k: int) -> np.ndarray:
    """A UAV orbiting (100, 0) at 160 m and 60 m height, 0.08 rad/s."""
    th = 0.08 * k * DT
    return np.array([100.0 + 160.0 * np.cos(th), 160.0 * np.sin(th), 60.0])


def test_a_stopped_car_is_held_by_the_stop_mode_and_a_moving_one_by_the_moving_model():
    """20 seeds of a radar-only track (range σ 20 m, azimuth σ 7°, 2 Hz): while the car stands, the moving model's EKF
    turns the radar's noise into velocity and wanders (mean error ≈ 14 m); the IMM's stop mode averages the returns
    (≈ 8 m, measured 0.55 of the EKF's), and it costs nothing while the car drives (ratio 1.02, measured)."""
    truth, stopped = _drive_stop_drive()
    t = (np.arange(len(truth)) + 1) * DT
    model = Singer(alpha=0.6, sigma_a=2.0, dim=2)
    P0 = np.diag([100.0, 25.0, 4.0, 100.0, 25.0, 4.0])
    err_ekf, err_imm, mu_stop = [], [], []
    for seed in range(20):
        rng = np.random.default_rng(seed)
        x0 = np.zeros(6)
        x0[[0, 3]] = rng.normal(0.0, 10.0, 2)
        ekf = make_filter("ekf", model, x0, P0, 0.0)
        imm = move_stop_imm(x0, P0, 0.0, moving=model, mean_moving_s=30.0, mean_stopped_s=10.0, stopped_q=0.01)
        e1, e2, mu = [], [], []
        for k, x in enumerate(truth):
            p = _radar(k + 1)
            z = RadarModel(SINGER, p, 2).h(x) + rng.normal(size=2) * [SIGMA_RANGE, SIGMA_AZ]
            m = Measurement(z=z, R=np.diag([SIGMA_RANGE**2, SIGMA_AZ**2]), t_meas=(k + 1) * DT, p_sensor_W=p)
            ekf.update(m)
            imm.update(m)
            e1.append(np.hypot(*(ekf.x - x)[[0, 3]]))
            e2.append(np.hypot(*(imm.x - x)[[0, 3]]))
            mu.append(imm.mu[1])
        err_ekf.append(e1)
        err_imm.append(e2)
        mu_stop.append(mu)
    E1, E2, MU = np.array(err_ekf), np.array(err_imm), np.array(mu_stop)
    standing = stopped & (t > 30.0)  # 5 s after the car stopped, to its restart
    driving = ((t > 7.0) & (t <= 20.0)) | (t > 62.0)
    assert E2[:, standing].mean() < 0.7 * E1[:, standing].mean()
    assert E2[:, driving].mean() < 1.15 * E1[:, driving].mean()
    assert MU[:, standing].mean() - MU[:, driving].mean() > 0.3  # measured 0.61 against 0.11


def test_the_tracker_builds_the_move_stop_imm_on_its_model():
    cfg = TrackerConfig(filter="imm", model="singer", imm_modes="move_stop", ekf_iterations=3, singer_alpha=0.6,
                        imm_mean_moving_s=20.0, imm_mean_stopped_s=5.0)
    f = ConfiguredFilters(cfg, make_motion_model(cfg))(np.zeros(6), np.eye(6), 0.0)
    assert [type(m.model).__name__ for m in f.filters] == ["Singer", "Stopped"]
    assert all(m.iterations == 3 for m in f.filters)
    np.testing.assert_allclose(f.mu, [0.8, 0.2], rtol=1e-15)
    with pytest.raises(ValueError, match="cv_ct"):
        TrackerConfig(filter="imm", model="singer")
    with pytest.raises(ValueError, match="imm_modes"):
        TrackerConfig(filter="imm", imm_modes="stop")
    cv = ConfiguredFilters(TrackerConfig(filter="imm", imm_modes="move_stop"), ConstantVelocity(q=1.0))
    assert cv(np.zeros(4), np.eye(4), 0.0).filters[1].model.layout == CV_2D
