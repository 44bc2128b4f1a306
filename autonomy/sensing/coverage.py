"""Where a camera frame could have seen a car: the frame's coverage, for negative information.

A frame that shows no car where a track predicts one tells the tracker something, but only where the camera could
have seen it: inside the image, in front of the camera, near enough for the car's blob to reach the detector's
smallest area, and not hidden behind something nearer along the ray (a building). :class:`FrameCoverage` keeps what
the camera knew when it took the frame (its pose, intrinsics and depth image) and answers
:meth:`FrameCoverage.visible` for ground points: the depth image is the renderer's, as a real system would
predict it from the city model it flies over; it is never truth about the cars (a car standing at the point shows
at its own depth, which the test allows for).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scene import CameraIntrinsics, CameraPose

__all__ = ["CAR_TOP_AREA_M2", "DEPTH_TOLERANCE_M", "FrameCoverage"]

DEPTH_TOLERANCE_M = 3.0
"""m: a point counts as hidden when the depth image at its pixel is nearer than the point by more than this (a car's
half-length and a margin: a car standing at the point, seen end on, is at most this much nearer than its centre)."""

CAR_TOP_AREA_M2 = 8.0
"""m²: the top of the smallest car the detector should find (a sedan, 4.5 m × 1.8 m), for the range at which its
blob reaches the detector's smallest area."""


@dataclass(frozen=True, kw_only=True)
class FrameCoverage:
    """One camera frame's coverage.

    Attributes
    ----------
    t_meas : float
        Exposure time (s).
    t_arrival : float
        When the frame's detections reach the estimator (s).
    sensor_id : str
        The camera's id (as its detections').
    camera : CameraPose
        Where the camera was and looked.
    intrinsics : CameraIntrinsics
        Its pinhole model.
    depth : np.ndarray
        (H, W) distance along the optical axis (m) of what each pixel shows; ``intrinsics.far`` where nothing.
    min_blob_area_px : float
        Smallest blob the detector accepts (px).
    """

    t_meas: float
    t_arrival: float
    sensor_id: str
    camera: CameraPose
    intrinsics: CameraIntrinsics
    depth: np.ndarray
    min_blob_area_px: float

    def __post_init__(self) -> None:
        if self.depth.shape != (self.intrinsics.height, self.intrinsics.width):
            raise ValueError(f"FrameCoverage.depth is {self.depth.shape}, the intrinsics say "
                             f"{(self.intrinsics.height, self.intrinsics.width)}")
        if not self.t_arrival >= self.t_meas:
            raise ValueError(f"FrameCoverage.t_arrival {self.t_arrival} is before t_meas {self.t_meas}")

    def visible(self, p_W: np.ndarray) -> np.ndarray:
        """(N,) bool: whether a car at each of the points ``p_W`` ((N, 3) m, its centre) would have been in view.

        In view: in front of the camera, its pixel inside the image, its top's projected area (``CAR_TOP_AREA_M2``
        foreshortened by the elevation of the view) at least twice the detector's smallest blob, and the depth image
        at its pixel no nearer than the point's depth less :data:`DEPTH_TOLERANCE_M`.
        """
        p = np.atleast_2d(np.asarray(p_W, dtype=float))
        K = self.intrinsics
        d_W = p - self.camera.p_W
        d_C = d_W @ self.camera.R_WC  # rows: R_WCᵀ d
        x = d_C[:, 0]
        ahead = x > K.near
        with np.errstate(divide="ignore", invalid="ignore"):
            u = K.cx - K.fx * d_C[:, 1] / x
            v = K.cy - K.fy * d_C[:, 2] / x
        inside = ahead & (u >= 0) & (u < K.width) & (v >= 0) & (v < K.height)
        r = np.linalg.norm(d_W, axis=1)
        sin_el = np.abs(d_W[:, 2]) / np.maximum(r, 1e-9)
        area = (K.fx * K.fy / np.maximum(x, 1e-9) ** 2) * CAR_TOP_AREA_M2 * sin_el
        out = inside & (area >= 2.0 * self.min_blob_area_px)
        idx = np.flatnonzero(out)
        if idx.size:
            col = np.minimum(u[idx].astype(int), K.width - 1)
            row = np.minimum(v[idx].astype(int), K.height - 1)
            out[idx] = self.depth[row, col] >= x[idx] - DEPTH_TOLERANCE_M
        return out
