"""The iterated EKF update: the plain EKF on linear measurements, the posterior's mode on a curved one."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from autonomy.estimation.factory import make_filter
from autonomy.estimation.measurements import Measurement, measurement_model
from autonomy.estimation.models import ConstantVelocity
from autonomy.estimation.tracker import ConfiguredFilters, TrackerConfig

CAMERA = np.array([0.0, 0.0, 60.0])  # a camera 60 m above the ground


def _bearing(p_target: np.ndarray, sigma: float) -> Measurement:
    d = np.array([p_target[0], p_target[1], 0.0]) - CAMERA
    z = np.array([np.arctan2(d[1], d[0]), np.arctan2(d[2], np.hypot(d[0], d[1]))])
    return Measurement(z=z, R=np.eye(2) * sigma**2, t_meas=0.0, kind="bearing", p_sensor_W=CAMERA)


def test_iterations_change_nothing_on_a_linear_measurement():
    model = ConstantVelocity(q=0.3)
    x0, P0 = np.array([1.0, 2.0, -1.0, 0.5]), np.diag([30.0, 4.0, 20.0, 4.0])
    plain, iterated = make_filter("ekf", model, x0, P0), make_filter("ekf", model, x0, P0, iterations=5)
    m = Measurement(z=np.array([10.0, -4.0]), R=np.eye(2) * 2.0, t_meas=0.0, kind="box")
    a, b = plain.update(m), iterated.update(m)
    np.testing.assert_allclose(iterated.x, plain.x, atol=1e-12)
    np.testing.assert_allclose(iterated.P, plain.P, atol=1e-12)
    np.testing.assert_allclose(b.nu, a.nu, atol=1e-12)


def test_iterated_update_finds_the_posterior_mode_of_a_close_bearing():
    """A car 90 m out seen from 60 m up, the prior 30 m short of it (σ 30 m): one linearisation lands metres off
    with a covariance of centimetres; the iterations reach the maximum a posteriori, found here by scipy."""
    model = ConstantVelocity(q=0.3)
    layout = model.layout
    ix, iy = layout.index("x"), layout.index("y")
    x0 = np.zeros(4)
    x0[ix], x0[iy] = 60.0, 0.0
    P0 = np.eye(4) * 4.0
    P0[ix, ix] = P0[iy, iy] = 30.0**2
    truth = np.array([90.0, 10.0])
    meas = _bearing(truth, sigma=0.002)
    mm = measurement_model(meas, layout, 0.0)

    def neg_log_posterior(x: np.ndarray) -> float:
        r = mm.residual(meas.z, mm.h(x))
        d = x - x0
        return 0.5 * (r @ np.linalg.solve(meas.R, r) + d @ np.linalg.solve(P0, d))

    mode = minimize(neg_log_posterior, x0, method="BFGS", options={"gtol": 1e-10}).x
    plain, iterated = make_filter("ekf", model, x0, P0), make_filter("ekf", model, x0, P0, iterations=20)
    plain.update(meas)
    iterated.update(meas)
    pos = [ix, iy]
    assert np.linalg.norm(iterated.x[pos] - mode[pos]) < 0.05
    assert np.linalg.norm(plain.x[pos] - mode[pos]) > 2.0  # what the iterations are for
    assert np.linalg.norm(iterated.x[pos] - truth) < 1.0
    assert np.all(np.linalg.eigvalsh(iterated.P) > 0)


def test_iterations_validated_and_configured():
    with pytest.raises(ValueError, match="iterations"):
        make_filter("ekf", ConstantVelocity(q=0.3), np.zeros(4), np.eye(4), iterations=0)
    with pytest.raises(ValueError, match="ekf_iterations"):
        TrackerConfig(ekf_iterations=0)
    cfg = TrackerConfig(ekf_iterations=4)
    f = ConfiguredFilters(cfg, ConstantVelocity(q=cfg.q))(np.zeros(4), np.eye(4), 0.0)
    assert f.iterations == 4
