"""Bearings-only sensor: layout, noise statistics, wrapping, occlusion, detection probability."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from autonomy.estimation.measurements import BearingDetectionModel
from autonomy.sensing.bearing import BearingConfig, BearingSensor
from autonomy.sensing.fake_scene import FakeScene
from autonomy.sensing.fov import FieldOfRegard
from autonomy.sensing.measurement import wrap_angle
from autonomy.sensing.scene import SensorPose, TargetTruth
from worlds.geometry import Building

POSE = SensorPose(p_W=[10.0, -20.0, 120.0])


def targets(points) -> TargetTruth:
    pts = np.asarray(points, dtype=float)
    m = len(pts)
    return TargetTruth(ids=np.arange(m) + 10, p_W=pts, v_W=np.zeros((m, 3)), kind=("car",) * m, yaw=np.zeros(m))


def test_azimuth_only_layout_and_true_values():
    sensor = BearingSensor(BearingConfig(sigma_azimuth=1e-9, latency_s=0.1), sensor_id="b1")
    out = sensor.measure(2.0, POSE, targets([[110.0, 80.0, 0.0]]), FakeScene(), np.random.default_rng(0))
    (det,) = out.detections
    assert det.z.shape == (1,) and det.R.shape == (1, 1)
    assert det.z[0] == pytest.approx(np.arctan2(100.0, 100.0), abs=1e-7)
    assert (det.t_meas, det.t_arrival, det.kind) == (2.0, 2.1, "bearing")
    assert det.model is sensor.model and det.model == BearingDetectionModel(dim=1, name="bearing")


@pytest.mark.parametrize("with_elevation", [False, True], ids=["az", "az_el"])
def test_noise_chi2_and_wrap_near_pi(with_elevation):
    cfg = BearingConfig(sigma_azimuth=0.05, sigma_elevation=0.03 if with_elevation else None)
    sensor = BearingSensor(cfg)
    # target almost due west: the true azimuth is within 0.01 rad of +pi, noise wraps it across -pi
    tgt = targets([[POSE.p_W[0] - 500.0, POSE.p_W[1] + 5.0, 0.0]])
    d = tgt.p_W[0] - POSE.p_W
    z_true = np.array([np.arctan2(d[1], d[0]), np.arctan2(d[2], np.hypot(d[0], d[1]))])[: 2 if with_elevation else 1]
    rng = np.random.default_rng(21)
    res = []
    for _ in range(1000):
        (det,) = sensor.measure(0.0, POSE, tgt, FakeScene(), rng).detections
        assert -np.pi <= det.z[0] < np.pi
        e = det.z - z_true
        e[0] = wrap_angle(e[0])
        res.append(e)
    res = np.array(res)
    n, m = res.shape
    nis = np.einsum("ij,jk,ik->", res, np.linalg.inv(cfg.R), res)
    assert stats.chi2.ppf(0.005, n * m) <= nis <= stats.chi2.ppf(0.995, n * m)
    assert np.any(res[:, 0] + z_true[0] > np.pi)  # some draws really wrapped


def test_occlusion_fov_and_range():
    scene = FakeScene([Building.cuboid((200.0, -20.0), (30.0, 30.0, 150.0))])
    cfg = BearingConfig(
        sigma_azimuth=0.01, max_range=1000.0, fov=FieldOfRegard(frame="world", azimuth_limits=(-2.0, 2.0))
    )
    sensor = BearingSensor(cfg)
    tg = targets([[400.0, -20.0, 0.0], [400.0, 200.0, 0.0], [-400.0, -20.0, 0.0], [1500.0, 300.0, 0.0]])
    out = sensor.measure(0.0, POSE, tg, scene, np.random.default_rng(0))
    # behind the tower, visible, outside the sector (west), out of range
    assert out.truth_ids.tolist() == [11]


def test_detection_probability_binomial():
    cfg = BearingConfig(sigma_azimuth=0.01, pd=0.6)
    sensor = BearingSensor(cfg)
    tg = targets([[300.0, 0.0, 0.0], [0.0, 300.0, 0.0]])
    rng = np.random.default_rng(8)
    n = 1000
    hits = sum(len(sensor.measure(0.0, POSE, tg, FakeScene(), rng).detections) for _ in range(n))
    lo, hi = stats.binom.interval(0.99, 2 * n, 0.6)
    assert lo <= hits <= hi
