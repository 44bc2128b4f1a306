"""Ground regions in the video (the search's sets): filled where they project, holes open, cut where the camera cannot
see them (behind it, or behind a building), and read back from the run's set snapshots."""

import gzip
import json
import warnings

import numpy as np
import pytest
import shapely

from simulator.record import RunRecorder
from simulator.render.overlays import GroundRegion, OverlayFrame, _in_front, draw_overlays
from simulator.render.projection import CameraView
from simulator.runrecord import load_search_sets

H, VFOV, W_PX, H_PX = 400.0, np.deg2rad(40.0), 640, 480
F_PX = H_PX / 2 / np.tan(VFOV / 2)  # pixels per unit of (lateral / depth)


def _down(x=0.0, y=0.0):
    return CameraView(eye_W=np.array([x, y, H]), target_W=np.array([x, y, 0.0]), up_W=np.array([0.0, 1.0, 0.0]),
                      vfov=VFOV)


def _filled(geom, view, alpha=1.0, ground_visible=None):
    img = np.zeros((H_PX, W_PX, 3), np.uint8)
    draw_overlays(img, view, OverlayFrame(target_W=None, regions=[GroundRegion((0.0, 1.0, 0.0), alpha, geom)]),
                  ground_visible=ground_visible)
    return img[:, :, 1] > 128


def test_a_square_seen_from_above_fills_its_projected_area():
    """A 100 m square seen straight down from 400 m covers (100 F / H)² pixels, at its projected place."""
    sq = shapely.box(-60.0, -20.0, 40.0, 80.0)
    mask = _filled(sq, _down())
    side = 100.0 * F_PX / H
    assert mask.sum() == pytest.approx(side**2, rel=0.03)
    rows, cols = np.nonzero(mask)
    # centre (-10, 30) m: right of the image centre by x F / H, above it by y F / H (image y grows downwards)
    assert cols.mean() + 0.5 == pytest.approx(W_PX / 2 - 10.0 * F_PX / H, abs=1.0)
    assert rows.mean() + 0.5 == pytest.approx(H_PX / 2 - 30.0 * F_PX / H, abs=1.0)


