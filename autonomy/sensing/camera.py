"""Gimballed camera: render, detect painted cars by colour, and report bearings and pixel boxes.

Cars are painted :data:`CAR_RGBA` (saturated magenta, a colour absent from roads, roofs, grass and sky); the
simulator uses this constant when it builds car bodies. The detector works on the RGB image only:

1. convert to HSV (OpenCV: H in [0, 180), S, V in [0, 255]) and keep pixels inside ``[hsv_low, hsv_high]``;
2. 8-connected components with at least ``min_blob_area_px`` pixels are detections;
3. each blob centroid ``(u, v)`` (continuous pixel coordinates, pixel centres at ``j + 1/2``) plus Gaussian noise
   ``N(0, pixel_sigma**2 I)`` gives the camera-frame ray ``[1, (c_x - u)/f_x, (c_y - v)/f_y]``, rotated into the world
   and reported as ``z = [azimuth, elevation]`` with ``R = (pixel_sigma**2 + centroid_model_sigma**2) J J^T``,
   ``J = d(az, el)/d(u, v)``: the second term accounts for the blob centroid not being the projection of the
   target's reference point (partial views, pixelation) and keeps ``R`` positive definite; it is not simulated.

Every frame also hands out its coverage (``SensorOutput.extras["coverage"]``, :mod:`.coverage`: where the frame could
have seen a car), for the trackers' negative information.

The reported pixel box is the blob's box shifted by the same centroid noise. The segmentation mask is used only to
tell the recorder which target a blob came from (``TargetTruth.seg_ids``; without them, by projecting the targets).
Two cars whose blobs touch in the image give one detection.

Gimbal: with ``pointing="body"`` the camera frame is ``R_WC = R_z(yaw) R_y(pitch)`` when stabilised (it follows the
heading only) or ``R_WC = R_WB R_y(pitch)`` when fixed to the airframe; positive ``gimbal_pitch`` looks down.

With ``pointing="track"`` the camera hangs in a two-axis (pan, tilt) gimbal below the airframe, stabilised in the
world frame, that points the optical axis at the look point the pose carries (``SensorPose.look_at_W``: the UAV's
own target estimate, see :func:`look_point`). With ``d = look_at_W - p_C`` from the optical centre ``p_C``,

    pan = atan2(d_y, d_x),   tilt = atan2(-d_z, ||d_xy||),   R_WC = R_z(pan) R_y(tilt),

so the look point projects onto the principal point and the image is kept level (no roll). The gimbal reaches the
whole lower hemisphere: tilt is clipped to ``[0, pi/2]`` (a look point above the camera is watched at the horizon,
in its direction), and straight down (``d_xy = 0``) the pan is the heading. It slews at once (no rate limit, no
lag). Without a look point (no estimate yet, or one straight above the optical centre or at it) the camera takes
its ``"body"`` pose (``stabilised``, ``gimbal_pitch``), which is otherwise unused in this mode.

With ``classify`` (:class:`~autonomy.sensing.classify.Classifier` of ``"colour"`` and / or ``"body"``), every
detection also carries the camera's readings of the car's paint colour and body type (``Detection.classes``) of
the target the blob came from (a blob of no target, or of a static decoy, reads uniform classes). The detector
itself stays the colour-keyed blob finder above (every car is rendered in :data:`CAR_RGBA`): the readings are
simulated from the target's true classes through the confusion matrix, drawn from the generator
:func:`~autonomy.sensing.classify.class_generator` spawns from the frame's, so the centroid noise of this and every
later frame is the same with classification on or off.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

from autonomy.estimation.measurements import BearingDetectionModel
from interfaces.state import TargetEstimate

from .classify import Classifier, check_classifiers, class_generator, read_classes
from .coverage import FrameCoverage
from .measurement import CLUTTER_ID, Detection, Sensor, SensorOutput, azimuth_elevation
from .scene import CameraIntrinsics, CameraPose, RenderedImage, SceneQuery, SensorPose, TargetTruth, yaw_rot

__all__ = [
    "CAMERA_ATTRIBUTES",
    "CAMERA_POINTINGS",
    "CAR_RGBA",
    "GROUND_Z_M",
    "Blob",
    "Camera",
    "CameraConfig",
    "camera_pose",
    "detect_blobs",
    "look_point",
]

CAMERA_ATTRIBUTES: tuple[str, ...] = ("colour", "body")
"""The class attributes a camera may read: the paint colour and the body type."""

CAMERA_POINTINGS: tuple[str, ...] = ("body", "track")
"""Where the gimbal points: fixed to the airframe or the heading (``"body"``), or at the UAV's target estimate
(``"track"``)."""

GROUND_Z_M = 0.0
"""Height of the (flat) ground the look point of a horizontal target estimate is put on (m)."""

CAR_RGBA: tuple[float, float, float, float] = (1.0, 0.0, 1.0, 1.0)
"""Colour of every car body in the simulator (RGBA in [0, 1]): saturated magenta, OpenCV hue 150."""


def _rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@dataclass(frozen=True, kw_only=True)
class CameraConfig:
    """Camera parameters.

    Attributes
    ----------
    width, height : int
        Image size (px).
    hfov : float
        Horizontal field of view (rad); square pixels.
    gimbal_pitch : float
        Downward tilt of the optical axis below the horizontal (rad), in [-pi/2, pi/2].
    stabilised : bool
        True: gimbal keeps the camera level and follows the heading; False: fixed to the airframe.
    mount_offset_B : tuple[float, float, float]
        Optical centre in the body frame (m).
    rate_hz : float
        Frames per second (Hz).
    pixel_sigma : float
        Standard deviation of the simulated blob-centroid noise per axis (px).
    centroid_model_sigma : float
        Standard deviation (px) of the centroid-to-reference-point offset, added to ``R`` only.
    near, far : float
        Render clip distances (m).
    hsv_low, hsv_high : tuple[int, int, int]
        Inclusive HSV thresholds of the car colour (OpenCV ranges).
    min_blob_area_px : int
        Smallest blob accepted as a car (px).
    latency_s : float
        Delay from exposure to arrival (s).
    keep_frame : bool
        Put the rendered frame in ``SensorOutput.extras["frame"]`` (for video and debugging).
    classify : tuple[Classifier, ...]
        Class readings attached to every detection (attributes of :data:`CAMERA_ATTRIBUTES`); empty: none, and no
        random number is drawn for them.
    pointing : str
        ``"body"``: the optical axis is fixed by ``gimbal_pitch`` and ``stabilised``; ``"track"``: the gimbal points
        it at the pose's look point, falling back to ``"body"`` without one (module docstring).
    """

    width: int = 160
    height: int = 120
    hfov: float = np.deg2rad(60.0)
    gimbal_pitch: float = np.deg2rad(45.0)
    stabilised: bool = True
    mount_offset_B: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rate_hz: float = 10.0
    pixel_sigma: float = 0.5
    centroid_model_sigma: float = 1.0
    near: float = 0.1
    far: float = 1000.0
    hsv_low: tuple[int, int, int] = (140, 120, 40)
    hsv_high: tuple[int, int, int] = (160, 255, 255)
    min_blob_area_px: int = 2
    latency_s: float = 0.0
    keep_frame: bool = False
    classify: tuple[Classifier, ...] = ()
    pointing: str = "body"

    def __post_init__(self) -> None:
        if self.pointing not in CAMERA_POINTINGS:
            raise ValueError(f"CameraConfig.pointing must be one of {CAMERA_POINTINGS}, got {self.pointing!r}")
        object.__setattr__(self, "classify", check_classifiers("CameraConfig", self.classify, CAMERA_ATTRIBUTES))
        if self.width < 1 or self.height < 1:
            raise ValueError(f"CameraConfig size must be >= 1 px, got {self.width}x{self.height}")
        if not (0 < self.hfov < np.pi):
            raise ValueError(f"CameraConfig.hfov must be in (0, pi) rad, got {self.hfov}")
        if not (-np.pi / 2 <= self.gimbal_pitch <= np.pi / 2):
            raise ValueError(f"CameraConfig.gimbal_pitch must be in [-pi/2, pi/2] rad, got {self.gimbal_pitch}")
        if not (self.rate_hz > 0):
            raise ValueError(f"CameraConfig.rate_hz must be > 0, got {self.rate_hz}")
        if not (self.pixel_sigma >= 0):
            raise ValueError(f"CameraConfig.pixel_sigma must be >= 0 px, got {self.pixel_sigma}")
        if not (self.centroid_model_sigma >= 0) or self.pixel_sigma + self.centroid_model_sigma <= 0:
            raise ValueError(
                "CameraConfig.centroid_model_sigma must be >= 0 px with a positive total, "
                f"got {self.centroid_model_sigma}"
            )
        for name in ("hsv_low", "hsv_high"):
            v = getattr(self, name)
            if len(v) != 3 or not all(0 <= c <= 255 for c in v) or v[0] > 179:
                raise ValueError(f"CameraConfig.{name} must be (H <= 179, S, V) in OpenCV ranges, got {v}")
        if any(lo > hi for lo, hi in zip(self.hsv_low, self.hsv_high, strict=True)):
            raise ValueError(f"CameraConfig.hsv_low {self.hsv_low} must not exceed hsv_high {self.hsv_high}")
        if not (0 < self.near < self.far):
            raise ValueError(f"CameraConfig needs 0 < near < far, got near={self.near}, far={self.far}")
        if self.min_blob_area_px < 1:
            raise ValueError(f"CameraConfig.min_blob_area_px must be >= 1, got {self.min_blob_area_px}")
        if not (self.latency_s >= 0):
            raise ValueError(f"CameraConfig.latency_s must be >= 0, got {self.latency_s}")

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return CameraIntrinsics.from_hfov(self.width, self.height, self.hfov, near=self.near, far=self.far)


def camera_pose(config: CameraConfig, pose: SensorPose) -> CameraPose:
    """Camera pose of a camera mounted on the body at ``pose`` (see the module docstring for the gimbal)."""
    R_WB = pose.R_WB
    p_C = pose.p_W + R_WB @ np.asarray(config.mount_offset_B)
    if config.pointing == "track" and pose.look_at_W is not None:
        d = pose.look_at_W - p_C
        horizontal = float(np.hypot(d[0], d[1]))
        if horizontal > 0.0 or d[2] < 0.0:
            pan = float(np.arctan2(d[1], d[0])) if horizontal > 0.0 else pose.yaw
            tilt = float(np.clip(np.arctan2(-d[2], horizontal), 0.0, np.pi / 2))
            return CameraPose(p_W=p_C, R_WC=yaw_rot(pan) @ _rot_y(tilt))
    base = yaw_rot(pose.yaw) if config.stabilised else R_WB
    return CameraPose(p_W=p_C, R_WC=base @ _rot_y(config.gimbal_pitch))


def look_point(estimate: TargetEstimate | None, t: float) -> np.ndarray | None:
    """Where a target-cued gimbal points at time ``t`` (s): the estimate carried forward at constant velocity to
    ``t``, ``p + v (t - t_est)`` (m), on the ground (:data:`GROUND_Z_M`) when the estimate is horizontal; None
    without an estimate."""
    if estimate is None:
        return None
    p = estimate.p_W + (t - estimate.t) * estimate.v_W
    return p if p.size == 3 else np.array([p[0], p[1], GROUND_Z_M])


@dataclass(frozen=True, kw_only=True)
class Blob:
    """A connected region of car-coloured pixels.

    Attributes
    ----------
    centroid : np.ndarray
        (2,) centroid (u, v) in continuous pixel coordinates (px).
    box : np.ndarray
        (4,) ``[u_min, v_min, u_max, v_max]`` (px).
    area : int
        Pixel count.
    mask : np.ndarray
        (H, W) bool pixels of the blob.
    """

    centroid: np.ndarray
    box: np.ndarray
    area: int
    mask: np.ndarray


def detect_blobs(
    rgb: np.ndarray, hsv_low: tuple[int, int, int], hsv_high: tuple[int, int, int], min_area: int
) -> list[Blob]:
    """Blobs of pixels whose HSV colour lies in ``[hsv_low, hsv_high]`` in an (H, W, 3) uint8 RGB image."""
    hsv = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2HSV)
    mask = cv2.inRange(hsv, np.array(hsv_low, np.uint8), np.array(hsv_high, np.uint8))
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
    blobs = []
    for k in range(1, n):
        area = int(stats[k, cv2.CC_STAT_AREA])
        if area < min_area:
            continue
        x, y, w, h = (
            int(stats[k, c]) for c in (cv2.CC_STAT_LEFT, cv2.CC_STAT_TOP, cv2.CC_STAT_WIDTH, cv2.CC_STAT_HEIGHT)
        )
        blobs.append(
            Blob(centroid=centroids[k] + 0.5, box=np.array([x, y, x + w, y + h], float), area=area, mask=labels == k)
        )
    return blobs


class Camera(Sensor):
    """Colour-detecting camera (module docstring)."""

    def __init__(self, config: CameraConfig, sensor_id: str = "camera"):
        self.config = config
        self.sensor_id = sensor_id
        self.rate_hz = config.rate_hz
        self.latency_s = config.latency_s
        self.intrinsics = config.intrinsics
        self.model = BearingDetectionModel(dim=2, name="camera")  # [az, el] of the blob's centroid ray

    def look_point(self, estimate: TargetEstimate | None, t: float) -> np.ndarray | None:
        """The look point this camera's gimbal takes at ``t`` (s) from its UAV's target estimate (:func:`look_point`);
        None when it does not point at the track."""
        return look_point(estimate, t) if self.config.pointing == "track" else None

    def bearing_of_pixel(self, uv: np.ndarray, cam: CameraPose) -> np.ndarray:
        """World azimuth and elevation (N, 2) (rad) of the rays through pixels ``uv`` (N, 2)."""
        d_W = self.intrinsics.ray_C(uv) @ cam.R_WC.T
        az, el = azimuth_elevation(d_W)
        return np.column_stack([az, el])

    def _covariance(self, uv: np.ndarray, cam: CameraPose) -> np.ndarray:
        h = 1e-3
        du = self.bearing_of_pixel(np.array([uv + [h, 0], uv - [h, 0]]), cam)
        dv = self.bearing_of_pixel(np.array([uv + [0, h], uv - [0, h]]), cam)
        ju = du[0] - du[1]
        ju[0] = (ju[0] + np.pi) % (2 * np.pi) - np.pi
        jv = dv[0] - dv[1]
        jv[0] = (jv[0] + np.pi) % (2 * np.pi) - np.pi
        J = np.column_stack([ju, jv]) / (2 * h)
        return (self.config.pixel_sigma**2 + self.config.centroid_model_sigma**2) * (J @ J.T)

    def _associate(self, blob: Blob, frame: RenderedImage, cam: CameraPose, targets: TargetTruth) -> int:
        if targets.seg_ids is not None:
            labels, counts = np.unique(frame.seg[blob.mask], return_counts=True)
            for lab in labels[np.argsort(-counts)]:
                hit = np.flatnonzero(targets.seg_ids == lab)
                if hit.size:
                    return int(targets.ids[hit[0]])
            return CLUTTER_ID
        if len(targets) == 0:
            return CLUTTER_ID
        uv = self.intrinsics.project((targets.p_W - cam.p_W) @ cam.R_WC)
        u0, v0, u1, v1 = blob.box + np.array([-2.0, -2.0, 2.0, 2.0])
        inside = (uv[:, 0] >= u0) & (uv[:, 0] <= u1) & (uv[:, 1] >= v0) & (uv[:, 1] <= v1)
        if not np.any(inside):
            return CLUTTER_ID
        dist = np.where(inside, np.linalg.norm(uv - blob.centroid, axis=1), np.inf)
        return int(targets.ids[int(np.argmin(dist))])

    def measure(
        self, tick_time_s: float, pose: SensorPose, targets: TargetTruth, scene: SceneQuery, rng: np.random.Generator
    ) -> SensorOutput:
        cfg = self.config
        cam = camera_pose(cfg, pose)
        frame = scene.render(cam, self.intrinsics)
        blobs = detect_blobs(frame.rgb, cfg.hsv_low, cfg.hsv_high, cfg.min_blob_area_px)
        dets, ids = [], []
        for blob in blobs:
            duv = cfg.pixel_sigma * rng.standard_normal(2)
            uv = blob.centroid + duv
            z = self.bearing_of_pixel(uv[None, :], cam)[0]
            dets.append(
                Detection(
                    z=z,
                    R=self._covariance(uv, cam),
                    t_meas=tick_time_s,
                    t_arrival=tick_time_s + cfg.latency_s,
                    sensor_id=self.sensor_id,
                    p_sensor_W=cam.p_W,
                    model=self.model,
                    pixel_box=blob.box + np.tile(duv, 2),
                )
            )
            ids.append(self._associate(blob, frame, cam, targets))
        if cfg.classify and dets:
            readings = read_classes(cfg.classify, ids, targets, class_generator(rng))
            dets = [replace(d, classes=c) for d, c in zip(dets, readings, strict=True)]
        extras = {"frame": frame, "camera_pose": cam} if cfg.keep_frame else {}
        extras["coverage"] = FrameCoverage(t_meas=tick_time_s, t_arrival=tick_time_s + cfg.latency_s,
                                           sensor_id=self.sensor_id, camera=cam, intrinsics=self.intrinsics,
                                           depth=frame.depth, min_blob_area_px=cfg.min_blob_area_px)
        return SensorOutput(detections=tuple(dets), truth_ids=np.asarray(ids, dtype=int), extras=extras)
