"""The replay stage: a PyBullet DIRECT client holding the static scene and visual-only bodies posed from the record.

The static scene is built once from the run directory's ``geometry.npz`` (building footprints with heights, road
centre-lines) in a :class:`simulator.scene.Scene` client. Buildings are drawn as flat-shaded triangle soups (one vertex
per face corner, so walls and roofs take different light), roads as strips around their centre-lines. The ground is not
a body: pixels the renderer left empty are painted ground or sky by the direction of their viewing ray
(:func:`ground_mask`), which costs less than rasterising one screen-filling polygon and has no shadow-map seams.
UAVs are drawn as X-frames (two crossed arms and a hub, coloured per UAV, enlarged ``uav_scale`` times) and cars as
boxes in the car colour; they carry no collision shapes and are moved with ``resetBasePositionAndOrientation``.

Two renderers: TinyRenderer (software, always there) and the EGL plugin (:func:`simulator.scene_query.try_load_egl`).
On machines without a GPU the EGL plugin runs on Mesa's llvmpipe and crashes on visual meshes given as vertex lists,
so with EGL the buildings and roads are written as OBJ files and loaded by file name instead; the plugin only draws
bodies created after it loaded, so it is loaded before any visual body is made.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pybullet as p
import trimesh

from autonomy.sensing.camera import CAR_RGBA
from simulator.render.projection import CameraView, perspective, to_gl
from simulator.runrecord import RecordError
from simulator.scene import BUILDING_RGBA, GROUND_RGBA, ROAD_RGBA, Scene, SceneConfig, _extrude
from simulator.scene_query import try_load_egl
from worlds.geometry import Building

__all__ = ["SKY_RGB", "UAV_COLORS", "Stage", "StaticGeometry", "ground_level_mask", "ground_mask", "load_geometry",
           "pixel_ray_z", "ribbon_mesh"]

SKY_RGB = (0.72, 0.82, 0.93)
_EMPTY_DEPTH = 1.0 - 1e-7  # depth-buffer value of pixels nothing was drawn on
_CHUNK = 256  # buildings per visual mesh
_ROAD_Z = 0.03  # m, road strips just above the ground
_GROUND_LEVEL_Z = 0.25  # m: a drawn surface below this height is ground level (roads), for overlays of ground regions
_LIGHT_DIR = (-0.45, -0.75, 1.0)  # towards the light (sun in the south-south-west, high): walls and roofs differ

# RGB in [0, 1] per UAV index (matplotlib's tab10, as in the run's plots)
UAV_COLORS = ((0.12, 0.47, 0.71), (1.0, 0.50, 0.05), (0.17, 0.63, 0.17), (0.58, 0.40, 0.74), (0.55, 0.34, 0.29),
              (0.89, 0.47, 0.76), (0.74, 0.74, 0.13), (0.09, 0.75, 0.81))


def flat_mesh(buildings: Sequence[Building]) -> tuple[np.ndarray, np.ndarray]:
    """Buildings as a triangle soup for flat shading: vertices (3F, 3) m, three per face, and their face normals.

    Shared vertices would get normals averaged over the faces meeting there, which shades a box like a blob; one
    vertex per face corner keeps walls and roofs apart.
    """
    parts = [_extrude(b.footprint, b.base_z, b.top_z) for b in buildings]
    tri = np.concatenate([v[f] for v, f in parts])  # (F, 3, 3)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    return tri.reshape(-1, 3), np.repeat(n, 3, axis=0)


def ground_mask(view: CameraView, width: int, height: int, aspect: float) -> np.ndarray:
    """(H, W) bool: pixels whose viewing ray goes down, i.e. meets the flat ground z = 0 if nothing is in the way.

    Pixel (i, j) looks along ``f + x_i tan(vfov/2) aspect s + y_j tan(vfov/2) u`` (``s, u, f`` the camera's right,
    up and forward axes, ``x_i = 2 (i + 0.5) / W - 1``, ``y_j = 1 - 2 (j + 0.5) / H``); it sees ground where the
    ray's z component is negative.
    """
    return pixel_ray_z(view, width, height, aspect) < 0.0


def pixel_ray_z(view: CameraView, width: int, height: int, aspect: float) -> np.ndarray:
    """(H, W) z component of each pixel's viewing ray ``f + x_i tan(vfov/2) aspect s + y_j tan(vfov/2) u``."""
    V = view.view_matrix()
    right, up, fwd = V[0, :3], V[1, :3], -V[2, :3]
    ty = np.tan(view.vfov / 2.0)
    x = (2.0 * (np.arange(width) + 0.5) / width - 1.0) * ty * aspect
    y = (1.0 - 2.0 * (np.arange(height) + 0.5) / height) * ty
    return fwd[2] + x[None, :] * right[2] + y[:, None] * up[2]


