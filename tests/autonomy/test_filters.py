"""Filters (EKF, UKF, CKF, SCIF) and measurement models: exact Kalman answers, Jacobians, angle wrapping, SPD."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autonomy.estimation.base import GaussianFilter
from autonomy.estimation.factory import make_filter
from autonomy.estimation.measurements import (
    BearingModel,
    Measurement,
    MeasurementLike,
    NadirRadarModel,
    PositionModel,
    RadarModel,
    StackedMeasurement,
    measurement_model,
    wrap_angle,
)
from autonomy.estimation.models import ConstantVelocity, CoordinatedTurnEstimated, Singer
from autonomy.estimation.scif import SCIF

KINDS = ["ekf", "ukf", "ckf", "scif"]


def kalman_reference(F, Q, H, R, x, P, z):
    """Textbook Kalman predict + update (covariance form)."""
    x = F @ x
    P = F @ P @ F.T + Q
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    return x + K @ (z - H @ x), (np.eye(len(x)) - K @ H) @ P


@pytest.mark.parametrize("kind", KINDS, ids=KINDS)
@pytest.mark.parametrize("model", [ConstantVelocity(q=0.5), Singer(alpha=0.6, sigma_a=0.66),
                                   ConstantVelocity(q=0.2, dim=3)], ids=["cv", "singer", "cv3d"])
def test_filters_equal_kalman_filter_on_linear_model(kind, model):
    rng = np.random.default_rng(1)
    n = len(model.layout)
    x = rng.normal(size=n)
    P = np.diag(rng.uniform(1.0, 5.0, size=n))
    f = make_filter(kind, model, x, P, t0=0.0)
    t = 0.0
    m = 3 if "z" in model.layout else 2
    H = PositionModel(model.layout, m).H
    R = np.diag(rng.uniform(0.5, 2.0, size=m))
    for _ in range(25):
        dt = float(rng.uniform(0.05, 0.8))  # asynchronous time stamps
        t += dt
        z = rng.normal(size=m) * 3.0
        F, Q = model.matrices(dt)
        x, P = kalman_reference(F, Q, H, R, x, P, z)
        f.update(Measurement(z=z, R=R, t_meas=t, kind="box"))
        assert f.t == pytest.approx(t)
    np.testing.assert_allclose(f.x, x, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(f.P, P, rtol=1e-8, atol=1e-10)


LAYOUTS = [("x", "vx", "y", "vy"), ("x", "vx", "ax", "y", "vy", "ay"), ("x", "vx", "y", "vy", "z", "vz")]


def _state(layout, rng):
    x = rng.normal(size=len(layout)) * 3.0
    for name, v in zip(("x", "y", "z"), (120.0, -80.0, 5.0), strict=True):
        if name in layout:
            x[layout.index(name)] = v + rng.normal()
    return x


@pytest.mark.parametrize("layout", LAYOUTS, ids=["cv2", "singer", "cv3"])
@pytest.mark.parametrize(
    "make",
    [
        lambda L: RadarModel(L, np.array([10.0, 20.0, 100.0]), 2),
        lambda L: RadarModel(L, np.array([10.0, 20.0, 100.0]), 3),
        lambda L: RadarModel(L, np.array([10.0, 20.0, 100.0]), 4, v_sensor_W=np.array([3.0, -1.0, 0.5])),
        lambda L: NadirRadarModel(L, np.array([10.0, 20.0, 100.0])),
        lambda L: BearingModel(L, np.array([10.0, 20.0, 30.0]), 1),
        lambda L: BearingModel(L, np.array([10.0, 20.0, 30.0]), 2),
        lambda L: PositionModel(L, 2),
    ],
    ids=["radar2", "radar3", "radar_rr", "nadir", "bearing", "bearing_el", "box"],
)
def test_measurement_jacobians_match_finite_differences(layout, make):
    rng = np.random.default_rng(2)
    mm = make(layout)
    x = _state(layout, rng)
    eps = 1e-6
    J = np.column_stack([(mm.h(x + eps * e) - mm.h(x - eps * e)) / (2 * eps) for e in np.eye(len(layout))])
    np.testing.assert_allclose(mm.jacobian(x), J, rtol=1e-6, atol=1e-8)
    z_lin, H_lin = mm.linearise(x)
    np.testing.assert_allclose(z_lin, mm.h(x), rtol=1e-14)
    np.testing.assert_allclose(H_lin, mm.jacobian(x), rtol=1e-14)
    # vectorised evaluation over columns agrees with single evaluation
    X = np.column_stack([x, x + 1.0])
    np.testing.assert_allclose(mm.h(X)[:, 1], mm.h(x + 1.0), atol=1e-12)


def test_radar_geometry_closed_form():
    layout = ("x", "vx", "y", "vy")
    p_s = np.array([0.0, 0.0, 100.0])
    x = np.array([100.0, 3.0, 0.0, 4.0])  # target on the ground 100 m east, 100 m below the sensor
    z = RadarModel(layout, p_s, 4).h(x)
    np.testing.assert_allclose(z, [100 * np.sqrt(2), 0.0, -np.pi / 4, 3.0 / np.sqrt(2)], atol=1e-12)
    np.testing.assert_allclose(NadirRadarModel(layout, p_s).h(x)[2], np.pi / 4)
    x_north = np.array([0.0, 0.0, 50.0, 0.0])
    assert BearingModel(layout, p_s, 1).h(x_north)[0] == pytest.approx(np.pi / 2)


@pytest.mark.parametrize("kind", KINDS, ids=KINDS)
def test_azimuth_residual_wrapped_across_pi(kind):
    """Predicted azimuth just below +π, measured just above −π: a 0.02 rad correction, not a 2π one."""
    model = ConstantVelocity(q=0.01)
    x0 = np.array([-100.0, 0.0, 1.0, 0.0])  # azimuth from the origin ≈ π − 0.01
    P0 = np.diag([1.0, 0.1, 1.0, 0.1])
    f = make_filter(kind, model, x0, P0)
    z = np.array([wrap_angle(np.pi + 0.01)])
    inn = f.update(Measurement(z=z, R=np.array([[1e-4]]), t_meas=0.0, kind="bearing", p_sensor_W=np.zeros(3)))
    pred = np.arctan2(1.0, -100.0)
    assert inn.nu[0] == pytest.approx(wrap_angle(z[0] - pred), abs=1e-6)
    assert abs(inn.nu[0]) < 0.03
    assert abs(f.x[0] - x0[0]) < 0.5 and -2.0 < f.x[2] < 0.5  # moved across the −x axis, by about 2 m


def test_stacked_measurement_equals_sequential_updates_on_linear_problem():
    model = ConstantVelocity(q=0.3)
    x0, P0 = np.zeros(4), np.eye(4) * 10.0
    a, b = make_filter("ekf", model, x0, P0), make_filter("ekf", model, x0, P0)
    m1 = Measurement(z=np.array([1.0, 2.0]), R=np.eye(2), t_meas=0.5, kind="box", sensor_id=1)
    m2 = Measurement(z=np.array([1.5, 1.0]), R=np.diag([2.0, 0.5]), t_meas=0.5, kind="box", sensor_id=2)
    a.update(StackedMeasurement(parts=(m1, m2)))
    b.update(m1)
    b.update(m2)
    np.testing.assert_allclose(a.x, b.x, atol=1e-12)
    np.testing.assert_allclose(a.P, b.P, atol=1e-12)


def test_scif_information_state_is_consistent():
    model = Singer(alpha=0.6, sigma_a=0.66, discretisation="euler")
    f = SCIF(model, np.array([100.0, 2.0, 0.0, 50.0, 1.0, 0.0]), np.diag([50.0, 5.0, 1.0, 50.0, 5.0, 1.0]))
    f.update(Measurement(z=np.array([150.0, 0.5, -0.7]), R=np.diag([1.0, 1e-3, 1e-3]), t_meas=0.5,
                         p_sensor_W=np.array([0.0, 0.0, 100.0])))
    info = f.information_state
    np.testing.assert_allclose(np.linalg.inv(info.Y), f.P, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(info.Y @ f.x, info.h, rtol=1e-9, atol=1e-9)


def test_time_handling():
    f = make_filter("ekf", ConstantVelocity(q=1.0), np.array([0.0, 1.0, 0.0, 0.0]), np.eye(4), t0=2.0)
    f.predict(2.0)
    np.testing.assert_allclose(f.x, [0.0, 1.0, 0.0, 0.0])
    f.predict(3.5)
    assert f.t == 3.5 and f.x[0] == pytest.approx(1.5)
    with pytest.raises(ValueError, match="backwards"):
        f.update(Measurement(z=np.zeros(2), R=np.eye(2), t_meas=3.0, kind="box"))


def test_sensing_detection_satisfies_the_measurement_protocol():
    from autonomy.sensing.measurement import Detection

    det = Detection(z=np.array([141.0, 0.01, -0.78]), R=np.diag([1.0, 1e-4, 1e-4]), t_meas=0.5, t_arrival=0.6,
                    sensor_id="uav1/radar", p_sensor_W=np.array([0.0, 0.0, 100.0]), kind="radar")
    assert isinstance(det, MeasurementLike)
    f = make_filter("ekf", ConstantVelocity(q=0.1), np.array([100.0, 0.0, 0.0, 0.0]), np.eye(4) * 25.0)
    inn = f.update(det)
    assert f.t == 0.5 and inn.nu.shape == (3,)
    np.testing.assert_allclose(inn.nu[0], 141.0 - 100.0 * np.sqrt(2), rtol=1e-3)


def test_measurement_validation_and_dispatch():
    with pytest.raises(ValueError, match="R must have shape"):
        Measurement(z=np.zeros(3), R=np.eye(2), t_meas=0.0)
    with pytest.raises(ValueError, match="kind"):
        Measurement(z=np.zeros(2), R=np.eye(2), t_meas=0.0, kind="lidar")
    with pytest.raises(ValueError, match="t_arrival"):
        Measurement(z=np.zeros(2), R=np.eye(2), t_meas=1.0, t_arrival=0.5)
    with pytest.raises(ValueError, match="kind must be one of"):
        make_filter("pf", ConstantVelocity(q=1.0), np.zeros(4), np.eye(4))
    layout = ("x", "vx", "y", "vy")
    for kind, m, cls in [("radar", 3, RadarModel), ("bearing", 1, BearingModel), ("camera", 2, BearingModel),
                         ("box", 2, PositionModel)]:
        meas = Measurement(z=np.ones(m), R=np.eye(m), t_meas=0.0, kind=kind, p_sensor_W=np.array([0.0, 0.0, 50.0]))
        assert isinstance(measurement_model(meas, layout), cls)


@settings(max_examples=12, deadline=None, derandomize=True)
@given(kind=st.sampled_from(KINDS), seed=st.integers(0, 2**32 - 1), sigma_r=st.floats(0.1, 50.0),
       sigma_a=st.floats(1e-4, 0.2), dt=st.floats(0.01, 2.0), nonlinear=st.booleans())
def test_covariance_stays_symmetric_positive_definite(kind, seed, sigma_r, sigma_a, dt, nonlinear):
    rng = np.random.default_rng(seed)
    if nonlinear:
        model = CoordinatedTurnEstimated(q=0.5, q_omega=1e-3)
        x = np.array([300.0, 10.0, -200.0, 5.0, 0.1])
    else:
        model = Singer(alpha=0.6, sigma_a=0.66)
        x = np.array([300.0, 10.0, 0.0, -200.0, 5.0, 0.0])
    P = np.diag(rng.uniform(0.1, 100.0, size=len(x)))
    f: GaussianFilter = make_filter(kind, model, x, P)
    p_s = np.array([0.0, 0.0, 120.0])
    R = np.diag([sigma_r**2, sigma_a**2, sigma_a**2])
    for k in range(15):
        z = RadarModel(model.layout, p_s, 3).h(f.x) + rng.normal(size=3) * [sigma_r, sigma_a, sigma_a]
        f.update(Measurement(z=z, R=R, t_meas=(k + 1) * dt, p_sensor_W=p_s))
        P = f.P
        np.testing.assert_allclose(P, P.T, rtol=1e-9, atol=1e-9)
        assert np.linalg.eigvalsh(P).min() > 0.0
