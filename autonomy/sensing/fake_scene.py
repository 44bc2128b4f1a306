"""An exact, engine-free :class:`~autonomy.sensing.scene.SceneQuery` for tests.

Buildings are prisms (``worlds.geometry.Building``: a footprint extruded from ``base_z`` to ``top_z``). A
non-convex footprint is split into convex pieces (constrained Delaunay triangles); each convex prism is the
intersection of half-spaces ``n_k . x <= c_k`` and a segment ``x(t) = a + t (b - a)``, ``t in [0, 1]``, is clipped
against it by Cyrus-Beck: ``t_in = max over entering planes``, ``t_out = min over leaving planes``. The segment is
cut when ``t_in < t_out`` (a segment that only touches a face is not cut).

``render`` casts one ray per pixel against the ground plane, the buildings and optional coloured boxes (cars),
with flat colours: enough to exercise a colour-threshold detector without a renderer.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from worlds.geometry import Building

from .scene import CameraIntrinsics, CameraPose, RenderedImage

__all__ = ["FakeScene", "SceneBox", "convex_prisms", "segment_prism_interval"]

GROUND_RGB = (110, 110, 110)
BUILDING_RGB = (175, 170, 160)
SKY_RGB = (200, 220, 255)
GROUND_SEG = 0
BUILDING_SEG_OFFSET = 1000


@dataclass(frozen=True, kw_only=True)
class SceneBox:
    """A coloured movable box (a car) in a :class:`FakeScene`; never an occluder for ``line_of_sight``.

    Attributes
    ----------
    center_W : tuple[float, float, float]
        Box centre (m).
    size : tuple[float, float, float]
        Full length along ``yaw``, width, height (m).
    yaw : float
        Heading (rad).
    rgb : tuple[int, int, int]
        Flat colour (0-255).
    seg_id : int
        Label written to the segmentation mask.
    """

    center_W: tuple[float, float, float]
    size: tuple[float, float, float]
    yaw: float = 0.0
    rgb: tuple[int, int, int] = (255, 0, 255)
    seg_id: int = 1

    def __post_init__(self) -> None:
        if any(s <= 0 for s in self.size):
            raise ValueError(f"SceneBox.size must be positive, got {self.size}")

    def as_building(self) -> Building:
        cx, cy, cz = self.center_W
        return Building.cuboid((cx, cy), self.size, yaw=self.yaw, base_z=cz - self.size[2] / 2)


@dataclass(frozen=True)
class _Prism:
    normals: np.ndarray  # (K, 3) outward
    offsets: np.ndarray  # (K,)


def convex_prisms(building: Building) -> list[_Prism]:
    """Half-space descriptions of the convex pieces of ``building``."""
    fp = np.asarray(building.footprint)
    poly = shapely.Polygon(fp)
    if poly.convex_hull.area - poly.area <= 1e-9 * max(poly.area, 1.0):
        pieces = [fp]
    else:
        tris = shapely.get_parts(shapely.constrained_delaunay_triangles(poly))
        pieces = [np.asarray(t.exterior.coords)[:-1] for t in tris]
    out = []
    for pts in pieces:
        if shapely.Polygon(pts).exterior.is_ccw is False:
            pts = pts[::-1]
        nxt = np.roll(pts, -1, axis=0)
        e = nxt - pts
        n2 = np.column_stack([e[:, 1], -e[:, 0]])  # outward for a counter-clockwise polygon
        n2 /= np.linalg.norm(n2, axis=1, keepdims=True)
        normals = np.vstack([np.column_stack([n2, np.zeros(len(n2))]), [[0, 0, 1.0], [0, 0, -1.0]]])
        offsets = np.concatenate([np.sum(n2 * pts, axis=1), [building.top_z, -building.base_z]])
        out.append(_Prism(normals=normals, offsets=offsets))
    return out


def segment_prism_interval(a: np.ndarray, b: np.ndarray, prism: _Prism) -> tuple[np.ndarray, np.ndarray]:
    """Cyrus-Beck clip of segments ``a -> b`` ((N, 3) each) against a convex prism.

    Returns ``(t_in, t_out)`` (N,) with the part inside the prism being ``t in [t_in, t_out]``; empty when
    ``t_in >= t_out``. Parameters are clipped to [0, 1].
    """
    d = b - a
    num = prism.offsets[None, :] - a @ prism.normals.T  # (N, K): n.a <= c  <=>  num >= 0
    den = d @ prism.normals.T  # (N, K)
    t_in = np.zeros(len(a))
    t_out = np.ones(len(a))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = num / den
    entering = den < 0
    leaving = den > 0
    parallel_out = (den == 0) & (num < 0)
    t_in = np.maximum(t_in, np.max(np.where(entering, t, -np.inf), axis=1))
    t_out = np.minimum(t_out, np.min(np.where(leaving, t, np.inf), axis=1))
    t_out = np.where(np.any(parallel_out, axis=1), -np.inf, t_out)
    return t_in, t_out


class FakeScene:
    """Exact scene made of prism buildings on a flat ground plane, plus optional coloured boxes.

    Parameters
    ----------
    buildings : Sequence[Building]
        Static occluders.
    boxes : Sequence[SceneBox]
        Movable coloured boxes (cars); rendered, never occluding ``line_of_sight``.
    ground_z : float
        Height of the ground plane (m); the ground itself does not occlude ``line_of_sight`` (points above it).
    """

    def __init__(self, buildings: Sequence[Building] = (), boxes: Sequence[SceneBox] = (), ground_z: float = 0.0):
        self.buildings = tuple(buildings)
        self.boxes = tuple(boxes)
        self.ground_z = float(ground_z)
        self._of_building = [convex_prisms(b) for b in self.buildings]
        self._prisms = [(i, pr) for i, prisms in enumerate(self._of_building) for pr in prisms]
        self._box_prisms = [(j, pr) for j, bx in enumerate(self.boxes) for pr in convex_prisms(bx.as_building())]
        fp = [np.asarray(b.footprint, dtype=float) for b in self.buildings]
        self._lo = np.array([f.min(axis=0) for f in fp]).reshape(-1, 2)  # footprint bounding boxes
        self._hi = np.array([f.max(axis=0) for f in fp]).reshape(-1, 2)

    def with_boxes(self, boxes: Sequence[SceneBox]) -> FakeScene:
        """The same buildings with other movable boxes."""
        return FakeScene(self.buildings, boxes, self.ground_z)

    def line_of_sight(self, from_W: np.ndarray, to_W: np.ndarray) -> np.ndarray:
        a = np.atleast_2d(np.asarray(from_W, dtype=float))
        b = np.atleast_2d(np.asarray(to_W, dtype=float))
        if a.shape != b.shape or a.shape[1] != 3:
            raise ValueError(f"line_of_sight needs two (N, 3) arrays, got {a.shape} and {b.shape}")
        clear = np.ones(len(a), dtype=bool)
        if not self.buildings or not len(a):
            return clear
        # a segment can only cross a prism whose footprint's bounding box its own overlaps: the prism test runs on
        # those pairs alone (on a city map, a handful of 1,500 buildings per segment)
        seg_lo, seg_hi = np.minimum(a, b)[:, :2], np.maximum(a, b)[:, :2]
        overlap = np.all((self._lo[:, None] <= seg_hi[None]) & (seg_lo[None] <= self._hi[:, None]), axis=2)
        for k in np.flatnonzero(overlap.any(axis=1)):
            rows = np.flatnonzero(overlap[k])
            for pr in self._of_building[k]:
                t_in, t_out = segment_prism_interval(a[rows], b[rows], pr)
                clear[rows] &= ~(t_in < t_out)
        return clear

    def render(self, camera: CameraPose, intrinsics: CameraIntrinsics) -> RenderedImage:
        h, w = intrinsics.height, intrinsics.width
        jj, ii = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
        dirs_C = intrinsics.ray_C(np.column_stack([jj.ravel(), ii.ravel()]))
        dirs_C = dirs_C / dirs_C[:, :1]  # unit optical-axis component, so t below is the depth
        dirs_W = dirs_C @ camera.R_WC.T
        far = intrinsics.far
        a = np.repeat(camera.p_W[None, :], len(dirs_W), axis=0)
        b = a + far * dirs_W
        depth = np.full(len(a), far)
        rgb = np.tile(np.array(SKY_RGB, dtype=np.uint8), (len(a), 1))
        seg = np.full(len(a), -1, dtype=int)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_ground = (self.ground_z - a[:, 2]) / dirs_W[:, 2]
        hit = (t_ground > intrinsics.near) & (t_ground < depth)
        depth[hit], rgb[hit], seg[hit] = t_ground[hit], GROUND_RGB, GROUND_SEG
        for items, colour_of, seg_of in (
            (self._prisms, lambda i: BUILDING_RGB, lambda i: BUILDING_SEG_OFFSET + i),
            (self._box_prisms, lambda j: self.boxes[j].rgb, lambda j: self.boxes[j].seg_id),
        ):
            for idx, pr in items:
                t_in, t_out = segment_prism_interval(a, b, pr)
                t_hit = t_in * far
                hit = (t_in < t_out) & (t_hit > intrinsics.near) & (t_hit < depth)
                depth[hit], rgb[hit], seg[hit] = t_hit[hit], colour_of(idx), seg_of(idx)
        return RenderedImage(rgb=rgb.reshape(h, w, 3), depth=depth.reshape(h, w), seg=seg.reshape(h, w))
