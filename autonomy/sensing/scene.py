"""The narrow interface through which sensor models see the physical world.

Sensor models never touch the physics engine: they receive a :class:`SceneQuery` (line-of-sight raycasts and
camera rendering), the carrying body's :class:`SensorPose` and, for measurement generation only, the targets'
:class:`TargetTruth`. The simulator implements :class:`SceneQuery` with PyBullet; tests use
:class:`autonomy.sensing.fake_scene.FakeScene`.

Frames: world ENU (x east, y north, z up), body FLU, metres, radians, quaternions (x, y, z, w).
The camera frame ``C`` is FLU-like: x along the optical axis, y to the image's left, z to the image's top, so a
point ``p_C`` projects to pixel ``u = c_x - f_x p_y / p_x``, ``v = c_y - f_y p_z / p_x`` (``u`` to the right,
``v`` down, pixel ``(row i, column j)`` covering ``[j, j+1) x [i, i+1)``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = [
    "TARGET_KINDS",
    "CameraIntrinsics",
    "CameraPose",
    "RenderedImage",
    "SceneQuery",
    "SensorPose",
    "TargetTruth",
    "quat_to_rot",
    "yaw_rot",
]

TARGET_KINDS = ("car", "decoy")


def quat_to_rot(q_xyzw: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion (x, y, z, w); the quaternion is normalised first."""
    q = np.asarray(q_xyzw, dtype=float)
    x, y, z, w = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def yaw_rot(yaw: float) -> np.ndarray:
    """Rotation about +z by ``yaw`` rad (3x3)."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _vec(name: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
    arr = np.array(value, dtype=float)
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, kw_only=True)
class SensorPose:
    """Pose of the body carrying a sensor.

    Attributes
    ----------
    p_W : np.ndarray
        (3,) body position in the world frame (m).
    q_WB : np.ndarray
        (4,) body-to-world attitude quaternion (x, y, z, w).
    v_W : np.ndarray
        (3,) body velocity in the world frame (m/s); used for range-rate measurements. Defaults to zero.
    look_at_W : np.ndarray | None
        (3,) world point a target-cued gimbal points its sensor at (m): the carrier's own target estimate, handed in
        by the simulator only to sensors that point at the track; None (default): no cue, the sensor keeps its
        body-fixed or heading-stabilised pose.
    """

    p_W: np.ndarray
    q_WB: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 0.0, 1.0]))
    v_W: np.ndarray = field(default_factory=lambda: np.zeros(3))
    look_at_W: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "p_W", _vec("SensorPose.p_W", self.p_W, (3,)))
        q = _vec("SensorPose.q_WB", self.q_WB, (4,))
        n = float(np.linalg.norm(q))
        if abs(n - 1.0) > 1e-6:
            raise ValueError(f"SensorPose.q_WB must be a unit quaternion, got norm {n}")
        object.__setattr__(self, "q_WB", q)
        object.__setattr__(self, "v_W", _vec("SensorPose.v_W", self.v_W, (3,)))
        if self.look_at_W is not None:
            object.__setattr__(self, "look_at_W", _vec("SensorPose.look_at_W", self.look_at_W, (3,)))

    @property
    def R_WB(self) -> np.ndarray:
        """(3, 3) body-to-world rotation."""
        return quat_to_rot(self.q_WB)

    @property
    def yaw(self) -> float:
        """Heading of the body x axis, counter-clockwise from +x (rad)."""
        R = self.R_WB
        return float(np.arctan2(R[1, 0], R[0, 0]))


@dataclass(frozen=True, kw_only=True)
class TargetTruth:
    """Ground truth of the targets, handed to measurement generation only (never to estimators).

    Attributes
    ----------
    ids : np.ndarray
        (M,) integer target identifiers (>= 0).
    p_W : np.ndarray
        (M, 3) reference points (body centres) in the world frame (m).
    v_W : np.ndarray
        (M, 3) velocities in the world frame (m/s).
    kind : tuple[str, ...]
        (M,) ``"car"`` or ``"decoy"``.
    yaw : np.ndarray
        (M,) headings (rad).
    cone_axis_W : np.ndarray | None
        (M, 3) unit axis of each decoy's visibility cone (rows of cars are ignored); ``None``: decoys are visible
        from every direction.
    cone_half_angle : np.ndarray | None
        (M,) half aperture of each visibility cone (rad), required with ``cone_axis_W``.
    seg_ids : np.ndarray | None
        (M,) label of each target in rendered segmentation masks (the simulator's body ids), for truth association.
    attributes : dict[str, np.ndarray] | None
        Class attributes a sensor may read, by name (``"colour"``, ``"body"``, ``"length"``): (M,) class index of
        each target (``worlds.catalog`` lists the classes; -1: the attribute does not apply, e.g. a static decoy).
    """

    ids: np.ndarray
    p_W: np.ndarray
    v_W: np.ndarray
    kind: tuple[str, ...]
    yaw: np.ndarray
    cone_axis_W: np.ndarray | None = None
    cone_half_angle: np.ndarray | None = None
    seg_ids: np.ndarray | None = None
    attributes: dict[str, np.ndarray] | None = None

    def __post_init__(self) -> None:
        ids = np.array(self.ids, dtype=int).reshape(-1)
        m = ids.size
        object.__setattr__(self, "ids", ids)
        object.__setattr__(self, "p_W", _vec("TargetTruth.p_W", np.reshape(self.p_W, (m, 3)), (m, 3)))
        object.__setattr__(self, "v_W", _vec("TargetTruth.v_W", np.reshape(self.v_W, (m, 3)), (m, 3)))
        object.__setattr__(self, "yaw", _vec("TargetTruth.yaw", np.reshape(self.yaw, (m,)), (m,)))
        kind = tuple(self.kind)
        if len(kind) != m or any(k not in TARGET_KINDS for k in kind):
            raise ValueError(f"TargetTruth.kind must be {m} entries of {TARGET_KINDS}, got {kind}")
        object.__setattr__(self, "kind", kind)
        if np.any(ids < 0):
            raise ValueError(f"TargetTruth.ids must be >= 0, got {ids}")
        if (self.cone_axis_W is None) != (self.cone_half_angle is None):
            raise ValueError("TargetTruth.cone_axis_W and cone_half_angle must be given together")
        if self.cone_axis_W is not None:
            axis = _vec("TargetTruth.cone_axis_W", np.reshape(self.cone_axis_W, (m, 3)), (m, 3))
            axis = axis / np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-12)
            object.__setattr__(self, "cone_axis_W", axis)
            object.__setattr__(
                self,
                "cone_half_angle",
                _vec("TargetTruth.cone_half_angle", np.reshape(self.cone_half_angle, (m,)), (m,)),
            )
        if self.seg_ids is not None:
            object.__setattr__(self, "seg_ids", np.array(self.seg_ids, dtype=int).reshape(m))
        if self.attributes is not None:
            attrs = {}
            for name, values in self.attributes.items():
                a = np.array(values, dtype=int).reshape(-1)
                if a.size != m:
                    raise ValueError(f"TargetTruth.attributes[{name!r}] must have {m} entries, got {a.size}")
                a.setflags(write=False)
                attrs[str(name)] = a
            object.__setattr__(self, "attributes", attrs)

    def __len__(self) -> int:
        return int(self.ids.size)

    @classmethod
    def empty(cls) -> TargetTruth:
        """No targets."""
        return cls(ids=np.zeros(0, int), p_W=np.zeros((0, 3)), v_W=np.zeros((0, 3)), kind=(), yaw=np.zeros(0))


@dataclass(frozen=True, kw_only=True)
class CameraIntrinsics:
    """Pinhole intrinsics with square pixels.

    Attributes
    ----------
    width, height : int
        Image size (px).
    fx, fy : float
        Focal lengths (px).
    cx, cy : float
        Principal point (px, continuous coordinates: the image spans ``[0, width] x [0, height]``).
    near, far : float
        Clip distances of the renderer (m).
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    near: float = 0.1
    far: float = 2000.0

    def __post_init__(self) -> None:
        if self.width < 1 or self.height < 1:
            raise ValueError(f"CameraIntrinsics size must be >= 1 px, got {self.width}x{self.height}")
        if not (self.fx > 0 and self.fy > 0):
            raise ValueError(f"CameraIntrinsics focal lengths must be > 0, got fx={self.fx}, fy={self.fy}")
        if not (0 < self.near < self.far):
            raise ValueError(f"CameraIntrinsics needs 0 < near < far, got near={self.near}, far={self.far}")

    @classmethod
    def from_hfov(
        cls, width: int, height: int, hfov: float, near: float = 0.1, far: float = 2000.0
    ) -> CameraIntrinsics:
        """Square-pixel intrinsics from the image size (px) and horizontal field of view ``hfov`` (rad).

        ``f = (width / 2) / tan(hfov / 2)``, principal point at the image centre.
        """
        if not (0 < hfov < np.pi):
            raise ValueError(f"hfov must be in (0, pi) rad, got {hfov}")
        f = 0.5 * width / np.tan(0.5 * hfov)
        return cls(width=width, height=height, fx=f, fy=f, cx=0.5 * width, cy=0.5 * height, near=near, far=far)

    @property
    def vfov(self) -> float:
        """Vertical field of view (rad): ``2 atan(height / (2 f_y))``."""
        return float(2.0 * np.arctan(0.5 * self.height / self.fy))

    @property
    def hfov(self) -> float:
        """Horizontal field of view (rad)."""
        return float(2.0 * np.arctan(0.5 * self.width / self.fx))

    def project(self, p_C: np.ndarray) -> np.ndarray:
        """Pixels (N, 2) of camera-frame points (N, 3); NaN for points behind the camera."""
        p = np.atleast_2d(np.asarray(p_C, dtype=float))
        with np.errstate(divide="ignore", invalid="ignore"):
            u = self.cx - self.fx * p[:, 1] / p[:, 0]
            v = self.cy - self.fy * p[:, 2] / p[:, 0]
        uv = np.column_stack([u, v])
        uv[p[:, 0] <= 0] = np.nan
        return uv

    def ray_C(self, uv: np.ndarray) -> np.ndarray:
        """Unit camera-frame directions (N, 3) through pixels ``uv`` (N, 2)."""
        uv = np.atleast_2d(np.asarray(uv, dtype=float))
        d = np.column_stack([np.ones(len(uv)), (self.cx - uv[:, 0]) / self.fx, (self.cy - uv[:, 1]) / self.fy])
        return d / np.linalg.norm(d, axis=1, keepdims=True)


@dataclass(frozen=True, kw_only=True)
class CameraPose:
    """Camera position and orientation.

    Attributes
    ----------
    p_W : np.ndarray
        (3,) optical centre in the world frame (m).
    R_WC : np.ndarray
        (3, 3) camera-to-world rotation; columns are the optical axis, image-left and image-up directions.
    """

    p_W: np.ndarray
    R_WC: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "p_W", _vec("CameraPose.p_W", self.p_W, (3,)))
        R = _vec("CameraPose.R_WC", self.R_WC, (3, 3))
        if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ValueError("CameraPose.R_WC must be a rotation matrix")
        object.__setattr__(self, "R_WC", R)

    @property
    def forward_W(self) -> np.ndarray:
        return self.R_WC[:, 0]

    @property
    def up_W(self) -> np.ndarray:
        return self.R_WC[:, 2]


