"""Road graph: successors (no U-turn), shortest routes, random walks, nearest road, connectivity, spec parsing."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.stats import binom

from worlds.roads.network import RoadNetwork, street_road_ids
from worlds.roads.road import Road

# A square A-B-C-D (D pulled up so that C->D->A is longer than C->B->A), a dead-end spur B-E,
# a one-way diagonal A->C, and node F with no roads.
NODES = {"A": [0.0, 0.0], "B": [100.0, 0.0], "C": [100.0, 100.0], "D": [0.0, 110.0], "E": [200.0, 0.0]}
STREETS = [
    {"id": "ab", "nodes": ["A", "B"]},
    {"id": "bc", "nodes": ["B", "C"], "lanes": 2},
    {"id": "cd", "nodes": ["C", "D"]},
    {"id": "da", "nodes": ["D", "A"]},
    {"id": "be", "nodes": ["B", "E"], "speed_limit": 8.0},
    {"id": "ac", "nodes": ["A", "C"], "via": [[40.0, 60.0]], "two_way": False},
]


@pytest.fixture(scope="module")
def net() -> RoadNetwork:
    return RoadNetwork.from_spec({"nodes": NODES, "streets": STREETS})


def test_from_spec_builds_twins_and_attributes(net):
    assert len(net.roads) == 11
    assert street_road_ids("ab") == ("ab.f", "ab.r")
    ab, ba = net.roads["ab.f"], net.roads["ab.r"]
    assert (ab.start_node, ab.end_node, ab.twin) == ("A", "B", "ab.r")
    assert (ba.start_node, ba.end_node, ba.twin) == ("B", "A", "ab.f")
    np.testing.assert_allclose(ba.point(0.0), NODES["B"])
    assert net.roads["bc.r"].lanes == 2 and net.roads["be.f"].speed_limit == 8.0
    assert net.roads["ac.f"].twin is None and "ac.r" not in net.roads
    np.testing.assert_allclose(net.roads["ac.f"].point(0.0), NODES["A"], atol=1e-12)
    np.testing.assert_allclose(net.roads["ac.f"].point(net.roads["ac.f"].length), NODES["C"], atol=1e-9)


def test_from_spec_accepts_attribute_objects():
    streets = [SimpleNamespace(id="s", nodes=("A", "B"), via=[], lanes=1, lane_width=3.0, speed_limit=10.0,
                               two_way=True)]
    net = RoadNetwork.from_spec(SimpleNamespace(nodes={"A": (0, 0), "B": (10, 0)}, streets=streets))
    assert set(net.roads) == {"s.f", "s.r"} and net.roads["s.f"].lane_width == 3.0


def test_successors_exclude_twin_unless_dead_end(net):
    assert sorted(net.successors("ab.f")) == ["bc.f", "be.f"]
    assert net.successors("be.f") == ["be.r"]  # dead end: U-turn is the only way on
    assert sorted(net.successors("da.f")) == ["ab.f", "ac.f"]
    assert sorted(net.successors("ac.f")) == ["bc.r", "cd.f"]
    with pytest.raises(ValueError, match="unknown road"):
        net.successors("zz")


def test_route_shortest_by_length(net):
    assert net.route("A", "C") == ["ac.f"]  # one-way diagonal, 141.4 m < 200 m
    assert net.route("C", "A") == ["bc.r", "ab.r"]  # 200 m < 100.5 + 110 m via D
    assert net.route("E", "D") == ["be.r", "bc.f", "cd.f"]  # 300.5 m < 310 m via A
    assert net.route("A", "A") == []
    with pytest.raises(ValueError, match="unknown node"):
        net.route("A", "Q")


def test_route_unreachable_raises():
    net = RoadNetwork.from_spec({"nodes": {"A": [0, 0], "B": [10, 0], "F": [50, 50]},
                                 "streets": [{"id": "ab", "nodes": ["A", "B"], "two_way": False}]})
    with pytest.raises(ValueError, match="cannot be reached"):
        net.route("B", "A")
    with pytest.raises(ValueError, match="cannot be reached"):
        net.route("A", "F")
    assert not net.is_connected()


def test_connectivity(net):
    assert net.is_connected()
    one_way_loop = RoadNetwork.from_spec({"nodes": NODES, "streets": [
        {"id": s, "nodes": n, "two_way": False} for s, n in (("ab", ["A", "B"]), ("bc", ["B", "C"]),
                                                              ("cd", ["C", "D"]), ("da", ["D", "A"]))]})
    assert not one_way_loop.is_connected()  # E has no roads
    del_e = dict(NODES)
    del del_e["E"]
    loop = RoadNetwork.from_spec({"nodes": del_e, "streets": [
        {"id": s, "nodes": n, "two_way": False} for s, n in (("ab", ["A", "B"]), ("bc", ["B", "C"]),
                                                              ("cd", ["C", "D"]), ("da", ["D", "A"]))]})
    assert loop.is_connected()
    assert loop.route("B", "A") == ["bc.f", "cd.f", "da.f"]


def test_random_route_follows_successors_and_is_seeded(net):
    r1 = net.random_route("ab.f", 200, np.random.default_rng(7))
    r2 = net.random_route("ab.f", 200, np.random.default_rng(7))
    r3 = net.random_route("ab.f", 200, np.random.default_rng(8))
    assert r1 == r2 and r1 != r3 and len(r1) == 200 and r1[0] == "ab.f"
    for a, b in zip(r1[:-1], r1[1:], strict=True):
        assert b in net.successors(a)
        np.testing.assert_allclose(net.roads[a].point(net.roads[a].length), net.roads[b].point(0.0), atol=1e-9)
    with pytest.raises(ValueError, match="n_roads"):
        net.random_route("ab.f", 0, np.random.default_rng(0))


def test_random_route_choice_is_uniform(net):
    """After ab.f the walk picks bc.f or be.f with probability 1/2 each: count inside the 99.9 % binomial interval."""
    rng = np.random.default_rng(11)
    n = 2000
    hits = sum(net.random_route("ab.f", 2, rng)[1] == "bc.f" for _ in range(n))
    lo, hi = binom.interval(0.999, n, 0.5)
    assert lo <= hits <= hi


def test_nearest_prefers_own_carriageway(net):
    rid, s, lat = net.nearest(np.array([50.0, -2.0]))  # right of A->B
    assert (rid, s, lat) == ("ab.f", pytest.approx(50.0), pytest.approx(-2.0))
    rid, s, lat = net.nearest(np.array([50.0, 2.0]))  # right of B->A
    assert (rid, s, lat) == ("ab.r", pytest.approx(50.0), pytest.approx(-2.0))
    rid, s, lat = net.nearest(np.array([160.0, 1.0]))
    assert rid == "be.r" and s == pytest.approx(40.0) and lat == pytest.approx(-1.0)


def test_nearest_matches_brute_force(net):
    rng = np.random.default_rng(5)
    for p in rng.uniform([-20, -20], [220, 130], size=(200, 2)):
        rid, s, _ = net.nearest(p)
        d = np.hypot(*(net.roads[rid].point(s) - p))
        best = min(np.hypot(*(r.point(r.project(p)[0]) - p)) for r in net.roads.values())
        assert d == pytest.approx(best, abs=1e-6)


def test_lengths(net):
    diag = net.roads["ac.f"].length
    assert 141.42 < diag < 160.0  # bowed through (40, 60)
    streets = 100 + 100 + np.hypot(100, 10) + 110 + 100
    assert net.street_length() == pytest.approx(streets + diag)
    assert net.total_length() == pytest.approx(2 * streets + diag)


@pytest.mark.parametrize("spec,match", [
    ({"nodes": {"A": [0, 0]}, "streets": [{"id": "s", "nodes": ["A", "X"]}]}, "node 'X' is not in nodes"),
    ({"nodes": {"A": [0, 0], "B": [1, 0]}, "streets": [{"id": "s", "nodes": ["A", "B"]}] * 2}, "used twice"),
    ({"nodes": {"A": [0, 0], "B": [1, 0]}, "streets": [{"id": "s", "nodes": ["A"]}]}, "nodes must be"),
    ({"nodes": {"A": [0, 0], "B": [1, 0]}, "streets": [{"nodes": ["A", "B"]}]}, "missing id"),
    ({"nodes": {"A": [0, 0], "B": [0, 0]}, "streets": [{"id": "s", "nodes": ["A", "B"]}]}, "street 's'.*coincide"),
    ({"nodes": {"A": [0, "x"]}, "streets": []}, "could not convert|node 'A'"),
])
def test_from_spec_errors(spec, match):
    with pytest.raises(ValueError, match=match):
        RoadNetwork.from_spec(spec)


def test_network_checks_geometry_against_nodes():
    road = Road(id="r", vertices=[[0, 0], [10, 0]], start_node="A", end_node="B")
    with pytest.raises(ValueError, match="is 1.000 m from"):
        RoadNetwork([road], {"A": [0, 0], "B": [11, 0]})
    with pytest.raises(ValueError, match="twin 'q' is not in the network"):
        RoadNetwork([Road(id="r", vertices=[[0, 0], [10, 0]], start_node="A", end_node="B", twin="q")],
                    {"A": [0, 0], "B": [10, 0]})
