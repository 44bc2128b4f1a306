"""A camera frame's coverage (negative information): what a frame could have seen, in closed form (image bounds,
behind the camera, the blob-size range) and by the depth image (a building in front hides a point, one behind does
not, a car standing at the point does not); the camera hands every frame's coverage out with its detections."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.sensing.camera import CAR_RGBA, Camera, CameraConfig, camera_pose
from autonomy.sensing.coverage import CAR_TOP_AREA_M2, DEPTH_TOLERANCE_M, FrameCoverage
from autonomy.sensing.fake_scene import FakeScene, SceneBox
from autonomy.sensing.scene import SensorPose, TargetTruth
from worlds.geometry import Building

UAV = np.array([0.0, 0.0, 60.0])
LOOK = np.array([150.0, 0.0, 0.75])  # the standoff geometry of the traffic world: 150 m out, 60 m up
CFG = CameraConfig(width=160, height=120, hfov=math.radians(30.0), pointing="track")
CAR_RGB = tuple(round(255 * c) for c in CAR_RGBA[:3])


def _coverage(scene: FakeScene, cfg: CameraConfig = CFG) -> FrameCoverage:
    out = Camera(cfg, sensor_id="cam").measure(2.5, SensorPose(p_W=UAV, q_WB=[0, 0, 0, 1], look_at_W=LOOK),
                                               TargetTruth.empty(), scene, np.random.default_rng(0))
    return out.extras["coverage"]


def test_every_frame_hands_out_its_coverage():
    cfg = CameraConfig(width=160, height=120, hfov=math.radians(30.0), pointing="track", latency_s=0.1)
    out = Camera(cfg, sensor_id="cam").measure(2.5, SensorPose(p_W=UAV, q_WB=[0, 0, 0, 1], look_at_W=LOOK),
                                               TargetTruth.empty(), FakeScene(), np.random.default_rng(0))
    cov = out.extras["coverage"]
    assert out.detections == () and (cov.t_meas, cov.t_arrival, cov.sensor_id) == (2.5, 2.6, "cam")
    cam = camera_pose(cfg, SensorPose(p_W=UAV, q_WB=[0, 0, 0, 1], look_at_W=LOOK))
    np.testing.assert_allclose(cov.camera.R_WC, cam.R_WC)
    assert cov.depth.shape == (120, 160) and cov.min_blob_area_px == cfg.min_blob_area_px


def test_the_image_bounds_and_the_camera_s_back_in_closed_form():
    """Points 100 m along the optical axis (in the air, nearer than the ground behind them) at pixels just inside
    and just outside each edge of the image, and points behind the camera."""
    cov = _coverage(FakeScene())
    K, cam = cov.intrinsics, cov.camera

    def at(u: float, v: float, x: float = 100.0) -> np.ndarray:
        return cam.p_W + cam.R_WC @ np.array([x, (K.cx - u) * x / K.fx, (K.cy - v) * x / K.fy])

    inside = [at(K.cx, K.cy), at(0.5, K.cy), at(K.width - 0.5, K.cy), at(K.cx, 0.5), at(K.cx, K.height - 0.5)]
    outside = [at(-0.5, K.cy), at(K.width + 0.5, K.cy), at(K.cx, -0.5), at(K.cx, K.height + 0.5),
               at(K.cx, K.cy, -100.0)]
    np.testing.assert_array_equal(cov.visible(np.array(inside + outside)), [True] * 5 + [False] * 5)


def test_a_car_too_far_for_its_blob_is_out_of_view():
    """Looking straight down on a car at range x, its top of CAR_TOP_AREA_M2 covers fx fy A / x² px: in view while
    that is at least twice the detector's smallest blob (a range of fx sqrt(A / (2 min_blob)), 422 m here)."""
    K = CFG.intrinsics
    x_max = math.sqrt(K.fx * K.fy * CAR_TOP_AREA_M2 / (2.0 * CFG.min_blob_area_px))
    car = np.array([0.0, 0.0, 0.75])
    seen = []
    for x in (0.98 * x_max, 1.02 * x_max):
        pose = SensorPose(p_W=car + [0, 0, x], q_WB=[0, 0, 0, 1], look_at_W=car)
        cov = Camera(CFG, sensor_id="cam").measure(0.0, pose, TargetTruth.empty(), FakeScene(),
                                                   np.random.default_rng(0)).extras["coverage"]
        seen.append(bool(cov.visible(car[None])[0]))
    assert seen == [True, False]


def test_a_building_in_front_hides_a_point_and_one_behind_does_not():
    wall = lambda x0: Building(footprint=np.array([[x0, -30.0], [x0 + 5, -30.0], [x0 + 5, 30.0], [x0, 30.0]]),  # noqa: E731
                               height=40.0)
    assert not _coverage(FakeScene(buildings=[wall(120.0)])).visible(LOOK[None])[0]  # between camera and point
    assert _coverage(FakeScene(buildings=[wall(170.0)])).visible(LOOK[None])[0]  # beyond the point
    assert _coverage(FakeScene()).visible(LOOK[None])[0]


def test_a_car_standing_at_the_point_does_not_hide_it():
    """The depth image shows the car's own near face, at most a half-length nearer than its centre: within the
    tolerance, so a frame that shows the car (and, with the detector, detects it) counts the point in view."""
    car = SceneBox(center_W=tuple(LOOK), size=(4.5, 1.8, 1.5), yaw=0.0, rgb=CAR_RGB)
    cov = _coverage(FakeScene(boxes=[car]))
    row, col = int(cov.intrinsics.cy), int(cov.intrinsics.cx)
    x_look = float((LOOK - cov.camera.p_W) @ cov.camera.forward_W)
    assert x_look - DEPTH_TOLERANCE_M < cov.depth[row, col] < x_look  # the car's face is in the depth image
    assert cov.visible(LOOK[None])[0]


def test_coverage_refuses_a_depth_image_of_another_size():
    cov = _coverage(FakeScene())
    with pytest.raises(ValueError, match=r"depth is \(10, 10\), the intrinsics say \(120, 160\)"):
        FrameCoverage(t_meas=0.0, t_arrival=0.0, sensor_id="c", camera=cov.camera, intrinsics=cov.intrinsics,
                      depth=np.zeros((10, 10)), min_blob_area_px=2)