def test_a_hole_stays_open_and_alpha_blends():
    ring = shapely.box(-100.0, -100.0, 100.0, 100.0).difference(shapely.box(-30.0, -30.0, 30.0, 30.0))
    mask = _filled(ring, _down())
    assert not mask[H_PX // 2 - 5:H_PX // 2 + 5, W_PX // 2 - 5:W_PX // 2 + 5].any()
    assert mask.sum() == pytest.approx((200.0**2 - 60.0**2) * (F_PX / H) ** 2, rel=0.03)
    img = np.zeros((H_PX, W_PX, 3), np.uint8)
    draw_overlays(img, _down(), OverlayFrame(target_W=None, regions=[GroundRegion((0.0, 1.0, 0.0), 0.3, ring)]))
    assert img[H_PX // 2, W_PX // 2 + 100, 1] == pytest.approx(0.3 * 255, abs=2)  # inside the fill, off its edge


def test_front_half_plane_closed_form():
    """Camera at (0, 0, 10) looking along +x and down 45°: a ground point (x, y, 0) is d in front of it when
    (x cos 45° + 10 sin 45°) >= d, i.e. x >= d √2 − 10."""
    view = CameraView(eye_W=np.array([0.0, 0.0, 10.0]), target_W=np.array([10.0, 0.0, 0.0]))
    front = _in_front(view, 0.0, 1.5)
    x0 = 1.5 * np.sqrt(2.0) - 10.0
    for x, inside in ((x0 + 0.01, True), (x0 - 0.01, False), (500.0, True), (-500.0, False)):
        assert front.contains(shapely.Point(x, 37.0)) == inside
    assert _in_front(_down(), 0.0, 1.0) is None  # looking straight down from above: all the ground is in front


def test_a_region_behind_or_across_the_camera_is_cut_not_smeared():
    view = CameraView(eye_W=np.array([0.0, 0.0, 10.0]), target_W=np.array([40.0, 0.0, 0.0]))
    assert not _filled(shapely.box(-300.0, -50.0, -20.0, 50.0), view).any()  # wholly behind
    across = _filled(shapely.box(-300.0, -20.0, 300.0, 20.0), view)  # a strip under and behind the camera
    assert across.any()
    rows, cols = np.nonzero(across)
    # the strip's in-front part is a trapezoid from the bottom edge of the image up to the horizon, centred
    assert rows.max() == H_PX - 1 and rows.min() > 0 and abs(cols.mean() + 0.5 - W_PX / 2) < 2.0


def test_regions_only_where_the_ground_is_seen():
    visible = np.ones((H_PX, W_PX), bool)
    visible[:, : W_PX // 2] = False  # e.g. a building wall over the left half
    mask = _filled(shapely.box(-100.0, -100.0, 100.0, 100.0), _down(), ground_visible=visible)
    assert mask[:, W_PX // 2:].sum() > 0 and not mask[:, : W_PX // 2].any()


def test_set_snapshots_round_trip_with_shared_sets_and_a_killed_tail(tmp_path):
    rec = RunRecorder(tmp_path)
    a, b = "POLYGON ((0 0, 1 0, 1 1, 0 0))", "POLYGON ((0 0, 5 0, 5 5, 0 0))"
    rec.append_line("search_sets.jsonl.gz", {"tick": 240, "t": 1.0, "uavs": [{"uav": 0, "X": a, "Xbar": b},
                                                                              {"uav": 1, "same_as": 0}]})
    rec.append_line("search_sets.jsonl.gz", {"tick": 480, "t": 2.0, "uavs": [{"uav": 0, "X": b, "Xbar": a},
                                                                              {"uav": 1, "X": a, "Xbar": a}]})
    rec.close()
    with gzip.open(tmp_path / "search_sets.jsonl.gz", "rt") as f:  # standard tools read it as one text
        assert [json.loads(line)["tick"] for line in f] == [240, 480]
    snaps = load_search_sets(tmp_path)
    assert [s.t for s in snaps] == [1.0, 2.0]
    assert snaps[0].sets == {0: (a, b), 1: (a, b)} and snaps[1].sets == {0: (b, a), 1: (a, a)}
    data = (tmp_path / "search_sets.jsonl.gz").read_bytes()
    (tmp_path / "search_sets.jsonl.gz").write_bytes(data[:-40])  # killed while writing the last line
    assert [s.t for s in load_search_sets(tmp_path)] == [1.0]
    assert load_search_sets(tmp_path / "nothing") == []


def test_replay_of_a_search_draws_the_sets_on_the_ground_only(tmp_path):
    """A short search run replayed top-down: the ridden UAV's sets are filled on the ground and never on a roof,
    the HUD gives each UAV's areas."""
    from simulator.api import run
    from simulator.render.config import RenderConfig
    from simulator.render.replay import Replayer

    res = run("search_decoys", duration=3.0, seed=1, out_dir=tmp_path / "run", plots=False)
    assert res.status == "completed", res.error
    snaps = load_search_sets(tmp_path / "run")
    assert [s.t for s in snaps] == [1.0, 2.0, 3.0] and all(len(s.sets) == 4 for s in snaps)
    cfg = RenderConfig(width=320, height=240, fps=2, t_start=2.5, renderer="tiny", camera="topdown", legend=False,
                       progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep = Replayer(tmp_path / "run", cfg)
    try:
        frame = next(rep.render_frames())
        (panel,) = frame.panels
        regions = rep.overlay_frame(frame.t).regions
        X, Xbar = (shapely.from_wkt(w) for w in snaps[1].sets[0])  # t = 2.5 s shows the snapshot of t = 2 s
        assert [r.geom.area for r in regions] == pytest.approx([Xbar.area, X.area], rel=1e-6)
        plain, _ = rep.stage.render(panel.view, panel.width, panel.height, ground_level=True)
        ground = rep.stage.ground_visible
        drawn = plain.copy()
        draw_overlays(drawn, panel.view, OverlayFrame(target_W=None, regions=regions), ground_visible=ground)
        tinted = np.abs(drawn.astype(int) - plain.astype(int)).sum(axis=2) > 12
        assert tinted[ground].mean() > 0.3 and not tinted[~ground].any()  # X̄ covers most of the area early on
        roofs = 0
        for b in rep.geometry.buildings:  # a roof's centre is not ground, and keeps its colour
            c = np.asarray(shapely.Polygon(b.footprint).centroid.coords[0])
            uv, front = panel.view.project(np.r_[c, b.top_z], panel.width, panel.height)
            i, j = int(uv[0, 0]), int(uv[0, 1])
            if front[0] and 0 <= i < panel.width and 0 <= j < panel.height:
                assert not ground[j, i]
                roofs += 1
        assert roofs >= 3
        lines = [text for text, _ in rep.hud_lines(frame.t)]
        assert all("X-bar" in line for line in lines[1:5]) and lines[5] == "sets drawn: uav1's"
    finally:
        rep.close()


def test_a_snapshot_writes_shared_sets_once():
    """UAVs whose sets are those of a UAV before them in the line (after fusing) are written ``same_as`` it."""
    from types import SimpleNamespace

    from simulator.search_team import _snapshot

    def slot(uav, X, Xbar):
        return uav, SimpleNamespace(X=shapely.from_wkt(X), Xbar=shapely.from_wkt(Xbar))

    a, b = "POLYGON ((0 0, 1 0, 1 1, 0 0))", "POLYGON ((0 0, 5 0, 5 5, 0 0))"
    line = _snapshot([slot(0, a, b), slot(1, b, a), slot(2, a, b), slot(3, b, a), slot(4, a, a)])
    assert [u.get("same_as") for u in line] == [None, None, 0, 1, None]
    assert line[4] == {"uav": 4, "X": a, "Xbar": a}
