"""skytrack roads as a SUMO network: SUMO's lanes lie on skytrack's lane centres, ids map both ways."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from vehicles.sumo._runtime import sumo_available
from vehicles.sumo.network import NetConfig, build_sumo_net, read_lane_shapes
from worlds.roads.network import RoadNetwork

pytestmark = pytest.mark.skipif(not sumo_available(), reason="SUMO is not installed (pip install 'skytrack[traffic]')")

STRAIGHT_TOL = 0.01  # m; SUMO lane centre vs skytrack lane centre on straight roads
CURVED_TOL = 0.05  # m; on curves (SUMO's polyline through 2 m samples of the spline)


def _network() -> RoadNetwork:
    """A 3 x 3 grid of 150 m blocks; the bottom row has 2 lanes per direction; plus a curved one-way road."""
    sp = 150.0
    nodes = {f"{i}_{j}": [i * sp, j * sp] for i in range(3) for j in range(3)}
    streets = [{"id": f"h{i}_{j}", "nodes": [f"{i}_{j}", f"{i + 1}_{j}"], "lanes": 2 if j == 0 else 1}
               for i in range(2) for j in range(3)]
    streets += [{"id": f"v{i}_{j}", "nodes": [f"{i}_{j}", f"{i}_{j + 1}"], "lane_width": 3.2}
                for i in range(3) for j in range(2)]
    streets.append({"id": "c", "nodes": ["0_0", "2_2"], "via": [[100, 20], [200, 100]], "two_way": False})
    return RoadNetwork.from_spec({"nodes": nodes, "streets": streets})


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    net = _network()
    return net, build_sumo_net(net, tmp_path_factory.mktemp("sumo_net"))


def test_lanes_lie_on_skytrack_lane_centres(built) -> None:
    net, sumo = built
    shapes = read_lane_shapes(sumo.net_file)
    checked = set()
    for lane_id, pts in shapes.items():
        if lane_id.startswith(":"):
            continue
        edge, k = lane_id.rsplit("_", 1)
        road = net.roads[sumo.edge_to_road[edge]]
        want = road.lane_offset(int(k))
        lat = np.array([road.project(q)[1] for q in pts])
        tol = CURVED_TOL if road.total_turn > 1e-9 else STRAIGHT_TOL
        assert np.max(np.abs(lat - want)) < tol, lane_id
        assert len(pts) >= 2 and np.hypot(*(pts[-1] - pts[0])) > 100.0, lane_id  # cut only at the junctions
        checked.add((road.id, int(k)))
    assert checked == {(r.id, k) for r in net.roads.values() for k in range(r.lanes)}
    # lanes of a two-way road on its right, of the one-way road centred on the centre-line
    assert net.roads["h0_0.f"].lane_offset(0) == -5.25 and net.roads["c.f"].lane_offset(0) == 0.0


def test_edge_ids_map_back_to_roads(built) -> None:
    net, sumo = built
    assert set(sumo.edge_to_road.values()) == set(net.roads)
    assert all(sumo.edge_to_road[sumo.road_to_edge[r]] == r for r in net.roads)
    assert sumo.road_of("h0_0.f") == "h0_0.f" and sumo.road_of(":1_1_0") == "" and sumo.road_of("nope") == ""
    root = ET.parse(sumo.net_file).getroot()
    edges = {e.get("id"): e for e in root.iter("edge") if e.get("function") != "internal"}
    assert set(edges) == set(sumo.edge_to_road)
    lane = edges["v1_0.f"].find("lane")
    assert float(lane.get("width")) == 3.2 and float(lane.get("speed")) == pytest.approx(13.9)
    assert len(edges["h0_0.r"].findall("lane")) == 2


def test_network_is_cached_by_content(built, tmp_path) -> None:
    net, sumo = built
    again = build_sumo_net(net, sumo.net_file.parent)
    assert again.net_file == sumo.net_file
    other = build_sumo_net(net, tmp_path, NetConfig(tls="none"))
    assert other.net_file.name != sumo.net_file.name


def test_signals_and_guessed_lights(tmp_path) -> None:
    net = _network()
    none = ET.parse(build_sumo_net(net, tmp_path, NetConfig(tls="none")).net_file).getroot()
    assert none.find("tlLogic") is None
    sig = ET.parse(build_sumo_net(net, tmp_path, NetConfig(tls="none", signals=("1_1",))).net_file).getroot()
    assert [t.get("id") for t in sig.iter("tlLogic")] == ["1_1"]
    types = {j.get("id"): j.get("type") for j in sig.iter("junction")}
    assert types["1_1"] == "traffic_light" and types["1_2"] == "priority"
    with pytest.raises(ValueError, match=r"NetConfig.signals: \['zz'\] are not nodes of the network"):
        build_sumo_net(net, tmp_path, NetConfig(signals=("zz",)))


def test_net_config_checks() -> None:
    with pytest.raises(ValueError, match="NetConfig.tls must be 'guess' or 'none', got 'osm'"):
        NetConfig(tls="osm")
    with pytest.raises(ValueError, match="NetConfig.shape_spacing must be > 0 m, got 0"):
        NetConfig(shape_spacing=0)


def test_signalised_junctions_within_20_m_run_one_program(tmp_path) -> None:
    """Two lit junctions 15 m apart (a divided road's two carriageways crossed by a street) get one traffic-light
    program (netconvert --tls.join); lit junctions 150 m apart keep one each."""
    nodes = {"A": [0, 0], "B": [15, 0], "W": [-150, 0], "E": [165, 0], "AN": [0, 150], "AS": [0, -150],
             "BN": [15, 150], "BS": [15, -150]}
    streets = [{"id": "wa", "nodes": ["W", "A"]}, {"id": "ab", "nodes": ["A", "B"]}, {"id": "be", "nodes": ["B", "E"]},
               {"id": "na", "nodes": ["AN", "A"], "two_way": False},
               {"id": "as", "nodes": ["A", "AS"], "two_way": False},
               {"id": "sb", "nodes": ["BS", "B"], "two_way": False},
               {"id": "bn", "nodes": ["B", "BN"], "two_way": False}]
    near = RoadNetwork.from_spec({"nodes": nodes, "streets": streets})
    root = ET.parse(build_sumo_net(near, tmp_path, NetConfig(tls="none", signals=("A", "B"))).net_file).getroot()
    assert len(root.findall("tlLogic")) == 1
    assert sorted(j.get("id") for j in root.iter("junction") if j.get("type") == "traffic_light") == ["A", "B"]
    far = ET.parse(build_sumo_net(_network(), tmp_path, NetConfig(tls="none", signals=("1_1", "1_2"))).net_file)
    assert sorted(t.get("id") for t in far.getroot().iter("tlLogic")) == ["1_1", "1_2"]


def _build_in(work_dir: str) -> str:
    return build_sumo_net(_network(), work_dir).net_file.name


def test_parallel_builds_of_one_network_share_the_cache_safely(tmp_path) -> None:
    """Four processes build the same network into one empty cache at once (a campaign's workers): each gets the one
    cached file, and no intermediate file is left behind."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(4, mp_context=mp.get_context("spawn")) as pool:
        names = list(pool.map(_build_in, [str(tmp_path)] * 4))
    assert len(set(names)) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == names[:1]
    assert ET.parse(tmp_path / names[0]).getroot().find("edge") is not None
