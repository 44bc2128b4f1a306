"""Target-cued camera (``pointing: track``): the gimbal puts the look point on the principal point, falls back to the
body pose without one, reaches the lower hemisphere only; the world-file key; the tick hands the UAV's estimate to
cued cameras only; a car beside the UAV's heading is seen by a cued camera and missed by a heading-fixed one."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from autonomy.sensing.camera import CAR_RGBA, GROUND_Z_M, Camera, CameraConfig, camera_pose, look_point
from autonomy.sensing.fake_scene import FakeScene, SceneBox
from autonomy.sensing.measurement import SensorOutput, azimuth_elevation, wrap_angle
from autonomy.sensing.scene import SensorPose, TargetTruth
from interfaces.state import TargetEstimate
from simulator.registry import build_sensor
from simulator.scene_query import PybulletSceneQuery
from worlds.errors import WorldError
from worlds.loader import load_world

CAR_HALF = (2.0, 0.9, 0.75)
CAR_RGB = tuple(round(255 * c) for c in CAR_RGBA[:3])
UAV_P = (0.0, 0.0, 30.0)
CAR_XY = (0.0, 40.0)  # due north of the UAV, which heads east: 90 degrees off its heading


def quat(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """(x, y, z, w) of R_z(yaw) R_y(pitch) R_x(roll)."""
    cr, sr, cp, sp, cy, sy = (f(a / 2) for a in (roll, pitch, yaw) for f in (np.cos, np.sin))
    return np.array([sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
                     cr * cp * cy + sr * sp * sy])


def car_truth(xy, seg_id=None) -> TargetTruth:
    return TargetTruth(ids=[5], p_W=[[xy[0], xy[1], CAR_HALF[2]]], v_W=[[0.0, 0, 0]], kind=("car",), yaw=[0.0],
                       seg_ids=None if seg_id is None else [seg_id])


# -- the gimbal in closed form --------------------------------------------------------------------------------------
@pytest.mark.parametrize("look, attitude, offset", [
    ((40.0, 25.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
    ((0.0, 40.0, 0.75), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
    ((-35.0, -12.0, 0.0), (0.2, -0.15, 2.5), (0.1, 0.0, -0.05)),
    ((3.0, -1.0, 29.0), (-0.3, 0.1, -1.0), (0.0, 0.05, -0.1)),
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.7), (0.0, 0.0, 0.0)),
], ids=["ahead", "abeam", "behind-tilted", "just-below", "nadir"])
def test_the_look_point_projects_onto_the_principal_point(look, attitude, offset):
    cfg = CameraConfig(pointing="track", mount_offset_B=offset)
    pose = SensorPose(p_W=UAV_P, q_WB=quat(*attitude), look_at_W=look)
    cam = camera_pose(cfg, pose)
    np.testing.assert_allclose(cam.p_W, pose.p_W + pose.R_WB @ offset, atol=1e-12)
    uv = cfg.intrinsics.project((np.asarray(look) - cam.p_W) @ cam.R_WC)[0]
    np.testing.assert_allclose(uv, [cfg.intrinsics.cx, cfg.intrinsics.cy], atol=1e-9)
    assert cam.R_WC[2, 1] == pytest.approx(0.0, abs=1e-12)  # image kept level: its left axis is horizontal
    assert cam.up_W[2] >= 0.0


def test_straight_down_the_pan_is_the_heading():
    cam = camera_pose(CameraConfig(pointing="track"), SensorPose(p_W=UAV_P, q_WB=quat(0, 0, 0.7), look_at_W=(0, 0, 0)))
    np.testing.assert_allclose(cam.forward_W, [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(cam.up_W, [np.cos(0.7), np.sin(0.7), 0], atol=1e-12)  # image top ahead


def test_a_look_point_above_the_camera_is_watched_at_the_horizon():
    cam = camera_pose(CameraConfig(pointing="track"), SensorPose(p_W=UAV_P, look_at_W=(-10.0, 10.0, 60.0)))
    np.testing.assert_allclose(cam.forward_W, [-np.sqrt(0.5), np.sqrt(0.5), 0.0], atol=1e-12)


@pytest.mark.parametrize("stabilised", [True, False])
def test_without_a_look_point_the_pose_is_the_body_pose(stabilised):
    pose = SensorPose(p_W=UAV_P, q_WB=quat(0.2, -0.1, 1.3))
    body = camera_pose(CameraConfig(stabilised=stabilised, mount_offset_B=(0.1, 0, -0.05)), pose)
    track = camera_pose(CameraConfig(stabilised=stabilised, mount_offset_B=(0.1, 0, -0.05), pointing="track"), pose)
    np.testing.assert_array_equal(track.R_WC, body.R_WC)
    np.testing.assert_array_equal(track.p_W, body.p_W)
    straight_up = SensorPose(p_W=UAV_P, q_WB=pose.q_WB, look_at_W=body.p_W + [0, 0, 20])  # out of the lower hemisphere
    np.testing.assert_array_equal(camera_pose(CameraConfig(stabilised=stabilised, mount_offset_B=(0.1, 0, -0.05),
                                                           pointing="track"), straight_up).R_WC, body.R_WC)
    cued = SensorPose(p_W=UAV_P, q_WB=pose.q_WB, look_at_W=(40.0, 25.0, 0.0))  # a body camera ignores a cue
    np.testing.assert_array_equal(camera_pose(CameraConfig(stabilised=stabilised, mount_offset_B=(0.1, 0, -0.05)),
                                              cued).R_WC, body.R_WC)


def test_look_point_of_an_estimate():
    flat = TargetEstimate(t=2.0, p_W=np.array([10.0, -4.0]), v_W=np.array([3.0, 1.0]))
    np.testing.assert_allclose(look_point(flat, 2.5), [11.5, -3.5, GROUND_Z_M])
    high = TargetEstimate(t=2.0, p_W=np.array([10.0, -4.0, 1.5]), v_W=np.array([3.0, 1.0, 0.0]))
    np.testing.assert_allclose(look_point(high, 2.0), [10.0, -4.0, 1.5])
    assert look_point(None, 2.0) is None
    assert Camera(CameraConfig(pointing="track")).look_point(flat, 2.0) is not None
    assert Camera(CameraConfig()).look_point(flat, 2.0) is None


def test_config_refuses_an_unknown_pointing():
    with pytest.raises(ValueError, match=r"CameraConfig.pointing .* got 'gimbal'"):
        CameraConfig(pointing="gimbal")


# -- the world file -------------------------------------------------------------------------------------------------
CAMERA = "uavs[1].sensors[0]"


def test_the_world_key_reaches_the_camera_and_defaults_to_body():
    world = load_world("demo", [f"{CAMERA}={{type: camera, rate_hz: 10}}"]).world
    assert world.uavs[1].sensors[0].pointing == "body"
    assert build_sensor(world.uavs[1].sensors[0], "c").config.pointing == "body"
    world = load_world("demo", [f"{CAMERA}={{type: camera, rate_hz: 10, pointing: track}}"]).world
    assert build_sensor(world.uavs[1].sensors[0], "c").config.pointing == "track"


def test_the_world_key_refuses_other_values_with_its_path():
    with pytest.raises(WorldError) as info:
        load_world("demo", [f"{CAMERA}={{type: camera, rate_hz: 10, pointing: target}}"])
    (issue,) = info.value.issues
    assert issue.path == f"{CAMERA}.pointing", str(info.value)
    assert "'body'" in issue.expected and "'track'" in issue.expected, issue.expected


# -- the tick hands the estimate to cued cameras only ---------------------------------------------------------------
class _PoseLog:
    """Keeps the pose a sensor is measured at and reports nothing."""

    def __init__(self) -> None:
        self.poses: list[SensorPose] = []

    def measure(self, t, pose, targets, scene, rng) -> SensorOutput:
        self.poses.append(pose)
        return SensorOutput(detections=(), truth_ids=np.zeros(0, int))


class _LoggingCamera(_PoseLog, Camera):
    def __init__(self, config: CameraConfig) -> None:
        Camera.__init__(self, config)
        _PoseLog.__init__(self)


class _LoggingRadar(_PoseLog):
    rate_hz, latency_s = 10.0, 0.0


def test_the_tick_cues_only_cameras_that_point_at_the_track(tmp_path):
    from simulator.clock import Clock
    from simulator.fake_engine import ScriptedUavs, fake_assembly
    from simulator.record import RunRecorder
    from simulator.slots import SensorSlot
    from simulator.streams import STREAMS

    hz = 240
    uavs = ScriptedUavs(lambda tick: np.array([UAV_P]), hz)
    sensors = [_LoggingCamera(CameraConfig(pointing="track")), _LoggingCamera(CameraConfig()), _LoggingRadar()]
    slots = [SensorSlot(uav=0, sensor=s, divisor=1, rng=np.random.default_rng(0), name=f"s{k}")
             for k, s in enumerate(sensors)]
    recorder = RunRecorder(tmp_path, schemas=STREAMS)
    asm = fake_assembly(clock=Clock(physics_hz=hz), recorder=recorder, uavs=uavs, uav_ids=["a"], agents=[],
                        methods=[], sensors=slots)
    asm.step(1)  # no estimate yet
    asm.latest_estimates[0] = TargetEstimate(t=0.0, p_W=np.array([0.0, 40.0]), v_W=np.array([24.0, 0.0]))
    asm.step(2)
    recorder.close()
    track, body, radar = (s.poses for s in sensors)
    assert all(pose.look_at_W is None for pose in [track[0], *body, *radar])
    np.testing.assert_allclose(track[1].look_at_W, [24.0 * 2 / hz, 40.0, GROUND_Z_M])


# -- a car beside the heading ---------------------------------------------------------------------------------------
def _beside(pointing: str, scene, seg_id=None) -> SensorOutput:
    cam = Camera(CameraConfig(pixel_sigma=0.0, pointing=pointing))
    estimate = TargetEstimate(t=0.0, p_W=np.array([1.0, 38.5]), v_W=np.zeros(2))  # 1.8 m off the car
    pose = SensorPose(p_W=UAV_P, look_at_W=cam.look_point(estimate, 0.0))  # heading east, the car due north
    return cam.measure(0.0, pose, car_truth(CAR_XY, seg_id), scene, np.random.default_rng(0))


def _check_seen(out: SensorOutput) -> None:
    (det,) = out.detections
    assert out.truth_ids.tolist() == [5]
    az, el = azimuth_elevation(np.array([CAR_XY[0], CAR_XY[1], CAR_HALF[2]]) - UAV_P)
    fx = Camera(CameraConfig()).intrinsics.fx
    assert np.all(np.abs(wrap_angle(det.z - [az[0], el[0]])) < 3.0 / fx)


def test_fake_scene_a_cued_camera_sees_the_car_beside_the_heading():
    box = SceneBox(center_W=(*CAR_XY, CAR_HALF[2]), size=tuple(2 * np.array(CAR_HALF)), rgb=CAR_RGB, seg_id=77)
    scene = FakeScene([], [box])
    assert _beside("body", scene, 77).detections == ()
    _check_seen(_beside("track", scene, 77))


def test_pybullet_a_cued_camera_sees_the_car_beside_the_heading():
    cid = p.connect(p.DIRECT)
    try:
        plane = p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid),
                                  p.createVisualShape(p.GEOM_BOX, halfExtents=[200, 200, 0.01],
                                                      rgbaColor=[0.4, 0.45, 0.4, 1], visualFramePosition=[0, 0, -0.01],
                                                      physicsClientId=cid), physicsClientId=cid)
        car = p.createMultiBody(0, p.createCollisionShape(p.GEOM_BOX, halfExtents=CAR_HALF, physicsClientId=cid),
                                p.createVisualShape(p.GEOM_BOX, halfExtents=CAR_HALF, rgbaColor=list(CAR_RGBA),
                                                    physicsClientId=cid),
                                basePosition=[*CAR_XY, CAR_HALF[2]], physicsClientId=cid)
        scene = PybulletSceneQuery(cid, {plane})
        assert _beside("body", scene, car).detections == ()
        _check_seen(_beside("track", scene, car))
    finally:
        p.disconnect(cid)