def ground_level_mask(view: CameraView, zbuf: np.ndarray, empty: np.ndarray, ray_z: np.ndarray,
                      max_z: float) -> np.ndarray:
    """(H, W) bool: pixels that show the ground, nothing in front of it: painted ground (``empty`` pixels whose ray
    goes down) or a drawn surface below ``max_z`` m (roads). ``ray_z`` is the z component of each pixel's ray
    (:func:`pixel_ray_z`).

    A drawn pixel's surface lies at ``eye + d (f + x_i s + y_j u)`` (the ray of :func:`ground_mask`), ``d`` its
    distance along the optical axis from the depth buffer value ``z``: ``d = far near / (far − (far − near) z)``.
    """
    n, f = view.near, view.far
    d = f * n / (f - (f - n) * np.minimum(zbuf, _EMPTY_DEPTH))
    return np.where(empty, ray_z < 0.0, view.eye_W[2] + d * ray_z < max_z)


class StaticGeometry:
    """Buildings and road centre-lines of a run (``geometry.npz``)."""

    def __init__(self, buildings: list[Building], roads: list[np.ndarray], road_ids: list[str] | None = None) -> None:
        self.buildings = buildings
        self.roads = roads
        self.road_ids = list(road_ids) if road_ids is not None else [""] * len(roads)

    def bounds(self) -> tuple[float, float, float, float] | None:
        """(xmin, xmax, ymin, ymax) of all buildings and roads, m; None if there are none."""
        pts = [b.footprint for b in self.buildings] + [r[:, :2] for r in self.roads]
        if not pts:
            return None
        xy = np.concatenate(pts)
        return float(xy[:, 0].min()), float(xy[:, 0].max()), float(xy[:, 1].min()), float(xy[:, 1].max())


def _is_rectangle(fp: np.ndarray) -> bool:
    if len(fp) != 4:
        return False
    edges = np.roll(fp, -1, axis=0) - fp
    dots = np.abs(np.sum(edges * np.roll(edges, -1, axis=0), axis=1))
    return bool(np.all(dots <= 1e-6 * np.sum(edges**2, axis=1).max()))


def load_geometry(path: Path) -> StaticGeometry:
    """Buildings (cuboids where the footprint is a rectangle) and road centre-lines from ``geometry.npz``."""
    if not Path(path).exists():
        return StaticGeometry([], [])
    try:
        with np.load(path, allow_pickle=False) as g:
            bxy, bo, heights = g["building_xy"], g["building_offsets"], g["building_height"]
            rxy, ro = g["road_xy"], g["road_offsets"]
            ids = [str(r) for r in g["road_ids"]] if "road_ids" in g.files else None
    except (OSError, ValueError, EOFError, KeyError) as exc:  # zipfile.BadZipFile is an OSError
        raise RecordError(f"{path}: not a readable geometry file ({type(exc).__name__}: {exc})") from exc
    buildings = []
    for i in range(len(bo) - 1):
        fp = bxy[bo[i]:bo[i + 1]]
        h = float(heights[i])
        if _is_rectangle(fp):
            e0, e1 = fp[1] - fp[0], fp[2] - fp[1]
            buildings.append(Building.cuboid(fp.mean(axis=0), (np.linalg.norm(e0), np.linalg.norm(e1), h),
                                             float(np.arctan2(e0[1], e0[0]))))
        else:
            buildings.append(Building(footprint=fp, height=h))
    roads = [rxy[ro[i]:ro[i + 1]] for i in range(len(ro) - 1)]
    return StaticGeometry(buildings, roads, ids)


