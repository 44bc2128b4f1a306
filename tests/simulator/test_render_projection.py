"""Projection, camera smoothing, interpolation, overlay geometry and replay timelines of the video renderer."""

import numpy as np
import pybullet as p
import pytest

from simulator.render.cameras import CameraInputs, CriticalDamper, TopDownCamera, yaw_of
from simulator.render.config import RenderConfig
from simulator.render.overlays import EstimateMark, OverlayFrame, covariance_ellipse, draw_overlays
from simulator.render.projection import CameraView, from_gl, look_at, perspective, project, to_gl
from simulator.render.timeline import Timeline, interp_positions, nlerp_quaternions


def test_pinhole_hand_computed():
    # camera at the origin looking along +x, z up, 90 deg vertical FoV on 640 x 480: f = 240 px
    cam = CameraView(eye_W=np.zeros(3), target_W=np.array([1.0, 0, 0]), vfov=np.pi / 2)
    pts = np.array([[10.0, 2.0, 1.0], [10.0, 0.0, 0.0], [5.0, -1.0, -2.0], [-3.0, 0.0, 0.0]])
    uv, front = cam.project(pts, 640, 480)
    assert front.tolist() == [True, True, True, False]
    # u = W/2 - f y / x, v = H/2 - f z / x
    np.testing.assert_allclose(uv[0], [320 - 240 * 0.2, 240 - 240 * 0.1], atol=1e-9)
    np.testing.assert_allclose(uv[1], [320, 240], atol=1e-9)
    np.testing.assert_allclose(uv[2], [320 + 240 * 0.2, 240 + 240 * 0.4], atol=1e-9)
    assert np.isnan(uv[3]).all()


def test_pinhole_aspect_and_off_axis_camera():
    # looking straight down from 100 m with north up: x east is image right, y north is image up
    cam = CameraView(eye_W=np.array([50.0, 20.0, 100.0]), target_W=np.array([50.0, 20.0, 0.0]),
                     up_W=np.array([0.0, 1.0, 0.0]), vfov=np.deg2rad(60))
    w, h = 800, 400
    f = h / 2 / np.tan(np.deg2rad(30))
    uv, _ = cam.project(np.array([[60.0, 25.0, 0.0]]), w, h)
    np.testing.assert_allclose(uv[0], [w / 2 + f * 10 / 100, h / 2 - f * 5 / 100], atol=1e-9)


@pytest.fixture(scope="module")
def client():
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(cid)


@pytest.mark.parametrize("eye,target,up", [([3, -4, 5], [10, 2, 0], [0, 0, 1]), ([0, 0, 80], [1, 2, 0], [0, 1, 0]),
                                           ([-20, 7, 1], [5, 5, 30], [0, 0, 1])])
