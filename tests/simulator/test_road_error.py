"""The along / across-road split of estimation errors used by paper 002's report."""

import numpy as np
import pytest

from simulator.reproduce.road_error import JUNCTION_BINS, road_lengths, split_error


def test_offsets_in_the_cars_frame_come_back_exactly():
    rng = np.random.default_rng(4)
    n = 200
    yaw = rng.uniform(-np.pi, np.pi, n)
    truth = rng.uniform(-300, 300, (n, 2))
    along, cross = rng.normal(-3.0, 5.0, n), rng.normal(1.0, 2.0, n)
    t, nrm = np.column_stack([np.cos(yaw), np.sin(yaw)]), np.column_stack([-np.sin(yaw), np.cos(yaw)])
    est = truth + along[:, None] * t + cross[:, None] * nrm
    jd = rng.uniform(0, 80, n)
    sp = split_error(est, truth, yaw, jd)
    assert sp.n == n
    assert sp.along_mean == pytest.approx(along.mean(), abs=1e-9)
    assert sp.cross_mean == pytest.approx(cross.mean(), abs=1e-9)
    assert sp.along_rms == pytest.approx(np.sqrt(np.mean(along ** 2)), abs=1e-9)
    assert sp.cross_rms == pytest.approx(np.sqrt(np.mean(cross ** 2)), abs=1e-9)
    assert sp.mean_error == pytest.approx(np.hypot(along, cross).mean(), abs=1e-9)
    for b, (lo, hi) in enumerate(zip(JUNCTION_BINS[:-1], JUNCTION_BINS[1:], strict=True)):
        k = (jd >= lo) & (jd < hi)
        assert sp.share_by_bin[b] == pytest.approx(k.mean())
        assert sp.along_mean_by_bin[b] == pytest.approx(along[k].mean(), abs=1e-9)
    assert sum(sp.share_by_bin) == pytest.approx(1.0)


def test_an_empty_bin_is_nan_not_an_error():
    sp = split_error(np.array([[1.0, 0.0]]), np.zeros((1, 2)), np.zeros(1), np.array([50.0]))
    assert np.isnan(sp.along_mean_by_bin[0]) and sp.along_mean_by_bin[-1] == pytest.approx(1.0)


def test_road_lengths_from_a_geometry_file(tmp_path):
    # a 3-4-5 polyline and a straight 10 m road, packed as simulator.plots.write_geometry packs them
    xy = np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 9.0], [0.0, 0.0], [10.0, 0.0]])
    np.savez(tmp_path / "geometry.npz", road_xy=xy, road_offsets=np.array([0, 3, 5]),
             road_ids=np.array(["a.f", "b.r"]))
    assert road_lengths(tmp_path / "geometry.npz") == pytest.approx({"a.f": 10.0, "b.r": 10.0})
