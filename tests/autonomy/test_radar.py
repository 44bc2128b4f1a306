"""GMTI radar model: detection law, Doppler notch, clutter statistics, noise covariance, occlusion."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest
from scipy import stats

from autonomy.estimation.measurements import RadarDetectionModel
from autonomy.sensing.fake_scene import FakeScene
from autonomy.sensing.fov import FieldOfRegard
from autonomy.sensing.measurement import CLUTTER_ID, azimuth_elevation, wrap_angle
from autonomy.sensing.radar import Radar, RadarConfig, swerling1_pd
from autonomy.sensing.scene import SensorPose, TargetTruth
from simulator.scene_query import PybulletSceneQuery
from worlds.geometry import Building

SIGMAS = {
    "sigma_range": 10.0,
    "sigma_azimuth": np.deg2rad(2.0),
    "sigma_elevation": np.deg2rad(3.0),
    "sigma_range_rate": 0.5,
}


def one_target(p_W, v_W=(10.0, 0.0, 0.0), kind="car") -> TargetTruth:
    return TargetTruth(ids=[3], p_W=[p_W], v_W=[v_W], kind=(kind,), yaw=[0.0])


def radial_target(pose: SensorPose, rng_m: float, speed: float = 10.0, az: float = 0.3) -> TargetTruth:
    """Target on the ground at slant range ``rng_m`` and azimuth ``az`` from the pose, driving away radially."""
    h = pose.p_W[2]
    rho = np.sqrt(rng_m**2 - h**2)
    pt = pose.p_W + np.array([rho * np.cos(az), rho * np.sin(az), -h])
    return one_target(pt, speed * np.array([np.cos(az), np.sin(az), 0.0]))


POSE = SensorPose(p_W=[0.0, 0.0, 300.0])


def test_pd_law_closed_form():
    cfg = RadarConfig(**SIGMAS, pd_ref=0.8, range_ref=2000.0, pfa=1e-5, max_range=4000.0)
    assert cfg.pd(2000.0) == pytest.approx(0.8, abs=1e-12)
    # Swerling I: ln Pd = ln Pfa / (1 + SNR),  SNR_ref = ln Pfa / ln Pd_ref - 1, SNR ~ r^-4
    snr_ref = np.log(1e-5) / np.log(0.8) - 1
    r = 1000.0
    assert cfg.pd(r) == pytest.approx(np.exp(np.log(1e-5) / (1 + 16 * snr_ref)), rel=1e-12)
    rs = np.linspace(10, 3999, 200)
    assert np.all(np.diff(cfg.pd(rs)) < 0)
    assert cfg.pd(4000.1) == 0.0
    assert swerling1_pd(1e6, 0.8, 2000.0, 1e-5) == pytest.approx(1e-5, rel=1e-3)


@pytest.mark.parametrize("slant_range", [1200.0, 2000.0, 2600.0])
def test_detection_rate_in_binomial_interval(slant_range):
    cfg = RadarConfig(**SIGMAS, pd_ref=0.7, range_ref=2000.0, max_range=3000.0, min_detectable_velocity=1.0)
    radar = Radar(cfg)
    tgt = radial_target(POSE, slant_range)
    scene = FakeScene()
    rng = np.random.default_rng(11)
    n = 1500
    hits = sum(len(radar.measure(0.0, POSE, tgt, scene, rng).detections) for _ in range(n))
    pd = float(cfg.pd(slant_range))
    lo, hi = stats.binom.interval(0.99, n, pd)
    assert lo <= hits <= hi, (hits, n * pd)


def test_measurement_noise_matches_covariance_chi2():
    cfg = RadarConfig(**SIGMAS, pd_ref=0.99, range_ref=5000.0, max_range=6000.0)
    radar = Radar(cfg)
    pose = SensorPose(p_W=[100.0, -50.0, 400.0], v_W=[20.0, 5.0, 0.0])
    tgt = one_target([1500.0, 900.0, 0.75], v_W=[8.0, -3.0, 0.0])
    d = tgt.p_W[0] - pose.p_W
    r = np.linalg.norm(d)
    az, el = azimuth_elevation(d)
    z_true = np.array([r, az[0], el[0], d @ (tgt.v_W[0] - pose.v_W) / r])
    rng = np.random.default_rng(5)
    res = []
    for _ in range(800):
        out = radar.measure(1.0, pose, tgt, FakeScene(), rng)
        for det in out.detections:
            e = det.z - z_true
            e[1] = wrap_angle(e[1])
            res.append(e)
            np.testing.assert_allclose(det.R, cfg.R)
    res = np.array(res)
    n, m = res.shape
    nis = np.einsum("ij,jk,ik->", res, np.linalg.inv(cfg.R), res)
    lo, hi = stats.chi2.ppf([0.005, 0.995], n * m)
    assert lo <= nis <= hi
    # each component separately unbiased within 4 standard errors
    assert np.all(np.abs(res.mean(axis=0)) < 4 * np.sqrt(np.diag(cfg.R) / n))


def test_doppler_notch_misses_stopped_and_tangential_targets():
    cfg = RadarConfig(**SIGMAS, pd_ref=0.99, range_ref=5000.0, min_detectable_velocity=1.5)
    radar = Radar(cfg)
    pose = SensorPose(p_W=[0.0, 0.0, 200.0], v_W=[30.0, 0.0, 0.0])  # the platform's own motion is compensated
    pt = np.array([800.0, 0.0, 0.0])
    rng = np.random.default_rng(2)
    d = pt - pose.p_W
    u = d / np.linalg.norm(d)
    for v in ([0.0, 0.0, 0.0], [0.0, 15.0, 0.0], 1.4 * u / 1.0):  # stopped, tangential, radial below the notch
        tgt = one_target(pt, v)
        assert all(not radar.measure(0.0, pose, tgt, FakeScene(), rng).detections for _ in range(300))
    tgt = one_target(pt, 1.6 * u)
    hits = sum(len(radar.measure(0.0, pose, tgt, FakeScene(), rng).detections) for _ in range(300))
    assert hits >= stats.binom.ppf(0.005, 300, float(cfg.pd(np.linalg.norm(d))))


def test_range_rate_sign_and_latency():
    cfg = RadarConfig(**SIGMAS, pd_ref=0.99, range_ref=5000.0, latency_s=0.25)
    radar = Radar(cfg, sensor_id="uav1/radar")
    pt = np.array([600.0, 0.0, 0.0])
    out = radar.measure(3.5, POSE, one_target(pt, [-12.0, 0.0, 0.0]), FakeScene(), np.random.default_rng(0))
    (det,) = out.detections
    r = np.linalg.norm(pt - POSE.p_W)
    assert det.z[3] == pytest.approx(-12.0 * 600.0 / r, abs=5 * SIGMAS["sigma_range_rate"])
    assert det.t_meas == 3.5 and det.t_arrival == 3.75 and det.sensor_id == "uav1/radar" and det.kind == "radar"
    assert det.model is radar.model and det.model == RadarDetectionModel(dim=4)
    assert out.truth_ids.tolist() == [3]


def test_clutter_count_is_poisson_and_inside_field_of_regard():
    lam = 3.0
    fov = FieldOfRegard(frame="heading", azimuth_limits=(-0.5, 0.5), elevation_limits=(-1.2, -0.1))
    cfg = RadarConfig(
        sigma_range=1e-3,
        sigma_azimuth=1e-6,
        sigma_elevation=1e-6,
        sigma_range_rate=0.1,
        fov=fov,
        max_range=2500.0,
        clutter_rate=lam,
        min_detectable_velocity=2.0,
        clutter_range_rate_max=20.0,
    )
    radar = Radar(cfg)
    yaw = 1.0
    pose = SensorPose(p_W=[0.0, 0.0, 300.0], q_WB=[0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2)])
    rng = np.random.default_rng(9)
    n = 1500
    counts, zs = [], []
    for _ in range(n):
        out = radar.measure(0.0, pose, TargetTruth.empty(), FakeScene(), rng)
        assert np.all(out.truth_ids == CLUTTER_ID)
        counts.append(len(out.detections))
        zs += [d.z for d in out.detections]
    counts = np.array(counts)
    lo, hi = stats.poisson.interval(0.99, n * lam)
    assert lo <= counts.sum() <= hi
    # dispersion index: sum (x - mean)^2 / mean ~ chi2(n - 1) for Poisson counts
    disp = np.sum((counts - counts.mean()) ** 2) / counts.mean()
    assert stats.chi2.ppf(0.005, n - 1) <= disp <= stats.chi2.ppf(0.995, n - 1)
    zs = np.array(zs)
    assert np.all(zs[:, 0] <= 2500.0 + 0.01)
    assert np.all(np.abs(wrap_angle(zs[:, 1] - yaw)) <= 0.5 + 1e-4)
    assert np.all((zs[:, 2] >= -1.2 - 1e-4) & (zs[:, 2] <= -0.1 + 1e-4))
    # on the ground: slant range and elevation agree with a point at z = 0
    np.testing.assert_allclose(-zs[:, 0] * np.sin(zs[:, 2]), 300.0, atol=0.05)
    assert np.all((np.abs(zs[:, 3]) >= 2.0 - 0.6) & (np.abs(zs[:, 3]) <= 20.0 + 0.6))
    # uniform on the ground: the fraction within the inner half of the ground radius band matches its area share
    rho = zs[:, 0] * np.cos(zs[:, 2])
    rho_min, rho_max = 300.0 / np.tan(1.2), np.sqrt(2500.0**2 - 300.0**2)
    rho_mid = np.sqrt((rho_min**2 + rho_max**2) / 2)
    inner = int(np.sum(rho <= rho_mid))
    lo, hi = stats.binom.interval(0.99, len(rho), 0.5)
    assert lo <= inner <= hi


def test_sector_in_body_heading_frame_follows_yaw():
    fov = FieldOfRegard(frame="heading", azimuth_limits=(-0.3, 0.3))
    radar = Radar(RadarConfig(**SIGMAS, fov=fov, pd_ref=0.999, range_ref=1e4, pfa=1e-7))
    tgt = one_target([0.0, 800.0, 0.0], [0.0, 10.0, 0.0])  # due north
    rng = np.random.default_rng(1)
    east = SensorPose(p_W=[0.0, 0.0, 200.0])
    north = SensorPose(p_W=[0.0, 0.0, 200.0], q_WB=[0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4)])
    assert not radar.measure(0.0, east, tgt, FakeScene(), rng).detections
    assert len(radar.measure(0.0, north, tgt, FakeScene(), rng).detections) == 1


def test_same_seed_same_output():
    cfg = RadarConfig(**SIGMAS, clutter_rate=2.0)
    radar = Radar(cfg)
    tgt = radial_target(POSE, 1500.0)
    a = radar.measure(0.0, POSE, tgt, FakeScene(), np.random.default_rng(4))
    b = radar.measure(0.0, POSE, tgt, FakeScene(), np.random.default_rng(4))
    assert len(a.detections) == len(b.detections)
    for da, db in zip(a.detections, b.detections, strict=True):
        np.testing.assert_array_equal(da.z, db.z)
    np.testing.assert_array_equal(a.truth_ids, b.truth_ids)


def test_fake_scene_building_hides_target():
    scene = FakeScene([Building.cuboid((400.0, 0.0), (40.0, 40.0, 60.0))])
    radar = Radar(RadarConfig(**SIGMAS, pd_ref=0.999, range_ref=1e4, pfa=1e-7))
    pose = SensorPose(p_W=[0.0, 0.0, 50.0])
    rng = np.random.default_rng(0)
    hidden = one_target([500.0, 0.0, 0.75])
    clear = one_target([500.0, 200.0, 0.75])
    assert all(not radar.measure(0.0, pose, hidden, scene, rng).detections for _ in range(50))
    assert sum(len(radar.measure(0.0, pose, clear, scene, rng).detections) for _ in range(50)) >= 48


@pytest.fixture
def bullet_town():
    cid = p.connect(p.DIRECT)
    plane = p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid), physicsClientId=cid)
    he = [10.0, 10.0, 15.0]
    bld = p.createMultiBody(
        0,
        p.createCollisionShape(p.GEOM_BOX, halfExtents=he, physicsClientId=cid),
        basePosition=[60.0, 0.0, 15.0],
        physicsClientId=cid,
    )
    car_he = [2.0, 0.9, 0.75]
    car = p.createMultiBody(
        0,
        p.createCollisionShape(p.GEOM_BOX, halfExtents=car_he, physicsClientId=cid),
        basePosition=[85.0, 0.0, 0.75],
        physicsClientId=cid,
    )
    yield cid, PybulletSceneQuery(cid, {plane, bld}), car
    p.disconnect(cid)


def test_pybullet_building_hides_car_until_it_drives_clear(bullet_town):
    cid, scene, car = bullet_town
    radar = Radar(RadarConfig(**SIGMAS, pd_ref=0.999, range_ref=1e4, pfa=1e-7))
    pose = SensorPose(p_W=[0.0, 0.0, 20.0])
    rng = np.random.default_rng(3)
    hidden = one_target([85.0, 0.0, 0.75])
    assert all(not radar.measure(0.0, pose, hidden, scene, rng).detections for _ in range(30))
    p.resetBasePositionAndOrientation(car, [85.0, 40.0, 0.75], [0, 0, 0, 1], physicsClientId=cid)
    clear = one_target([85.0, 40.0, 0.75])
    got = [radar.measure(0.0, pose, clear, scene, rng) for _ in range(30)]
    assert sum(len(o.detections) for o in got) >= 29
    assert all(o.truth_ids.tolist() in ([3], []) for o in got)


def test_config_validation_names_field():
    with pytest.raises(ValueError, match="pd_ref"):
        RadarConfig(**SIGMAS, pd_ref=1.0)
    with pytest.raises(ValueError, match="sigma_range"):
        RadarConfig(sigma_range=0.0, sigma_azimuth=0.1, sigma_elevation=0.1)
    with pytest.raises(ValueError, match="elevation_limits"):
        FieldOfRegard(frame="world", elevation_limits=(0.5, 0.2))


def test_field_of_regard_wrapping_sector_and_body_frame():
    behind = FieldOfRegard(frame="world", azimuth_limits=(3.0, -3.0))
    dirs = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-1.0, 0.1, 0.0], [-1.0, 0.2, 0.0]])
    np.testing.assert_array_equal(behind.contains(dirs, np.eye(3)), [True, False, True, False])
    # body-fixed sector looking 10-60 deg below the body x-y plane; pitching the body nose-up by 0.5 rad
    # (negative rotation about y) puts a horizontal direction 0.5 rad below the body plane; the heading frame ignores it
    pitch = -0.5
    R_WB = np.array([[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0], [-np.sin(pitch), 0, np.cos(pitch)]])
    body = FieldOfRegard(frame="body", azimuth_limits=(-0.5, 0.5), elevation_limits=(-1.05, -0.17))
    heading = FieldOfRegard(frame="heading", azimuth_limits=(-0.5, 0.5), elevation_limits=(-1.05, -0.17))
    ahead = np.array([[1.0, 0.0, 0.0]])
    assert body.contains(ahead, R_WB)[0] and not body.contains(ahead, np.eye(3))[0]
    assert not heading.contains(ahead, R_WB)[0]


def test_two_dimensional_radar_reports_range_and_azimuth_with_their_noise():
    """Without an elevation channel (papers 001/002) z = (slant range, azimuth), with R = diag(σr², σaz²)."""
    cfg = RadarConfig(sigma_range=20.0, sigma_azimuth=np.deg2rad(7.0), pd_ref=0.99, range_ref=5000.0,
                      max_range=6000.0, min_detectable_velocity=0.0)
    assert cfg.R.shape == (2, 2)
    radar = Radar(cfg)
    pose = SensorPose(p_W=[0.0, 0.0, 60.0])
    tgt = one_target([150.0, 40.0, 0.0])
    d = tgt.p_W[0] - pose.p_W
    z_true = np.array([np.linalg.norm(d), np.arctan2(d[1], d[0])])
    rng = np.random.default_rng(3)
    res = []
    for _ in range(600):
        for det in radar.measure(0.0, pose, tgt, FakeScene(), rng).detections:
            assert det.z.shape == (2,) and det.R.shape == (2, 2)
            e = det.z - z_true
            e[1] = wrap_angle(e[1])
            res.append(e @ np.linalg.solve(cfg.R, e))
    lo, hi = stats.chi2.interval(0.99, 2 * len(res))
    assert lo <= np.sum(res) <= hi
    with pytest.raises(ValueError, match="sigma_range_rate needs the elevation channel"):
        RadarConfig(sigma_range=1.0, sigma_azimuth=0.01, sigma_range_rate=0.5)


class _CountingScene(FakeScene):
    """A FakeScene that keeps how many sight lines it was asked for."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.asked = 0

    def line_of_sight(self, from_W, to_W):
        self.asked += len(np.atleast_2d(from_W))
        return super().line_of_sight(from_W, to_W)


