"""The run directory's plots: every figure the record allows, readable PNGs, redrawn from the directory alone."""

import cv2

from simulator.api import run
from simulator.plots import write_plots


def test_standoff_and_link_plots_appear_with_standoff_guidance_and_a_lossy_radio(tmp_path):
    out = tmp_path / "run"
    run("demo", duration=3.0, seed=2, out_dir=out, overrides=["comms.model=rayleigh", "comms.block_by_buildings=true"])
    names = {p.name for p in write_plots(out)}
    # demo has traffic: its multi-target tracks are drawn too
    assert names == {"trajectories.png", "errors.png", "altitude.png", "standoff.png", "links.png", "tracks.png"}
    for name in names:
        img = cv2.imread(str(out / "plots" / name))
        assert img is not None and img.shape[0] > 200 and img.std() > 5.0  # a drawn figure, not a blank canvas


def test_perfect_radio_has_no_link_plot(tmp_path):
    out = tmp_path / "run"
    run("demo", duration=1.0, seed=2, out_dir=out)
    names = {p.name for p in write_plots(out)}
    assert "links.png" not in names and "standoff.png" in names