def ribbon_mesh(polylines: Sequence[np.ndarray], half_width: float, z: float) -> trimesh.Trimesh | None:
    """Flat strips ``half_width`` m either side of each centre-line (K, 2), at height ``z`` m, faces up."""
    verts, faces, base = [], [], 0
    for line in polylines:
        line = np.asarray(line, dtype=float)[:, :2]
        if len(line) < 2:
            continue
        tangent = np.gradient(line, axis=0)
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-12)
        normal = np.c_[-tangent[:, 1], tangent[:, 0]]
        n = len(line)
        v = np.empty((2 * n, 3))
        v[0::2, :2], v[1::2, :2], v[:, 2] = line - half_width * normal, line + half_width * normal, z
        i = base + 2 * np.arange(n - 1)
        faces += [np.stack([i, i + 2, i + 1], axis=1), np.stack([i + 1, i + 2, i + 3], axis=1)]
        verts.append(v)
        base += 2 * n
    if not verts:
        return None
    return trimesh.Trimesh(vertices=np.vstack(verts), faces=np.vstack(faces), process=False)


class Stage:
    """A PyBullet client with the static scene and one visual body per UAV and vehicle.

    Parameters
    ----------
    geometry : StaticGeometry
        Buildings and roads.
    n_uavs : int
        UAV bodies to create.
    car_sizes : sequence of (length, width, height)
        One car box per vehicle, m.
    uav_span : float
        Tip-to-tip length of each X-frame arm, m.
    use_egl : bool
        Render with the EGL plugin (falls back to TinyRenderer when it does not load).
    road_half_width : float
        Half width of the road strips drawn around each centre-line, m.
    decoys : sequence of (size (3,), centre (3,), yaw)
        Static decoys (the world's ``decoys``): boxes in the car colour, m and rad.
    """

    def __init__(self, geometry: StaticGeometry, n_uavs: int, car_sizes: Sequence[Sequence[float]],
                 uav_span: float, use_egl: bool, road_half_width: float = 3.5,
                 decoys: Sequence[tuple[Sequence[float], Sequence[float], float]] = ()) -> None:
        self.scene = Scene.create(SceneConfig())
        c = self.client = self.scene.client
        # the ground is painted per pixel (see ground_mask): its one huge polygon costs either renderer more than
        # the rest of the scene, and EGL on llvmpipe shades it with a shadow-map seam
        p.resetBasePositionAndOrientation(self.scene.ground_id, [0, 0, -1e5], [0, 0, 0, 1], physicsClientId=c)
        self._ground_rgb = np.array([round(255 * v) for v in GROUND_RGBA[:3]], dtype=np.uint8)
        self._sky_rgb = np.array([round(255 * v) for v in SKY_RGB], dtype=np.uint8)
        self.egl = bool(use_egl) and try_load_egl(c)
        self.ground_visible: np.ndarray | None = None
        """(H, W) bool of the last :meth:`render` with ``ground_level``: pixels showing the ground or a road."""
        self._tmp = tempfile.TemporaryDirectory(prefix="skytrack-render-") if self.egl else None
        road = ribbon_mesh(geometry.roads, road_half_width, _ROAD_Z)
        for k in range(0, len(geometry.buildings), _CHUNK):
            verts, normals = flat_mesh(geometry.buildings[k:k + _CHUNK])
            if self.egl:
                tris = np.arange(len(verts)).reshape(-1, 3)
                self._file_mesh(trimesh.Trimesh(vertices=verts, faces=tris, process=False), BUILDING_RGBA, f"b{k}")
            else:
                vis = p.createVisualShape(p.GEOM_MESH, vertices=verts.tolist(), indices=list(range(len(verts))),
                                          normals=normals.tolist(), rgbaColor=list(BUILDING_RGBA), physicsClientId=c)
                p.createMultiBody(0, -1, vis, physicsClientId=c)
        if road is not None:
            if self.egl:
                self._file_mesh(road, ROAD_RGBA, "roads")
            else:
                self.scene.add_road_surface(road)
        self.uav_ids = [self._x_frame(uav_span, UAV_COLORS[i % len(UAV_COLORS)]) for i in range(n_uavs)]
        self.vehicle_ids = []
        for size in car_sizes:
            vis = p.createVisualShape(p.GEOM_BOX, halfExtents=[s / 2.0 for s in size], rgbaColor=list(CAR_RGBA),
                                      physicsClientId=c)
            self.vehicle_ids.append(p.createMultiBody(0, -1, vis, basePosition=[0, 0, -50], physicsClientId=c))
        for size, pos, yaw in decoys:  # static, shaped and painted like the cars they imitate
            vis = p.createVisualShape(p.GEOM_BOX, halfExtents=[s / 2.0 for s in size], rgbaColor=list(CAR_RGBA),
                                      physicsClientId=c)
            p.createMultiBody(0, -1, vis, basePosition=list(map(float, pos)),
                              baseOrientation=p.getQuaternionFromEuler([0.0, 0.0, float(yaw)]), physicsClientId=c)

    @property
    def renderer_name(self) -> str:
        """``"egl"`` or ``"tiny"``."""
        return "egl" if self.egl else "tiny"

    def _file_mesh(self, mesh: trimesh.Trimesh, rgba: Sequence[float], name: str) -> int:
        path = Path(self._tmp.name) / f"{name}.obj"
        mesh.export(path)
        vis = p.createVisualShape(p.GEOM_MESH, fileName=str(path), rgbaColor=list(rgba), physicsClientId=self.client)
        return p.createMultiBody(0, -1, vis, physicsClientId=self.client)

    def _x_frame(self, span: float, rgb: Sequence[float]) -> int:
        arm = [span / 2.0, span / 25.0, span / 40.0]
        hub = [span / 8.0, span / 8.0, span / 20.0]
        q1, q2 = p.getQuaternionFromEuler([0, 0, np.pi / 4]), p.getQuaternionFromEuler([0, 0, -np.pi / 4])
        vis = p.createVisualShapeArray(
            [p.GEOM_BOX] * 3, halfExtents=[arm, arm, hub], rgbaColors=[[*rgb, 1.0]] * 3,
            visualFramePositions=[[0, 0, 0]] * 3, visualFrameOrientations=[q1, q2, [0, 0, 0, 1]],
            physicsClientId=self.client)
        return p.createMultiBody(0, -1, vis, basePosition=[0, 0, -50], physicsClientId=self.client)

    def set_poses(self, uavs: Sequence[tuple[np.ndarray, np.ndarray]],
                  vehicles: Sequence[tuple[np.ndarray, np.ndarray]]) -> None:
        """Place every UAV and vehicle body: ``(p_W (3,) m, q_WB (4,) (x, y, z, w))`` in body order."""
        for body, (pos, q) in zip((*self.uav_ids, *self.vehicle_ids), (*uavs, *vehicles), strict=True):
            p.resetBasePositionAndOrientation(body, list(map(float, pos)), list(map(float, q)),
                                              physicsClientId=self.client)

    def render(self, view: CameraView, width: int, height: int, segmentation: bool = False,
               aspect: float | None = None, ground_level: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
        """RGB image (H, W, 3) uint8 and, if asked, the segmentation mask (H, W) of body ids (-1: background).

        ``aspect`` overrides ``width / height`` in the projection (an image rendered small and scaled up to a size
        of slightly different aspect). With ``ground_level``, :attr:`ground_visible` is set to the (H, W) mask of the
        pixels that show the ground or a road (:func:`ground_level_mask`), else to ``None``.
        """
        proj = perspective(view.vfov, aspect or width / height, view.near, view.far)
        flags = 0 if segmentation else p.ER_NO_SEGMENTATION_MASK
        renderer = p.ER_BULLET_HARDWARE_OPENGL if self.egl else p.ER_TINY_RENDERER
        _, _, rgba, zbuf, seg = p.getCameraImage(
            width, height, viewMatrix=to_gl(view.view_matrix()),
            projectionMatrix=to_gl(proj), renderer=renderer, flags=flags, shadow=0, lightDirection=_LIGHT_DIR,
            physicsClientId=self.client)
        rgb = np.ascontiguousarray(np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3])
        depth = np.asarray(zbuf).reshape(height, width)
        empty = depth >= _EMPTY_DEPTH
        ray_z = pixel_ray_z(view, width, height, aspect or width / height)
        ground = (ray_z < 0.0)[:, :, None]  # ground_mask, from the rays computed once for both masks
        np.copyto(rgb, np.where(ground, self._ground_rgb, self._sky_rgb), where=empty[:, :, None])
        self.ground_visible = ground_level_mask(view, depth, empty, ray_z, _GROUND_LEVEL_Z) if ground_level else None
        mask = np.asarray(seg, dtype=np.int64).reshape(height, width) if segmentation else None
        return rgb, mask

    def time_render(self, view: CameraView, width: int, height: int, repeats: int = 2) -> float:
        """Median wall time of ``repeats`` renders of ``view`` after an untimed first one (EGL's first render sets up
        its buffers), s; used to choose a renderer."""
        self.render(view, width, height)
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            self.render(view, width, height)
            times.append(time.perf_counter() - t0)
        return float(np.median(times))

    def close(self) -> None:
        self.scene.close()
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None
