"""Physics: a car drives a random route through the real Helsinki street network and stays on its roads."""

import numpy as np
import pytest

from simulator.api import run


@pytest.mark.slow
def test_car_completes_random_route_through_helsinki(tmp_path):
    result = run("helsinki_drive", duration=150.0, seed=4, out_dir=tmp_path, overrides=["uavs=[]"])
    assert result.status == "completed", result.error
    events = result.record.events
    entered = [e["road"] for e in events if e["type"] == "car_enter_road"]
    assert len(entered) >= 6, f"the car only reached {entered}"
    assert not [e for e in events if e["type"] == "car_left_road"]
    vt = result.stream("vehicle_truth", vehicle=0)
    assert np.percentile(np.abs(vt["lateral"]), 95) < 3.0  # within its carriageway (lane offset ≈ -1.75 m)
    travelled = np.sum(np.hypot(np.diff(vt["x"]), np.diff(vt["y"])))
    assert travelled > 300.0  # 30 km/h streets, stop-and-go at every junction with 2-8 s dwells
    from worlds.build import resolve_map_path
    from worlds.osm import load_osm

    network = load_osm(resolve_map_path("helsinki.osm.pbf", result.out_dir)).network
    route = ["w166170099_0.f", *entered]
    # a continuous route: each road leaves the junction the previous one enters
    for a, b in zip(route, route[1:], strict=False):
        assert b in network.successors(a), f"{b} does not follow {a}"
    assert np.all(np.abs(vt["z"]) < 1.5)  # on the ground: no flips, no sinking
