"""Tracks in the video: the ``tracks`` stream held per UAV step (indexed once), every track drawn as a ring with its
id, the track taken for the target as a filled dot with its ``p_target``, the other cars' truth in grey brackets, and
a replay of a synthetic tracking run carrying all of it."""

import warnings

import numpy as np
import pytest

from simulator.render.config import RenderConfig
from simulator.render.overlays import OverlayFrame, TrackMark, draw_overlays
from simulator.render.projection import CameraView
from simulator.render.replay import Replayer
from simulator.render.timeline import Timeline
from simulator.runrecord import load_run
from tests.simulator.track_runs import car_xy, uav0_rows, write_track_run

H, VFOV, W_PX, H_PX = 200.0, np.deg2rad(40.0), 640, 480
BLUE = (0.1, 0.4, 1.0)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    return write_track_run(tmp_path_factory.mktemp("track_video") / "run")


def _down():
    return CameraView(eye_W=np.array([0.0, 0.0, H]), target_W=np.array([0.0, 0.0, 0.0]),
                      up_W=np.array([0.0, 1.0, 0.0]), vfov=VFOV)


def _px(view, p_W):
    uv, front = view.project(np.atleast_2d(p_W), W_PX, H_PX)
    assert front.all()
    return int(uv[0, 0]), int(uv[0, 1])


@pytest.mark.parametrize("t", [0.0, 4.2, 5.0, 7.3, 9.9, 50.0])
def test_timeline_holds_each_uavs_tracks_of_its_last_step(run_dir, t):
    steps = Timeline(load_run(run_dir).streams).tracks[0]
    got = steps.at(t)
    t_step = min(np.floor(t / 0.5) * 0.5, 9.5)
    want = sorted(uav0_rows(t_step))
    assert got.t == pytest.approx(t_step)
    assert got.track.tolist() == [r[0] for r in want]
    assert got.is_target.tolist() == [r[3] for r in want]
    np.testing.assert_allclose(got.p_target, [r[2] for r in want])
    np.testing.assert_allclose(got.xy, [np.add(car_xy(r[1], t_step), (1.0, 0.5)) for r in want])


def test_no_tracks_before_the_first_step_and_none_without_the_stream(run_dir, tmp_path):
    assert Timeline(load_run(run_dir).streams).tracks[1].at(-0.1) is None
    bare = write_track_run(tmp_path / "bare", with_tracks=False)
    assert Timeline(load_run(bare).streams).tracks == {}


def test_tracks_and_traffic_are_drawn_where_they_project():
    view = _down()
    mark = TrackMark(uav=0, rgb=BLUE, track=np.array([4, 9]), xy=np.array([[-20.0, 10.0], [25.0, -15.0]]),
                     p_target=np.array([0.12, 0.87]), is_target=np.array([False, True]))
    traffic = np.array([[-30.0, -30.0, 0.0]])
    img = np.zeros((H_PX, W_PX, 3), np.uint8)
    draw_overlays(img, view, OverlayFrame(target_W=None, tracks=[mark], traffic_W=traffic))
    blue = (img[:, :, 2] > 150) & (img[:, :, 0] < 60)  # the UAV's colour, anti-aliased edges included
    grey = (np.ptp(img.astype(int), axis=2) < 8) & (img[:, :, 0] > 60)
    # the target track: a filled dot in the UAV's colour, its label (id and p_target) to its right
    u, v = _px(view, [25.0, -15.0, 0.0])
    assert blue[v - 1:v + 2, u - 1:u + 2].all()
    assert blue[v - 20:v + 30, u + 8:u + 120].sum() > 20  # the text (none there without a label)
    # another track: a ring (its centre left dark) with its id
    u, v = _px(view, [-20.0, 10.0, 0.0])
    assert not img[v, u].any() and blue[v - 5:v + 6, u - 5:u + 6].sum() > 8
    assert blue[v:v + 20, u + 3:u + 20].sum() > 5
    # a traffic car: grey corner brackets around it and nowhere else
    u, v = _px(view, traffic[0])
    assert grey[v - 9:v + 10, u - 9:u + 10].sum() > 12 and not grey[v - 4:v + 5, u - 4:u + 5].any()
    assert grey.sum() == grey[v - 9:v + 10, u - 9:u + 10].sum()


def test_replay_of_a_tracking_run_carries_tracks_traffic_and_the_target_track_in_the_hud(run_dir):
    cfg = RenderConfig(width=160, height=120, fps=2, renderer="tiny", camera="topdown", progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the synthetic run has no world file
        rep = Replayer(run_dir, cfg)
    try:
        marks = rep.overlay_frame(5.2)
        assert [m.uav for m in marks.tracks] == [0, 1]
        assert marks.tracks[0].track.tolist() == [2, 3] and marks.tracks[0].is_target.tolist() == [False, True]
        np.testing.assert_allclose(marks.traffic_W[:, :2], [car_xy(1, 5.2)], atol=1e-9)
        np.testing.assert_allclose(marks.target_W[:2], car_xy(0, 5.2), atol=1e-9)
        hud = [text for text, _ in rep.hud_lines(7.2)]
        assert "2 tracks, target 2 (p 0.60)" in hud[1] and "2 tracks, target 10 (p 0.95)" in hud[2]
        frames = list(rep.render_frames(stop=2))
        assert len(frames) == 2 and frames[1].rgb.shape == (120, 160, 3)
    finally:
        rep.close()


def test_other_cars_bracketed_are_those_of_role_traffic():
    from simulator.render.world_view import ReplayWorld
    from worlds.loader import load_world

    traffic = ReplayWorld(load_world("road_standoff_traffic").world)
    assert traffic.vehicle_role(0) == "target" and traffic.vehicle_role(25) is None
    assert {traffic.vehicle_role(v) for v in range(1, 25)} == {"traffic"}
    two_targets = ReplayWorld(load_world("search_decoys").world)
    assert [two_targets.vehicle_role(v) for v in (0, 1)] == ["target", "target"]  # no grey brackets there
