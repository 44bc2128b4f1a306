"""The plots of a multi-target tracking run: the target track per step and its ID switches read from the ``tracks``
stream, ``tracks.png`` drawn when (and only when) the record has one, and the switches marked on ``errors.png``."""

import cv2
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from simulator.plots import write_plots  # noqa: E402
from simulator.plots_tracks import id_switch_times, mark_id_switches, target_track_series  # noqa: E402
from simulator.runrecord import load_run  # noqa: E402
from tests.simulator.track_runs import STEPS, SWITCHES, uav0_rows, uav1_rows, write_track_run  # noqa: E402


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    return write_track_run(tmp_path_factory.mktemp("tracks") / "run")


@pytest.mark.parametrize("uav", [0, 1])
def test_id_switches_are_the_changes_of_the_target_track_id(run_dir, uav):
    tracks = load_run(run_dir).streams["tracks"]
    np.testing.assert_allclose(id_switch_times(tracks, uav), SWITCHES[uav])


@pytest.mark.parametrize(("uav", "rows"), [(0, uav0_rows), (1, uav1_rows)])
def test_target_track_series_takes_the_flagged_track_with_the_largest_p_target(run_dir, uav, rows):
    series = target_track_series(load_run(run_dir).streams["tracks"], uav)
    np.testing.assert_allclose(series.t, STEPS)
    for k, t in enumerate(STEPS):
        flagged = [(p, track) for track, _, p, is_target in rows(float(t)) if is_target]
        others = [p for _, _, p, is_target in rows(float(t)) if not is_target]
        if flagged:
            p, track = max(flagged)
            assert series.track[k] == track and series.p_target[k] == pytest.approx(p), t
        else:
            assert series.track[k] == -1 and np.isnan(series.p_target[k]), t
        if others:
            assert series.p_other[k] == pytest.approx(max(others)), t
        else:
            assert np.isnan(series.p_other[k]), t


def test_no_rows_of_a_uav_give_an_empty_series(run_dir):
    series = target_track_series(load_run(run_dir).streams["tracks"], 7)
    assert series.t.size == series.track.size == 0 and series.switch_times().size == 0


def test_id_switches_are_marked_at_their_times_in_the_uavs_colour(run_dir):
    fig, ax = plt.subplots()
    try:
        n = mark_id_switches(ax, load_run(run_dir), ["tab:blue", "tab:orange"])
        assert n == len(SWITCHES[0]) + len(SWITCHES[1])
        xs = sorted(float(line.get_xdata()[0]) for line in ax.lines)
        np.testing.assert_allclose(xs, SWITCHES[0])
        assert {line.get_color() for line in ax.lines} == {"tab:blue"}
    finally:
        plt.close(fig)


def _pixels_near(img_bgr, rgb, tol=40):
    return int((np.abs(img_bgr[:, :, ::-1].astype(int) - np.array(rgb)).max(axis=2) < tol).sum())


def test_tracks_png_is_drawn_with_the_target_truth_and_the_held_tracks(run_dir):
    names = {p.name for p in write_plots(run_dir)}
    assert {"tracks.png", "errors.png", "trajectories.png"} <= names
    img = cv2.imread(str(run_dir / "plots" / "tracks.png"))
    assert img is not None and img.shape[1] > img.shape[0] and img.std() > 5.0
    crimson = (220, 20, 60)
    blue, orange = (31, 119, 180), (255, 127, 14)  # tab:blue, tab:orange: UAV 0 and 1's held tracks
    assert _pixels_near(img, crimson) > 200
    half = img.shape[1] // 2
    assert _pixels_near(img[:, :half], blue) > 200 and _pixels_near(img[:, half:], blue) < 50
    assert _pixels_near(img[:, half:], orange) > 200 and _pixels_near(img[:, :half], orange) < 50


def test_no_tracks_stream_no_tracks_png(tmp_path):
    run_dir = write_track_run(tmp_path / "run", with_tracks=False)
    names = {p.name for p in write_plots(run_dir)}
    assert "tracks.png" not in names and "errors.png" in names
