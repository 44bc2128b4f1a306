"""Replaying a recorded demo run to video: a valid MP4 of the right length and size, and overlays that land on the
rendered target (checked against PyBullet's segmentation mask) for every camera."""

import dataclasses
import subprocess
import warnings

import cv2
import numpy as np
import pytest

from simulator.api import run
from simulator.render.config import RenderConfig
from simulator.render.encode import VideoEncoder
from simulator.render.replay import Replayer
from simulator.render.video import render_run


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("render_run")
    run("demo", duration=4.0, seed=3, out_dir=out)
    return out


def _decode(path):
    cap = cv2.VideoCapture(str(path))
    assert cap.isOpened()
    frames = []
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        frames.append(frame)
    fps = cap.get(cv2.CAP_PROP_FPS)
    cap.release()
    return frames, fps


def test_two_second_render_is_a_valid_mp4(run_dir, tmp_path):
    cfg = RenderConfig(out=tmp_path / "clip.mp4", width=320, height=180, fps=15, t_start=1.0, t_end=3.0,
                       renderer="tiny", camera="split", progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        path = render_run(run_dir, cfg)
    assert path == tmp_path / "clip.mp4" and path.stat().st_size > 1000
    assert path.read_bytes()[4:8] == b"ftyp"  # an MP4 container
    try:
        import imageio_ffmpeg
    except ImportError:  # the OpenCV fallback wrote mp4v
        imageio_ffmpeg = None
    if imageio_ffmpeg is not None:
        probe = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)],
                               capture_output=True, text=True, check=False).stderr
        assert "Video: h264" in probe and "yuv420p" in probe  # what browsers play
    frames, fps = _decode(path)
    assert abs(len(frames) - 15 * 2) <= 1
    assert fps == pytest.approx(15.0)
    assert frames[0].shape == (180, 320, 3)
    # the picture changes over time (bodies and cameras move) but is not noise
    diffs = [np.abs(a.astype(int) - b.astype(int)).mean() for a, b in zip(frames[:-1], frames[1:], strict=True)]
    assert 0.0 < np.mean(diffs) < 40.0


@pytest.mark.parametrize("camera,follow,scale", [("chase", False, 1.0), ("orbit", False, 1.0), ("topdown", True, 1.0),
                                                 ("onboard", False, 1.0), ("chase", False, 0.5)])
def test_projected_target_lies_on_its_rendered_pixels(run_dir, camera, follow, scale):
    cfg = RenderConfig(width=320, height=240, fps=5, t_start=0.5, t_end=3.5, renderer="tiny", camera=camera,
                       topdown_follow=follow, topdown_span_m=80.0, overlays=False, render_scale=scale,
                       progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = Replayer(run_dir, cfg)
    try:
        car = rep.stage.vehicle_ids[rep.target]
        checked = 0
        for frame in rep.render_frames(segmentation=True):
            (panel,) = frame.panels
            blob = panel.seg == car
            if blob.sum() < 4:
                continue
            p_t = rep.timeline.vehicles[rep.target].at(frame.t)[0]
            uv, front = panel.view.project(p_t, panel.width, panel.height)
            assert front[0]
            i, j = int(np.floor(uv[0, 0])), int(np.floor(uv[0, 1]))
            near = blob[max(j - 1, 0):j + 2, max(i - 1, 0):i + 2]  # within a pixel of the projected centre
            assert near.any(), f"{camera} t={frame.t:.2f}: projected car at {uv[0]} off its blob"
            rows, cols = np.nonzero(blob)
            assert np.hypot(cols.mean() + 0.5 - uv[0, 0], rows.mean() + 0.5 - uv[0, 1]) < 3.0
            checked += 1
        assert checked >= 10
    finally:
        rep.close()


def test_split_frame_layout_and_hud(run_dir):
    cfg = RenderConfig(width=400, height=200, fps=2, t_start=2.0, t_end=3.0, renderer="tiny", camera="split",
                       progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = Replayer(run_dir, cfg)
    try:
        frame = next(rep.render_frames())
        assert frame.rgb.shape == (200, 400, 3)
        assert [(pn.name, pn.x0, pn.width) for pn in frame.panels] == [("chase", 0, 200), ("topdown", 200, 200)]
        lines = rep.hud_lines(frame.t)
        assert lines[0][0].endswith(f"t = {frame.t:6.2f} s") and len(lines) == 1 + len(rep.uav_index)
    finally:
        rep.close()


def test_opencv_fallback_writer(tmp_path):
    rng = np.random.default_rng(0)
    with VideoEncoder(tmp_path / "cv.mp4", 64, 48, 10, backend="opencv") as enc:
        for _ in range(7):
            enc.write(rng.integers(0, 255, size=(48, 64, 3), dtype=np.uint8))
        with pytest.raises(ValueError, match="frame must be"):
            enc.write(np.zeros((10, 10, 3), np.uint8))
    frames, _ = _decode(tmp_path / "cv.mp4")
    assert len(frames) == 7 and frames[0].shape == (48, 64, 3)


@pytest.mark.slow
def test_auto_renderer_picks_a_working_one(run_dir, tmp_path):
    """``auto`` probes EGL in a child process, times both renderers and keeps one; the video is valid either way."""
    cfg = RenderConfig(out=tmp_path / "auto.mp4", width=256, height=144, fps=10, t_start=1.0, t_end=2.0,
                       renderer="auto", camera="orbit", progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = Replayer(run_dir, cfg)
    try:
        assert rep.stage.renderer_name in ("egl", "tiny")
        frames = list(rep.render_frames(segmentation=True))
        assert len(frames) == 10
        car = rep.stage.vehicle_ids[rep.target]
        assert sum(int((f.panels[0].seg == car).sum() > 0) for f in frames) >= 8  # the orbit camera keeps the car
    finally:
        rep.close()


def test_run_without_cars_renders(tmp_path):
    """A world without ground vehicles: the cameras look at the ground under the fleet and the HUD has no error."""
    run("demo", duration=1.5, seed=2, overrides=["ground_vehicles=[]"], out_dir=tmp_path / "run")
    cfg = RenderConfig(width=160, height=96, fps=10, renderer="tiny", camera="split", progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        path = render_run(tmp_path / "run", cfg)
    frames, _ = _decode(path)
    assert path == tmp_path / "run" / "video.mp4" and abs(len(frames) - 14) <= 1


def test_worker_processes_give_the_same_frames(run_dir):
    """Frames rendered by two worker processes equal those of one pass in this process, pixel for pixel."""
    from simulator.render.parallel import iter_frames

    cfg = RenderConfig(width=160, height=96, fps=10, t_start=0.5, t_end=3.5, renderer="tiny", camera="split",
                       progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        n1, serial = iter_frames(run_dir, cfg)
        one = list(serial)
        n2, pooled = iter_frames(run_dir, dataclasses.replace(cfg, workers=2))
        two = list(pooled)
    assert n1 == n2 == len(one) == len(two) == 30
    for a, b in zip(one, two, strict=True):
        np.testing.assert_array_equal(a, b)
