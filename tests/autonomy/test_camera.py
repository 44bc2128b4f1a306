"""Camera: intrinsics, gimbal, colour-blob detector, bearings against the truth, occlusion by rendering."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from autonomy.sensing.camera import CAR_RGBA, Camera, CameraConfig, camera_pose, detect_blobs
from autonomy.sensing.fake_scene import FakeScene, SceneBox
from autonomy.sensing.measurement import azimuth_elevation, wrap_angle
from autonomy.sensing.scene import CameraIntrinsics, SensorPose, TargetTruth
from simulator.scene_query import PybulletSceneQuery
from worlds.geometry import Building

CAR_HALF = (2.0, 0.9, 0.75)
CAR_RGB = tuple(round(255 * c) for c in CAR_RGBA[:3])


def yaw_q(yaw: float) -> np.ndarray:
    return np.array([0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2)])


def car_truth(xy, seg_id=None) -> TargetTruth:
    return TargetTruth(
        ids=[5],
        p_W=[[xy[0], xy[1], CAR_HALF[2]]],
        v_W=[[0.0, 0, 0]],
        kind=("car",),
        yaw=[0.0],
        seg_ids=None if seg_id is None else [seg_id],
    )


def looking_at(p_W, target_xy) -> SensorPose:
    return SensorPose(p_W=p_W, q_WB=yaw_q(np.arctan2(target_xy[1] - p_W[1], target_xy[0] - p_W[0])))


def true_bearing(pose_cam_p, target_p) -> np.ndarray:
    az, el = azimuth_elevation(np.asarray(target_p) - pose_cam_p)
    return np.array([az[0], el[0]])


def test_intrinsics_projection_round_trip():
    K = CameraIntrinsics.from_hfov(160, 120, np.deg2rad(60))
    assert K.fx == pytest.approx(80 / np.tan(np.deg2rad(30)))
    assert K.vfov == pytest.approx(2 * np.arctan(0.75 * np.tan(np.deg2rad(30))))
    uv = np.array([[0.0, 0.0], [80.0, 60.0], [159.5, 7.25]])
    rays = K.ray_C(uv)
    np.testing.assert_allclose(K.project(3.7 * rays), uv, atol=1e-9)
    assert np.isnan(K.project(np.array([[-1.0, 0, 0]]))).all()


def test_gimbal_stabilised_and_fixed():
    cfg = CameraConfig(gimbal_pitch=np.pi / 2)
    tilted = SensorPose(p_W=[0, 0, 10.0], q_WB=[np.sin(0.1), 0.0, 0.0, np.cos(0.1)])  # rolled 0.2 rad
    np.testing.assert_allclose(camera_pose(cfg, tilted).forward_W, [0, 0, -1], atol=1e-12)
    fixed = camera_pose(CameraConfig(gimbal_pitch=np.pi / 2, stabilised=False, mount_offset_B=(0.1, 0, -0.05)), tilted)
    assert fixed.forward_W[1] == pytest.approx(np.sin(0.2), abs=1e-12)  # nadir axis follows the roll
    np.testing.assert_allclose(fixed.p_W, tilted.p_W + tilted.R_WB @ [0.1, 0, -0.05])


def test_detector_finds_synthetic_blobs_with_exact_centroids():
    img = np.full((40, 60, 3), 90, np.uint8)
    img[10:14, 20:30] = CAR_RGB  # 4 x 10 block: centroid (25, 12) in continuous pixel coordinates
    img[30, 5] = CAR_RGB  # one pixel, below the minimum area
    img[25:27, 40:42] = (255, 0, 0)  # red: wrong hue
    cfg = CameraConfig()
    blobs = detect_blobs(img, cfg.hsv_low, cfg.hsv_high, min_area=2)
    assert len(blobs) == 1
    np.testing.assert_allclose(blobs[0].centroid, [25.0, 12.0])
    np.testing.assert_array_equal(blobs[0].box, [20, 10, 30, 14])
    assert blobs[0].area == 40


def test_fake_scene_camera_bearing_and_occlusion():
    cam = Camera(CameraConfig(pixel_sigma=0.0))
    building = Building.cuboid((20.0, 0.0), (10.0, 10.0, 20.0))
    pose_hidden = looking_at([0.0, 0.0, 30.0], (40.0, 0.0))
    box = SceneBox(center_W=(40.0, 0.0, CAR_HALF[2]), size=tuple(2 * np.array(CAR_HALF)), rgb=CAR_RGB, seg_id=77)
    scene = FakeScene([building], [box])
    assert cam.measure(0.0, pose_hidden, car_truth((40.0, 0.0)), scene, np.random.default_rng(0)).detections == ()
    box = SceneBox(center_W=(40.0, 25.0, CAR_HALF[2]), size=tuple(2 * np.array(CAR_HALF)), rgb=CAR_RGB, seg_id=77)
    pose = looking_at([0.0, 0.0, 30.0], (40.0, 25.0))
    out = cam.measure(1.0, pose, car_truth((40.0, 25.0), seg_id=77), scene.with_boxes([box]), np.random.default_rng(0))
    (det,) = out.detections
    assert out.truth_ids.tolist() == [5]
    err = det.z - true_bearing(pose.p_W, [40.0, 25.0, CAR_HALF[2]])
    assert np.all(np.abs(wrap_angle(err)) < 3.0 / cam.intrinsics.fx)


@pytest.fixture
def bullet_street():
    cid = p.connect(p.DIRECT)
    plane = p.createMultiBody(
        0,
        p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid),
        p.createVisualShape(
            p.GEOM_BOX,
            halfExtents=[200, 200, 0.01],
            rgbaColor=[0.4, 0.45, 0.4, 1],
            visualFramePosition=[0, 0, -0.01],
            physicsClientId=cid,
        ),
        physicsClientId=cid,
    )
    bld = p.createMultiBody(
        0,
        p.createCollisionShape(p.GEOM_BOX, halfExtents=[5, 5, 10], physicsClientId=cid),
        p.createVisualShape(p.GEOM_BOX, halfExtents=[5, 5, 10], rgbaColor=[0.7, 0.68, 0.65, 1], physicsClientId=cid),
        basePosition=[20.0, 0.0, 10.0],
        physicsClientId=cid,
    )
    car = p.createMultiBody(
        0,
        p.createCollisionShape(p.GEOM_BOX, halfExtents=CAR_HALF, physicsClientId=cid),
        p.createVisualShape(p.GEOM_BOX, halfExtents=CAR_HALF, rgbaColor=list(CAR_RGBA), physicsClientId=cid),
        basePosition=[40.0, 0.0, CAR_HALF[2]],
        physicsClientId=cid,
    )
    yield cid, PybulletSceneQuery(cid, {plane, bld}), car
    p.disconnect(cid)


def test_pybullet_camera_sees_car_only_in_the_clear(bullet_street):
    cid, scene, car = bullet_street
    cam = Camera(CameraConfig(pixel_sigma=0.0, keep_frame=True))
    rng = np.random.default_rng(0)
    hidden = cam.measure(0.0, looking_at([0.0, 0.0, 30.0], (40.0, 0.0)), car_truth((40.0, 0.0), car), scene, rng)
    assert hidden.detections == ()
    assert not np.any(hidden.extras["frame"].seg == car)
    for xy in [(40.0, 25.0), (30.0, -30.0), (55.0, 20.0)]:
        p.resetBasePositionAndOrientation(car, [xy[0], xy[1], CAR_HALF[2]], [0, 0, 0, 1], physicsClientId=cid)
        pose = looking_at([0.0, 0.0, 30.0], xy)
        out = cam.measure(0.5, pose, car_truth(xy, car), scene, rng)
        (det,) = out.detections
        assert out.truth_ids.tolist() == [5]
        err = wrap_angle(det.z - true_bearing(pose.p_W, [xy[0], xy[1], CAR_HALF[2]]))
        assert np.all(np.abs(err) < 3.0 / cam.intrinsics.fx), err * cam.intrinsics.fx
        u0, v0, u1, v1 = det.pixel_box
        assert (u1 - u0) * (v1 - v0) >= 20 and det.kind == "camera" and det.t_arrival == 0.5


def test_pybullet_camera_noise_covariance(bullet_street):
    cid, scene, car = bullet_street
    p.resetBasePositionAndOrientation(car, [40.0, 25.0, CAR_HALF[2]], [0, 0, 0, 1], physicsClientId=cid)
    cam = Camera(CameraConfig(pixel_sigma=1.0, centroid_model_sigma=0.0))
    pose = looking_at([0.0, 0.0, 30.0], (40.0, 25.0))
    rng = np.random.default_rng(4)
    zs, Rs = [], []
    for _ in range(200):
        (det,) = cam.measure(0.0, pose, car_truth((40.0, 25.0), car), scene, rng).detections
        zs.append(det.z)
        Rs.append(det.R)
    zs = np.array(zs)
    res = zs - zs.mean(axis=0)
    R = np.mean(Rs, axis=0)
    # sample covariance of the bearings agrees with the reported R (1 px noise through the pinhole Jacobian)
    np.testing.assert_allclose(np.diag(np.cov(res.T)), np.diag(R), rtol=0.25)
    assert np.sqrt(R[0, 0]) == pytest.approx(1.0 / cam.intrinsics.fx, rel=0.3)
    default_R = Camera(CameraConfig(pixel_sigma=0.0)).measure(0.0, pose, car_truth((40.0, 25.0), car), scene, rng)
    assert np.all(np.linalg.eigvalsh(default_R.detections[0].R) > 0)  # never singular, even without simulated noise


def test_config_validation_names_field():
    with pytest.raises(ValueError, match="hfov"):
        CameraConfig(hfov=4.0)
    with pytest.raises(ValueError, match="hsv_low"):
        CameraConfig(hsv_low=(170, 0, 0), hsv_high=(160, 255, 255))
