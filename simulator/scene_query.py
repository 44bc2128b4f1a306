"""PyBullet implementation of the sensors' :class:`~autonomy.sensing.scene.SceneQuery`.

``line_of_sight`` casts the segments with ``p.rayTestBatch``, in chunks of ``p.MAX_RAY_INTERSECTION_BATCH_SIZE - 1``
(pybullet 3.2.7 silently drops the last ray of a full batch).
Bullet reports only the first body a ray hits; when that body is not an occluder (a UAV, a car) the ray is cast
again from ``RECAST_PAST_HIT`` (1 cm) past the hit, up to ``max_passes`` times, so a car in front of a building does
not make the building transparent. A segment ending at or inside a car reports the car (clear), never what lies
beyond, because rays stop at the segment's end and a ray starting inside a convex body does not hit it — unless it
starts just inside its surface: Bullet then reports the body again, at the ray's start (measured on car boxes at
random poses within ±10 km: nearly every ray starting 1 mm inside, about one in nine at 2 mm, one in 400 still at
1 cm). A recast from 1 mm past the hit met the car again every time, one cast more for every ray that met one (a fifth
of a 1000-vehicle world's radar rays); a re-hit only costs one more cast. A hit within ``end_tolerance`` of the end
point (a ground point lying on the terrain) does not block. A segment that *starts* inside an occluder is not blocked
by it (Bullet rays do not hit a body from inside); sensors and radios sit outside buildings.

``render`` calls ``p.getCameraImage`` with a view matrix built from the camera frame (optical axis x, image-up z)
and a vertical-FoV projection; the depth buffer ``b`` is linearised as ``depth = far near / (far - (far - near) b)``.
"""

from __future__ import annotations

import pkgutil
import subprocess
import sys
from collections.abc import Iterable

import numpy as np
import pybullet as p

from autonomy.sensing.scene import CameraIntrinsics, CameraPose, RenderedImage
from simulator.stdio import quiet_c_stdout

__all__ = ["PybulletSceneQuery", "try_load_egl"]

# pybullet 3.2.7 returns only MAX_RAY_INTERSECTION_BATCH_SIZE - 1 results for a full batch of 16384 rays
_RAY_BATCH = p.MAX_RAY_INTERSECTION_BATCH_SIZE - 1
RECAST_PAST_HIT = 0.01  # m: where a ray is cast again past a body it looks through (module docstring)


_EGL_PROBE = """
import pkgutil, sys
import pybullet as p
cid = p.connect(p.DIRECT)
loader = pkgutil.get_loader("eglRenderer")
plugin = p.loadPlugin(loader.get_filename(), "_eglRendererPlugin") if loader else p.loadPlugin("eglRendererPlugin")
if plugin < 0:
    sys.exit(3)
col = p.createCollisionShape(p.GEOM_BOX, halfExtents=[1, 1, 1])
vis = p.createVisualShape(p.GEOM_BOX, halfExtents=[1, 1, 1], rgbaColor=[1, 0, 1, 1])
p.createMultiBody(0, col, vis, basePosition=[5, 0, 0])
view = p.computeViewMatrix([0, 0, 0], [1, 0, 0], [0, 0, 1])
proj = p.computeProjectionMatrixFOV(60, 1.0, 0.1, 100)
w, h, rgba, depth, seg = p.getCameraImage(16, 16, view, proj, renderer=p.ER_BULLET_HARDWARE_OPENGL)
p.rayTestBatch([[0, 0, 0]], [[10, 0, 0]])
sys.exit(0 if w == 16 else 4)
"""


def try_load_egl(client_id: int, probe_timeout_s: float = 60.0) -> bool:
    """Load the EGL renderer plugin into ``client_id``; True if it is usable, False (use TinyRenderer) otherwise.

    The plugin shipped with the ``pybullet`` wheel (``pkgutil.get_loader("eglRenderer")``) can load and then crash
    the process on the first render where the EGL driver is unusable (software-only machines), so it is first
    exercised in a child process (connect, load, render a box, cast a ray); only if that child exits cleanly is the
    plugin loaded into ``client_id``. Never raises.
    """
    try:
        probe = subprocess.run(
            [sys.executable, "-c", _EGL_PROBE], capture_output=True, timeout=probe_timeout_s, check=False
        )
        if probe.returncode != 0:
            return False
        loader = pkgutil.get_loader("eglRenderer")
        with quiet_c_stdout():  # the plugin prints its GL banner on descriptor 1
            if loader is not None:
                plugin = p.loadPlugin(loader.get_filename(), "_eglRendererPlugin", physicsClientId=client_id)
            else:
                plugin = p.loadPlugin("eglRendererPlugin", physicsClientId=client_id)
    except Exception:  # noqa: BLE001 - any failure means no EGL
        return False
    return plugin >= 0


