"""The SUMO cost benchmark runs end to end (tiny sizes; the figures themselves come from ``python -m
vehicles.sumo.bench``)."""

from __future__ import annotations

import pytest

from vehicles.sumo._runtime import sumo_available
from vehicles.sumo.bench import grid_network, run_bench


@pytest.mark.skipif(not sumo_available(), reason="SUMO is not installed (pip install 'skytrack[traffic]')")
def test_bench_runs_and_reports_three_real_time_factors(tmp_path) -> None:
    res = run_bench(n_vehicles=12, grid_n=3, spacing=100.0, seconds=1.0, warmup=0.5, repeats=1, work_dir=str(tmp_path))
    assert res.sumo_alone > 0 and res.mirrored > 0 and res.mirrored_synced > 0
    assert 0 < res.vehicles_on_road <= 12


def test_grid_network_shape() -> None:
    net = grid_network(3, 100.0)
    assert len(net.nodes) == 9 and len(net.roads) == 24 and net.is_connected()
