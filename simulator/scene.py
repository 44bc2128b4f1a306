"""The PyBullet scene: a DIRECT-mode client with gravity, a ground plane, buildings and the road surface.

Static geometry is batched: cuboid buildings become a few static *compound* bodies (``createCollisionShapeArray``, up to
``chunk`` boxes each) and non-cuboid footprints one static concave mesh. Hundreds of separate static bodies would cost
~0.2 ms per physics step in Bullet's broadphase (measured: 500 bodies 0.18 ms/step, one compound 0.002 ms/step);
batched,
a 500-building town adds nothing measurable to a step and builds in tens of milliseconds.
"""

from __future__ import annotations

import inspect
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pybullet as p
import trimesh

from worlds.geometry import Building
from worlds.map_cache import cached

__all__ = ["BUILDING_RGBA", "GROUND_RGBA", "ROAD_RGBA", "Scene", "SceneConfig"]

BUILDING_RGBA = (0.72, 0.72, 0.75, 1.0)
GROUND_RGBA = (0.36, 0.45, 0.33, 1.0)
ROAD_RGBA = (0.22, 0.22, 0.24, 1.0)


_UNIT_BOX = trimesh.creation.box(extents=(1.0, 1.0, 1.0))


def _box_mesh(centres: np.ndarray, sizes: np.ndarray, yaws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (8N, 3) and faces (12N, 3) of N boxes with given centres, full sizes (m) and yaws (rad)."""
    corners = np.asarray(_UNIT_BOX.vertices)[None] * sizes[:, None, :]  # (N, 8, 3)
    c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
    x, y = corners[..., 0], corners[..., 1]
    corners = np.stack([c * x - s * y, s * x + c * y, corners[..., 2]], axis=-1) + centres[:, None, :]
    faces = np.asarray(_UNIT_BOX.faces)[None] + 8 * np.arange(len(centres))[:, None, None]
    return corners.reshape(-1, 3), faces.reshape(-1, 3)


def _extrude(footprint: np.ndarray, z0: float, z1: float) -> tuple[np.ndarray, np.ndarray]:
    """Closed triangle mesh of a counter-clockwise footprint extruded from z0 to z1: (vertices (V, 3), faces (F, 3))."""
    import shapely

    tris = shapely.constrained_delaunay_triangles(shapely.Polygon(footprint))
    caps = np.array([np.asarray(t.exterior.coords)[:3] for t in shapely.get_parts(tris)])  # (T, 3, 2)
    for tri in caps:  # make every cap triangle counter-clockwise
        if (tri[1, 0] - tri[0, 0]) * (tri[2, 1] - tri[0, 1]) - (tri[1, 1] - tri[0, 1]) * (tri[2, 0] - tri[0, 0]) < 0:
            tri[[1, 2]] = tri[[2, 1]]
    n_t = len(caps)
    top = np.concatenate([caps.reshape(-1, 2), np.full((3 * n_t, 1), z1)], axis=1)
    bottom = np.concatenate([caps[:, ::-1].reshape(-1, 2), np.full((3 * n_t, 1), z0)], axis=1)
    a, b = footprint, np.roll(footprint, -1, axis=0)
    k = len(footprint)
    walls = np.stack([np.c_[a, np.full(k, z0)], np.c_[b, np.full(k, z0)], np.c_[b, np.full(k, z1)],
                      np.c_[a, np.full(k, z1)]], axis=1).reshape(-1, 3)  # quads a0 b0 b1 a1, outward for CCW
    verts = np.concatenate([top, bottom, walls])
    cap_faces = np.arange(6 * n_t).reshape(-1, 3)
    q = 6 * n_t + 4 * np.arange(k)[:, None]
    wall_faces = np.concatenate([q + [0, 1, 2], q + [0, 2, 3]])
    return verts, np.concatenate([cap_faces, wall_faces]).astype(int)


def _extrude_all(buildings: Sequence[Building]) -> tuple[np.ndarray, np.ndarray]:
    """One mesh of all ``buildings`` extruded (:func:`_extrude`): (vertices, faces)."""
    parts = [_extrude(b.footprint, b.base_z, b.top_z) for b in buildings]
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    return (np.concatenate([v for v, _ in parts]),
            np.concatenate([f + o for (_, f), o in zip(parts, offsets, strict=True)]))


def _extrude_key(buildings: Sequence[Building]) -> list[bytes | str]:
    """Map-cache key of :func:`_extrude_all` (a city's 446 footprints take ≈ 0.4 s to triangulate): the footprints,
    their heights and the meshing code."""
    data = b"".join(np.ascontiguousarray(b.footprint, dtype=float).tobytes() + b"|"
                    + np.array([b.base_z, b.top_z], dtype=float).tobytes() for b in buildings)
    return [data, inspect.getsource(_extrude), inspect.getsource(_extrude_all)]


@dataclass(frozen=True, kw_only=True)
class SceneConfig:
    """Static scene settings.

    Attributes
    ----------
    physics_hz : int
        Physics step rate, Hz.
    gravity : float
        Gravitational acceleration, m/s^2 (applied along -z).
    ground_size : tuple[float, float]
        Visual extent of the ground (x, y), m; collision is an infinite plane.
    chunk : int
        Maximum boxes per static compound body.
    contact_breaking_threshold : float
        Separation at which Bullet drops a point from a persistent contact manifold, m, > 0. Bullet's 0.02 m keeps
        the points a rolling sphere wheel leaves behind for several steps (3 per wheel, each a set of solver rows:
        one car in road_standoff cost 307 us per step); 1 mm keeps about one point per wheel and leaves the car's
        trajectory unchanged to the millimetre over 10 s (122-159 us per step). Contacts are still found at Bullet's
        collision margins.
    solver_iterations : int
        Iterations of Bullet's constraint solver per step, >= 1 (PyBullet's default is 50). The joints, motors and wheel
        contacts of the cars are its rows; 10 iterations halve a car's step (sedan at 240 Hz: 72 against 142 us) and
        leave its motion converged: driven open-loop at 10 m/s on a steady turn, speed and yaw rate equal to 4 digits
        and the path 0.14 m from the 50-iteration path after 100 m (it keeps its lane, stops and car-following
        gaps: ``tests/vehicles`` run with this setting). Quadrotors have no joints and are unaffected.
    """

    physics_hz: int = 240
    gravity: float = 9.81
    ground_size: tuple[float, float] = (2000.0, 2000.0)
    chunk: int = 256
    contact_breaking_threshold: float = 0.001
    solver_iterations: int = 10

    def __post_init__(self) -> None:
        if self.physics_hz <= 0:
            raise ValueError(f"SceneConfig.physics_hz must be > 0, got {self.physics_hz}")
        if self.chunk < 1:
            raise ValueError(f"SceneConfig.chunk must be >= 1, got {self.chunk}")
        if int(self.solver_iterations) != self.solver_iterations or self.solver_iterations < 1:
            raise ValueError(f"SceneConfig.solver_iterations must be an integer >= 1, got {self.solver_iterations}")
        if not self.contact_breaking_threshold > 0:
            raise ValueError(f"SceneConfig.contact_breaking_threshold must be > 0 m, got "
                             f"{self.contact_breaking_threshold}")


@dataclass
class Scene:
    """A built PyBullet scene; ``occluders`` are the static bodies that block sight and radio."""

    client: int
    config: SceneConfig
    ground_id: int
    building_ids: list[int] = field(default_factory=list)
    road_id: int | None = None

    @classmethod
    def create(cls, config: SceneConfig) -> Scene:
        client = p.connect(p.DIRECT)
        p.resetSimulation(physicsClientId=client)
        p.setGravity(0.0, 0.0, -config.gravity, physicsClientId=client)
        p.setPhysicsEngineParameter(fixedTimeStep=1.0 / config.physics_hz, numSubSteps=0,
                                    deterministicOverlappingPairs=1,
                                    contactBreakingThreshold=config.contact_breaking_threshold,  # before any body
                                    numSolverIterations=int(config.solver_iterations),
                                    physicsClientId=client)
        plane = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=client)
        sx, sy = config.ground_size
        vis = p.createVisualShape(p.GEOM_BOX, halfExtents=[sx / 2, sy / 2, 0.01], rgbaColor=GROUND_RGBA,
                                  visualFramePosition=[0, 0, -0.01], physicsClientId=client)
        ground = p.createMultiBody(0, plane, vis, physicsClientId=client)
        p.changeDynamics(ground, -1, lateralFriction=1.0, physicsClientId=client)
        return cls(client=client, config=config, ground_id=ground)

    @property
    def occluders(self) -> set[int]:
        return {self.ground_id, *self.building_ids}

    def add_buildings(self, buildings: Sequence[Building]) -> list[int]:
        """Add buildings as batched static bodies; returns the new body ids."""
        cuboids = [b for b in buildings if b.is_cuboid]
        others = [b for b in buildings if not b.is_cuboid]
        new: list[int] = []
        for start in range(0, len(cuboids), self.config.chunk):
            new.append(self._compound(cuboids[start:start + self.config.chunk]))
        if others:
            new.append(self._extruded(others))
        self.building_ids.extend(new)
        return new

    def _compound(self, boxes: Sequence[Building]) -> int:
        c = self.client
        centres, halves, quats = [], [], []
        for b in boxes:
            centre, size, yaw = b.cuboid_params
            centres.append(centre.tolist())
            halves.append((size / 2).tolist())
            quats.append(p.getQuaternionFromEuler([0, 0, yaw]))
        n = len(boxes)
        col = p.createCollisionShapeArray([p.GEOM_BOX] * n, halfExtents=halves, collisionFramePositions=centres,
                                          collisionFrameOrientations=quats, physicsClientId=c)
        # createVisualShapeArray crashes PyBullet 3.2.x beyond ~16 shapes: draw the chunk as one visual mesh instead.
        verts, faces = _box_mesh(np.array(centres), 2 * np.array(halves),
                                 np.array([b.cuboid_params[2] for b in boxes]))
        vis = p.createVisualShape(p.GEOM_MESH, vertices=verts.tolist(), indices=faces.ravel().tolist(),
                                  rgbaColor=list(BUILDING_RGBA), physicsClientId=c)
        return p.createMultiBody(0, col, vis, physicsClientId=c)

    def _extruded(self, buildings: Sequence[Building]) -> int:
        verts, faces = cached("extruded", _extrude_key(buildings), lambda: _extrude_all(buildings))
        return self.add_static_mesh(trimesh.Trimesh(vertices=verts, faces=faces, process=False), BUILDING_RGBA,
                                    collision=True)

    def add_static_mesh(self, mesh: trimesh.Trimesh, rgba: Sequence[float], collision: bool) -> int:
        """Add one static triangle mesh (concave collision when ``collision``; visual only otherwise)."""
        c = self.client
        verts = np.asarray(mesh.vertices, dtype=float).tolist()
        idx = np.asarray(mesh.faces, dtype=int).ravel().tolist()
        col = (p.createCollisionShape(p.GEOM_MESH, vertices=verts, indices=idx, flags=p.GEOM_FORCE_CONCAVE_TRIMESH,
                                      physicsClientId=c) if collision else -1)
        vis = p.createVisualShape(p.GEOM_MESH, vertices=verts, indices=idx, rgbaColor=list(rgba), physicsClientId=c)
        return p.createMultiBody(0, col, vis, physicsClientId=c)

    def add_static_box(self, centre: Sequence[float], size: Sequence[float], yaw: float, rgba: Sequence[float]) -> int:
        """Add one static box: centre (m), full size (length, width, height; m), heading ``yaw`` (rad)."""
        c = self.client
        half = [s / 2 for s in size]
        col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=c)
        vis = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=list(rgba), physicsClientId=c)
        return p.createMultiBody(0, col, vis, basePosition=list(centre),
                                 baseOrientation=p.getQuaternionFromEuler([0.0, 0.0, float(yaw)]), physicsClientId=c)

    def add_road_surface(self, mesh: trimesh.Trimesh) -> int:
        """Add the road surface (visual only: cars drive on the ground plane's collision)."""
        self.road_id = self.add_static_mesh(mesh, ROAD_RGBA, collision=False)
        return self.road_id

    def step(self) -> None:
        p.stepSimulation(physicsClientId=self.client)

    def close(self) -> None:
        if p.isConnected(self.client):
            p.disconnect(self.client)