class PybulletSceneQuery:
    """Scene queries against a PyBullet client.

    Parameters
    ----------
    client_id : int
        PyBullet physics client.
    occluder_body_ids : set[int]
        Bodies that block sight: buildings, terrain. Any other body a ray meets is looked through.
    use_egl : bool
        Render with ``ER_BULLET_HARDWARE_OPENGL`` (the EGL plugin must be loaded, see :func:`try_load_egl`);
        otherwise ``ER_TINY_RENDERER``.
    end_tolerance : float
        A hit closer than this to the segment's end does not block (m).
    max_passes : int
        Casts per segment when non-occluders are met on the way.
    """

    def __init__(
        self,
        client_id: int,
        occluder_body_ids: Iterable[int],
        use_egl: bool = False,
        end_tolerance: float = 1e-3,
        max_passes: int = 8,
    ):
        if end_tolerance < 0:
            raise ValueError(f"end_tolerance must be >= 0 m, got {end_tolerance}")
        if max_passes < 1:
            raise ValueError(f"max_passes must be >= 1, got {max_passes}")
        self.client_id = int(client_id)
        self.occluder_body_ids = frozenset(int(b) for b in occluder_body_ids)
        self.renderer = p.ER_BULLET_HARDWARE_OPENGL if use_egl else p.ER_TINY_RENDERER
        self.end_tolerance = float(end_tolerance)
        self.max_passes = int(max_passes)
        self.rays_cast = 0

    def _cast(self, a: np.ndarray, b: np.ndarray) -> list[tuple]:
        out: list[tuple] = []
        step = _RAY_BATCH
        for k in range(0, len(a), step):
            res = p.rayTestBatch(a[k : k + step].tolist(), b[k : k + step].tolist(), physicsClientId=self.client_id)
            if len(res) != len(a[k : k + step]):
                raise RuntimeError(f"rayTestBatch returned {len(res)} results for {len(a[k : k + step])} rays")
            out.extend(res)
        self.rays_cast += len(a)
        return out

    def line_of_sight(self, from_W: np.ndarray, to_W: np.ndarray) -> np.ndarray:
        a = np.array(np.atleast_2d(from_W), dtype=float)
        b = np.atleast_2d(np.asarray(to_W, dtype=float))
        if a.shape != b.shape or a.shape[1] != 3:
            raise ValueError(f"line_of_sight needs two (N, 3) arrays, got {a.shape} and {b.shape}")
        clear = np.ones(len(a), dtype=bool)
        active = np.arange(len(a))
        nudge = max(self.end_tolerance, RECAST_PAST_HIT)
        for _ in range(self.max_passes):
            if active.size == 0:
                break
            seg = b[active] - a[active]
            length = np.linalg.norm(seg, axis=1)
            results = self._cast(a[active], b[active])
            again = []
            for k, (uid, _link, frac, pos, _n) in enumerate(results):
                if uid < 0 or (1.0 - frac) * length[k] <= self.end_tolerance:
                    continue
                i = active[k]
                if uid in self.occluder_body_ids:
                    clear[i] = False
                    continue
                remaining = (1.0 - frac) * length[k]
                if remaining > nudge:
                    a[i] = np.asarray(pos) + seg[k] / length[k] * nudge
                    again.append(i)
            active = np.asarray(again, dtype=int)
        return clear

    def render(self, camera: CameraPose, intrinsics: CameraIntrinsics) -> RenderedImage:
        eye = camera.p_W
        view = p.computeViewMatrix(
            eye.tolist(), (eye + camera.forward_W).tolist(), camera.up_W.tolist(), physicsClientId=self.client_id
        )
        proj = p.computeProjectionMatrixFOV(
            fov=float(np.rad2deg(intrinsics.vfov)),
            aspect=intrinsics.width / intrinsics.height,
            nearVal=intrinsics.near,
            farVal=intrinsics.far,
            physicsClientId=self.client_id,
        )
        w, h = intrinsics.width, intrinsics.height
        _, _, rgba, zbuf, seg = p.getCameraImage(
            w, h, viewMatrix=view, projectionMatrix=proj, renderer=self.renderer, physicsClientId=self.client_id
        )
        rgb = np.asarray(rgba, dtype=np.uint8).reshape(h, w, 4)[:, :, :3].copy()
        zb = np.asarray(zbuf, dtype=float).reshape(h, w)
        near, far = intrinsics.near, intrinsics.far
        depth = far * near / (far - (far - near) * zb)
        return RenderedImage(rgb=rgb, depth=depth, seg=np.asarray(seg, dtype=int).reshape(h, w))