@dataclass(frozen=True, kw_only=True)
class RenderedImage:
    """One rendered frame.

    Attributes
    ----------
    rgb : np.ndarray
        (H, W, 3) uint8 colour image, row 0 at the top.
    depth : np.ndarray
        (H, W) float distance along the optical axis (m); ``far`` where nothing was hit.
    seg : np.ndarray
        (H, W) int segmentation labels (scene body ids, -1 for background); for tests and truth only.
    """

    rgb: np.ndarray
    depth: np.ndarray
    seg: np.ndarray

    def __post_init__(self) -> None:
        if self.rgb.ndim != 3 or self.rgb.shape[2] != 3 or self.rgb.dtype != np.uint8:
            raise ValueError(f"RenderedImage.rgb must be (H, W, 3) uint8, got {self.rgb.shape} {self.rgb.dtype}")
        if self.depth.shape != self.rgb.shape[:2] or self.seg.shape != self.rgb.shape[:2]:
            raise ValueError(
                f"RenderedImage depth {self.depth.shape} and seg {self.seg.shape} must match rgb {self.rgb.shape[:2]}"
            )


@runtime_checkable
class SceneQuery(Protocol):
    """What a sensor model may ask of the physical world."""

    def line_of_sight(self, from_W: np.ndarray, to_W: np.ndarray) -> np.ndarray:
        """(N,) bool for segments ``from_W[i] -> to_W[i]`` ((N, 3) each, m): True if no static occluder cuts it."""
        ...

    def render(self, camera: CameraPose, intrinsics: CameraIntrinsics) -> RenderedImage:
        """Render the scene seen by ``camera``."""
        ...