def test_matrices_equal_pybullets(client, eye, target, up):
    V = look_at(np.array(eye, float), np.array(target, float), np.array(up, float))
    np.testing.assert_allclose(V, from_gl(p.computeViewMatrix(eye, target, up, physicsClientId=client)), atol=1e-5)
    P = perspective(np.deg2rad(47.0), 16 / 9, 0.5, 3000.0)
    np.testing.assert_allclose(P, from_gl(p.computeProjectionMatrixFOV(47.0, 16 / 9, 0.5, 3000.0,
                                                                       physicsClientId=client)), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(from_gl(to_gl(V)), V)


def test_projection_lands_on_pybullets_pixels(client):
    """A small box rendered by TinyRenderer: the projected centre is the centroid of its segmentation blob."""
    vis = p.createVisualShape(p.GEOM_BOX, halfExtents=[0.3, 0.3, 0.3], physicsClientId=client)
    pos = np.array([12.0, -3.0, 2.0])
    body = p.createMultiBody(0, -1, vis, basePosition=pos.tolist(), physicsClientId=client)
    cam = CameraView(eye_W=np.array([-5.0, 2.0, 6.0]), target_W=np.array([10.0, 0.0, 1.0]), vfov=np.deg2rad(40))
    w, h = 320, 240
    _, _, _, _, seg = p.getCameraImage(w, h, to_gl(cam.view_matrix()), to_gl(cam.projection_matrix(w, h)),
                                       renderer=p.ER_TINY_RENDERER, physicsClientId=client)
    rows, cols = np.nonzero(np.asarray(seg).reshape(h, w) == body)
    assert rows.size > 20
    uv, front = project(pos, cam.view_matrix(), cam.projection_matrix(w, h), w, h)
    assert front[0]
    # pixel (i, j) covers [i, i+1) x [j, j+1): its centre is (i + 0.5, j + 0.5)
    np.testing.assert_allclose(uv[0], [cols.mean() + 0.5, rows.mean() + 0.5], atol=1.0)
    p.removeBody(body, physicsClientId=client)


def test_critical_damper_closed_form_and_no_overshoot():
    tau, dt = 0.4, 1 / 30
    d = CriticalDamper(tau)
    d.update(np.zeros(3), dt)  # first call jumps onto the goal
    goal = np.array([10.0, -4.0, 2.0])
    w = 1 / tau
    xs = []
    for k in range(1, 121):
        xs.append(d.update(goal, dt))
        t = k * dt
        np.testing.assert_allclose(xs[-1], goal - goal * (1 + w * t) * np.exp(-w * t), atol=1e-9)
    xs = np.array(xs)
    assert np.all(np.diff(xs[:, 0]) > 0) and np.all(xs[:, 0] < goal[0])  # monotone, never past the goal
    # exact integration: one step of 2 dt equals two steps of dt
    a, b = CriticalDamper(tau), CriticalDamper(tau)
    a.update(np.zeros(1), dt), b.update(np.zeros(1), dt)
    np.testing.assert_allclose(a.update(np.ones(1), 2 * dt), (b.update(np.ones(1), dt), b.update(np.ones(1), dt))[1])


def test_topdown_frames_the_area():
    bounds = (-100.0, 300.0, -50.0, 150.0)
    cam = TopDownCamera(np.deg2rad(40), 0.0, aspect=16 / 9, bounds=bounds, span_m=100.0)
    inputs = CameraInputs(0.0, np.zeros(3), np.array([0, 0, 0, 1.0]), np.zeros(3))
    view = cam.view(inputs, 0.0)
    corners = np.array([[bounds[0], bounds[2], 0], [bounds[1], bounds[3], 0]])
    uv, _ = view.project(corners, 1280, 720)
    assert np.all(uv >= -1e-6) and np.all(uv[:, 0] <= 1280 + 1e-6) and np.all(uv[:, 1] <= 720 + 1e-6)
    assert np.isclose(uv[1, 0] - uv[0, 0], 1280, rtol=1e-9)  # the wider side fills the width exactly


def test_interpolation():
    t = np.array([0.0, 0.1, 0.2])
    pts = np.array([[0.0, 0, 0], [1.0, 2, 0], [3.0, 2, 1]])
    np.testing.assert_allclose(interp_positions(t, pts, 0.15), [2.0, 2.0, 0.5])
    np.testing.assert_allclose(interp_positions(t, pts, -1.0), pts[0])
    np.testing.assert_allclose(interp_positions(t, pts, 9.0), pts[-1])
    q0 = np.array([0, 0, 0, 1.0])
    q1 = np.array([0, 0, np.sin(np.pi / 4), np.cos(np.pi / 4)])  # 90 deg yaw
    q = nlerp_quaternions(q0, -q1, 0.5)  # the sign of q1 must not matter
    assert np.isclose(np.linalg.norm(q), 1.0) and np.isclose(yaw_of(q), np.pi / 4)


def test_covariance_ellipse_is_the_two_sigma_contour():
    P = np.array([[9.0, 2.5], [2.5, 4.0]])
    m = np.array([10.0, -5.0])
    pts = covariance_ellipse(m, P)
    d = pts - m
    np.testing.assert_allclose(np.einsum("ni,ij,nj->n", d, np.linalg.inv(P), d), 4.0, rtol=1e-9)


def _streams():
    t = np.arange(0.0, 2.01, 0.1)
    n = len(t)
    z = np.zeros(n)
    uav = {"tick": np.arange(n), "t": t, "uav": z.astype(int), "x": 100 + 0 * t, "y": z.copy(), "z": 60 + z,
           "qx": z, "qy": z, "qz": z, "qw": 1 + z, "vx": z, "vy": z, "vz": z}
    car = {"tick": np.arange(n), "t": t, "vehicle": z.astype(int), "x": 10 * t, "y": 5 + z, "z": 0.5 + z, "yaw": z,
           "vx": 10 + z, "vy": z, "vz": z}
    # two detections at t = 1.0 (target + clutter) and one at 1.5
    target = np.array([10.0, 5.0, 0.5])
    d = target - np.array([100.0, 0.0, 60.0])
    r, az, el = np.linalg.norm(d), np.arctan2(d[1], d[0]), np.arctan2(d[2], np.hypot(d[0], d[1]))
    det = {"t_meas": np.array([1.0, 1.0, 1.5]), "uav": np.zeros(3, int), "sensor": np.array(["u/radar0"] * 3),
           "kind": np.array(["radar"] * 3), "truth_id": np.array([0, -1, 0]),
           "z0": np.array([r, 50.0, r]), "z1": np.array([az, 0.0, az]), "z2": np.array([el, -1.0, el]),
           "z3": np.zeros(3)}
    return {"uav_truth": uav, "vehicle_truth": car, "detections": det}, target


def test_timeline_radar_scan_points_and_hold():
    streams, target = _streams()
    tl = Timeline(streams, scan_hold=0.4)
    assert tl.radar_scans(0.9) == []
    (scan,) = tl.radar_scans(1.2)
    assert scan.t_meas == 1.0 and scan.clutter.tolist() == [False, True]
    np.testing.assert_allclose(scan.points_W[0], target, atol=1e-9)
    assert tl.radar_scans(1.45) == []  # older than scan_hold
    (scan,) = tl.radar_scans(1.6)
    assert scan.t_meas == 1.5 and scan.points_W.shape == (1, 3)
    np.testing.assert_allclose(tl.vehicles[0].at(1.05)[0], [10.5, 5.0, 0.5], atol=1e-9)


def test_timeline_needs_uav_truth_only():
    streams, _ = _streams()
    del streams["vehicle_truth"]
    tl = Timeline(streams)
    assert tl.vehicles == {} and (tl.t_start, tl.t_end) == (0.0, 2.0)
    del streams["uav_truth"]
    with pytest.raises(ValueError, match="uav_truth"):
        Timeline(streams)


@pytest.mark.parametrize("kw,field", [({"width": 641}, "width"), ({"fps": 0}, "fps"), ({"camera": "fisheye"}, "camera"),
                                      ({"render_scale": 1.5}, "render_scale"), ({"t_start": 5, "t_end": 2}, "t_end"),
                                      ({"renderer": "vulkan"}, "renderer"), ({"uav_scale": 0}, "uav_scale")])
def test_config_rejects_bad_values(kw, field):
    with pytest.raises(ValueError, match=f"RenderConfig.{field}"):
        RenderConfig(**kw)


def test_standoff_circle_drawn_at_its_projected_radius():
    """Seen straight down from height H, a ground circle of radius R is a pixel circle of radius R f / H."""
    H, R, vfov, w, h = 400.0, 100.0, np.deg2rad(40), 640, 480
    view = CameraView(eye_W=np.array([20.0, -10.0, H]), target_W=np.array([20.0, -10.0, 0.0]),
                      up_W=np.array([0.0, 1.0, 0.0]), vfov=vfov)
    mark = EstimateMark(0, (0.0, 1.0, 0.0), np.array([20.0, -10.0]), np.diag([1e-6, 1e-6]), standoff_m=R)
    img = np.zeros((h, w, 3), np.uint8)
    draw_overlays(img, view, OverlayFrame(target_W=None, estimates=[mark]))
    rows, cols = np.nonzero(img[:, :, 1] > 128)
    r_px = np.hypot(cols + 0.5 - w / 2, rows + 0.5 - h / 2)
    ring = r_px > 20  # leave out the estimate's cross at the centre
    f = h / 2 / np.tan(vfov / 2)
    assert ring.sum() > 200
    np.testing.assert_allclose(r_px[ring], R * f / H, atol=2.0)