def test_sight_lines_are_cast_only_for_targets_whose_draw_detects_them_and_the_hits_are_unchanged():
    """A scan's hits are the targets in view, unhidden, whose uniform draw falls below their pd (``detectable``'s mask
    and pd with the scan's first draw); the sight lines are asked only for those in view whose draw passed, about pd
    of them, not for every target in view."""
    scene = _CountingScene([Building.cuboid((600.0, 0.0), (80.0, 400.0, 60.0))])  # hides a few dozen
    radar = Radar(RadarConfig(**SIGMAS, clutter_rate=0.0, max_range=3000.0, range_ref=1500.0))
    pose = SensorPose(p_W=[0.0, 0.0, 50.0])
    rng = np.random.default_rng(8)
    n = 400
    xy = rng.uniform([-2000.0, -2000.0], [2000.0, 2000.0], (n, 2))
    v = rng.normal(0.0, 10.0, (n, 3)) * [1.0, 1.0, 0.0]
    tgt = TargetTruth(ids=list(range(n)), p_W=np.column_stack([xy, np.full(n, 0.75)]), v_W=v, kind=("car",) * n,
                      yaw=np.zeros(n))
    seen = FakeScene(scene.buildings)
    mask, pd = radar.detectable(pose, tgt, seen)
    in_view = radar._in_view(pose, tgt)[0]
    for seed in range(5):
        scene.asked = 0
        out = radar.measure(0.0, pose, tgt, scene, np.random.default_rng(seed))
        u = np.random.default_rng(seed).uniform(size=n)
        expect = np.flatnonzero(mask & (u < pd))
        assert sorted(out.truth_ids.tolist()) == expect.tolist()
        assert scene.asked == int(np.sum(in_view & (u < radar.config.pd(np.linalg.norm(tgt.p_W - pose.p_W, axis=1)))))
        assert scene.asked < 0.95 * in_view.sum() and mask.sum() <= in_view.sum() - 20
