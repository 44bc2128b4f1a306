"""PyBullet scene queries: occluder-only line of sight, agreement with the exact fake scene, rendering, EGL probe."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pybullet as p
import pytest
import shapely

from autonomy.sensing.fake_scene import FakeScene
from autonomy.sensing.scene import CameraIntrinsics, CameraPose, SceneQuery
from simulator.scene_query import PybulletSceneQuery
from worlds.geometry import Building


def add_box(cid: int, center, half, yaw: float = 0.0, rgba=(0.7, 0.7, 0.7, 1.0)) -> int:
    q = p.getQuaternionFromEuler([0, 0, yaw])
    col = p.createCollisionShape(p.GEOM_BOX, halfExtents=list(half), physicsClientId=cid)
    vis = p.createVisualShape(p.GEOM_BOX, halfExtents=list(half), rgbaColor=list(rgba), physicsClientId=cid)
    return p.createMultiBody(0, col, vis, basePosition=list(center), baseOrientation=q, physicsClientId=cid)


BUILDINGS = [
    Building.cuboid((30.0, 0.0), (10.0, 10.0, 20.0)),
    Building.cuboid((-20.0, 35.0), (16.0, 8.0, 35.0), yaw=0.6),
    Building.cuboid((10.0, -40.0), (12.0, 20.0, 12.0), yaw=-1.1),
]


@pytest.fixture
def town():
    cid = p.connect(p.DIRECT)
    plane = p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid), physicsClientId=cid)
    ids = {plane}
    for b in BUILDINGS:
        c, size, yaw = b.cuboid_params
        ids.add(add_box(cid, c, size / 2, yaw))
    yield cid, PybulletSceneQuery(cid, ids)
    p.disconnect(cid)


def test_is_a_scene_query(town):
    assert isinstance(town[1], SceneQuery)
    assert isinstance(FakeScene(), SceneQuery)


def test_building_blocks_and_non_occluders_are_looked_through(town):
    cid, sq = town
    uav = add_box(cid, [15.0, 0.0, 12.0], [0.3, 0.3, 0.1])  # a UAV body between the sensor and the building
    car = add_box(cid, [60.0, 30.0, 0.75], [2.0, 0.9, 0.75])
    a = np.array([0.0, 0.0, 12.0])
    seg_from = np.array([a, a, a, a, a, [61.0, 30.0, 1.0]])
    seg_to = np.array(
        [
            [50.0, 0.0, 5.0],  # through the building, with the UAV body in front of it: blocked
            [60.0, 30.0, 0.75],  # ends at the car centre (inside the car): clear
            [62.0, 30.0, 0.75],  # ends inside the car, beyond its near face: clear
            [
                60.0,
                30.0,
                0.0,
            ],  # ends on the ground under the car's middle: the car is looked through, ground not an obstacle
            [15.0, 0.0, 12.0],  # ends inside the UAV body: clear
            [90.0, 30.0, 1.0],  # starts inside the car, nothing beyond: clear
        ]
    )
    np.testing.assert_array_equal(sq.line_of_sight(seg_from, seg_to), [False, True, True, True, True, True])
    assert uav not in sq.occluder_body_ids and car not in sq.occluder_body_ids


def test_agrees_with_exact_fake_scene_on_random_segments(town):
    _, sq = town
    rng = np.random.default_rng(12)
    n = 2000
    a = np.column_stack([rng.uniform(-60, 60, n), rng.uniform(-60, 60, n), rng.uniform(0.5, 50, n)])
    b = np.column_stack([rng.uniform(-60, 60, n), rng.uniform(-60, 60, n), rng.uniform(0.5, 50, n)])
    # segments starting inside a building are out of scope (a Bullet ray does not hit a body from inside)
    outside = ~np.any(
        [
            shapely.intersects_xy(shapely.Polygon(bd.footprint), a[:, 0], a[:, 1]) & (a[:, 2] <= bd.top_z)
            for bd in BUILDINGS
        ],
        axis=0,
    )
    a, b = a[outside], b[outside]
    fake = FakeScene(BUILDINGS).line_of_sight(a, b)
    real = sq.line_of_sight(a, b)
    assert 0.1 < np.mean(~fake) < 0.9  # both outcomes are exercised
    assert np.mean(fake != real) <= 0.001  # rays grazing an edge may differ by Bullet's collision margin


def test_batches_larger_than_bullet_limit(town):
    _, sq = town
    n = p.MAX_RAY_INTERSECTION_BATCH_SIZE + 500
    a = np.tile([0.0, 0.0, 10.0], (n, 1))
    b = np.tile([[50.0, 0.0, 10.0], [0.0, 50.0, 10.0]], (n // 2, 1))
    out = sq.line_of_sight(a, b)
    assert out.shape == (n,) and not out[0::2].any() and out[1::2].all()


def test_render_nadir_depth_segmentation_and_orientation(town):
    cid, sq = town
    marker = add_box(cid, [-10.0, 80.0, 0.5], [2.0, 2.0, 0.5], rgba=(1.0, 0.0, 0.0, 1.0))
    K = CameraIntrinsics.from_hfov(64, 48, np.deg2rad(60.0), near=0.1, far=500.0)
    # camera 40 m above (-10, 70), optical axis down, image-up pointing north (+y)
    R_WC = np.column_stack([[0, 0, -1.0], [-1.0, 0, 0], [0, 1.0, 0]])
    img = sq.render(CameraPose(p_W=[-10.0, 70.0, 40.0], R_WC=R_WC), K)
    assert img.rgb.shape == (48, 64, 3) and img.rgb.dtype == np.uint8
    # ground plane at z = 0 seen along the axis: depth is the height above it
    assert img.depth[30, 5] == pytest.approx(40.0, abs=0.05)
    # the red marker 10 m north projects above the image centre: v = c_y - f * 10 / 39
    rows, cols = np.nonzero(img.seg == marker)
    assert rows.size > 0
    v_expected = K.cy - K.fy * 10.0 / 39.0
    assert abs(rows.mean() + 0.5 - v_expected) < 1.0 and abs(cols.mean() + 0.5 - K.cx) < 1.0
    assert img.depth[rows[0], cols[0]] == pytest.approx(39.0, abs=0.1)
    assert np.all(img.rgb[rows, cols, 0] > 150) and np.all(img.rgb[rows, cols, 1] < 30)


def test_egl_probe_fails_gracefully_and_egl_renders_when_loaded():
    code = (
        "import numpy as np, pybullet as p\n"
        "from simulator.scene_query import PybulletSceneQuery, try_load_egl\n"
        "from autonomy.sensing.scene import CameraIntrinsics, CameraPose\n"
        "cid = p.connect(p.DIRECT)\n"
        "egl = try_load_egl(cid)\n"
        "col = p.createCollisionShape(p.GEOM_BOX, halfExtents=[1, 1, 1])\n"
        "vis = p.createVisualShape(p.GEOM_BOX, halfExtents=[1, 1, 1], rgbaColor=[1, 0, 1, 1])\n"
        "box = p.createMultiBody(0, col, vis, basePosition=[10, 0, 0])\n"
        "img = PybulletSceneQuery(cid, {box}, use_egl=egl).render(\n"
        "    CameraPose(p_W=[0, 0, 0], R_WC=np.eye(3)), CameraIntrinsics.from_hfov(32, 24, 1.0))\n"
        "print('RESULT', 'EGL' if egl else 'TINY', int((img.seg == box).sum()))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr
    (line,) = [ln for ln in out.stdout.splitlines() if ln.startswith("RESULT")]
    _, which, pixels = line.split()
    assert which in ("EGL", "TINY")
    # a 2 m box at 10 m straight ahead covers the image centre: about (2 f / 10)^2 pixels
    f = 16 / np.tan(0.5)
    assert int(pixels) == pytest.approx((2 * f / 10) ** 2, rel=0.35)


def test_a_ray_into_a_car_is_cast_twice_and_finds_a_building_close_behind_it(town):
    """A ray that meets a car is cast again from 1 cm past the hit (Bullet reports a ray starting a millimetre or two
    inside a box as meeting it again at its start): a segment ending at a car's centre costs two casts, not three,
    and a building 5 cm behind the car's far side still blocks a segment that runs through the car into it."""
    cid, sq = town
    rng = np.random.default_rng(3)
    centres = np.column_stack([rng.uniform(-150, 150, 40), rng.uniform(100, 300, 40), np.full(40, 0.75)])
    for c in centres:
        add_box(cid, c, [2.4, 0.9, 0.75], yaw=rng.uniform(-np.pi, np.pi))
    n = 400
    ends = centres[rng.integers(0, 40, n)]
    elev, az = rng.uniform(0.1, 1.5, n), rng.uniform(-np.pi, np.pi, n)
    starts = ends + rng.uniform(20, 300, n)[:, None] * np.column_stack([np.cos(elev) * np.cos(az),
                                                                        np.cos(elev) * np.sin(az), np.sin(elev)])
    met = np.array([p.rayTest(a.tolist(), b.tolist(), physicsClientId=cid)[0][0]
                    for a, b in zip(starts, ends, strict=True)])
    starts, ends = starts[met >= 0], ends[met >= 0]  # the rays that meet the car they end in (no other in between)
    before = sq.rays_cast
    assert sq.line_of_sight(starts, ends).all()
    assert len(starts) > 300 and sq.rays_cast - before <= 2.02 * len(starts)
    car = add_box(cid, [200.0, 0.0, 0.75], [2.4, 0.9, 0.75])
    wall = add_box(cid, [200.0 + 2.4 + 0.05 + 0.5, 0.0, 5.0], [0.5, 10.0, 5.0])  # its face 5 cm past the car's
    blocked = PybulletSceneQuery(cid, sq.occluder_body_ids | {wall})
    assert car not in blocked.occluder_body_ids
    out = blocked.line_of_sight(np.array([[150.0, 0.0, 0.75], [150.0, 0.0, 0.75]]),
                                np.array([[205.0, 0.0, 0.75], [199.0, 0.0, 0.75]]))
    np.testing.assert_array_equal(out, [False, True])
