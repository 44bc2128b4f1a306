"""The batched EKF updates of a scan equal the per-filter updates (to round-off), for radar and position
detections, planar and 3-D radars, mixed time steps, and filters the batch does not take."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from autonomy.estimation.factory import make_filter
from autonomy.estimation.measurements import Measurement, PositionDetectionModel, RadarDetectionModel
from autonomy.estimation.models import ConstantVelocity, Singer
from autonomy.estimation.tracking.batch_update import update_pairs


def _filters(kind, model, n, rng, t0):
    out = []
    for k in range(n):
        x = np.zeros(len(model.layout))
        ix, iy = model.layout.index("x"), model.layout.index("y")
        x[ix], x[iy] = rng.uniform(-500, 500, 2)
        P = np.eye(len(x)) * rng.uniform(4, 50)
        out.append(make_filter(kind, model, x, P, t0[k % len(t0)]))
    return out


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("model", [ConstantVelocity(q=0.5), Singer(alpha=0.6, sigma_a=0.66)])
def test_batched_radar_updates_equal_the_per_filter_ones(dim, model):
    rng = np.random.default_rng(dim)
    fs = _filters("ekf", model, 12, rng, t0=(0.0, 0.25))
    p_s = np.array([30.0, -40.0, 80.0])
    R = np.diag([20.0**2, np.radians(3) ** 2, np.radians(2) ** 2][:dim])
    dets = [Measurement(z=np.r_[rng.uniform(100, 600), rng.uniform(-np.pi, np.pi), -0.2][:dim], R=R, t_meas=0.5,
                        p_sensor_W=p_s, model=RadarDetectionModel(dim=dim)) for _ in fs]
    ref = copy.deepcopy(fs)
    for f, d in zip(ref, dets, strict=True):
        f.update(d)
    update_pairs(list(zip(fs, dets, strict=True)), model.layout, 0.0)
    for a, b in zip(fs, ref, strict=True):
        assert a.t == b.t
        np.testing.assert_allclose(a.x, b.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(a.P, b.P, rtol=1e-9, atol=1e-9)


def test_mixed_sensors_and_filters_fall_back_exactly():
    rng = np.random.default_rng(7)
    model = ConstantVelocity(q=1.0)
    fs = _filters("ekf", model, 5, rng, t0=(0.0,)) + _filters("ukf", model, 3, rng, t0=(0.0,))
    dets = [Measurement(z=rng.uniform(-500, 500, 2), R=np.eye(2) * 9.0, t_meas=1.0, p_sensor_W=np.zeros(3),
                        model=PositionDetectionModel(dim=2)) for _ in fs]
    dets[1] = Measurement(z=np.array([300.0, 0.5]), R=np.diag([100.0, 0.01]), t_meas=1.0,
                          p_sensor_W=np.array([5.0, 5.0, 50.0]), model=RadarDetectionModel(dim=2))
    ref = copy.deepcopy(fs)
    for f, d in zip(ref, dets, strict=True):
        f.update(d)
    update_pairs(list(zip(fs, dets, strict=True)), model.layout, 0.0)
    for a, b in zip(fs, ref, strict=True):
        np.testing.assert_allclose(a.x, b.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(a.P, b.P, rtol=1e-9, atol=1e-9)
