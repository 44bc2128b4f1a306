"""Radio channel: Rayleigh erasure law, blockage, range, outages, latency, MST routing, message accounting."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from autonomy.sensing.channel import (
    Channel,
    ChannelConfig,
    LinkOutage,
    chain_routes,
    minimum_spanning_tree_routes,
    outage_holds,
    scheduled_links,
    scheduled_row,
)
from autonomy.sensing.fake_scene import FakeScene
from autonomy.sensing.messages import EstimateMessage, InformationMessage, Message
from worlds.geometry import Building

TICK_HZ = 240.0


def msg(sender: str, receiver: str | None, t: float = 0.0) -> Message:
    return Message(sender=sender, receiver=receiver, t_sent=t)


def test_table1_constants_give_cubic_kilometre_law():
    cfg = ChannelConfig()
    assert cfg.fading_scale == pytest.approx(1e-9, rel=1e-12)
    d = np.array([216.0, 472.0, 885.0, 1000.0, 1320.0])
    np.testing.assert_allclose(cfg.delivery_probability(d), np.exp(-((d / 1000.0) ** 3)), rtol=1e-12)
    np.testing.assert_allclose(cfg.delivery_probability(d), [0.99, 0.90, 0.50, 0.368, 0.10], atol=0.005)


@pytest.mark.parametrize("distance", [300.0, 700.0, 1000.0, 1300.0])
def test_empirical_delivery_rate_in_binomial_band(distance):
    ch = Channel(ChannelConfig(block_by_buildings=False), TICK_HZ, np.random.default_rng(int(distance)))
    pos = {"a": np.array([0.0, 0.0, 100.0]), "b": np.array([distance, 0.0, 100.0])}
    n = 2000
    ok = sum(ch.send(msg("a", "b"), pos, tick)["b"] for tick in range(n))
    pr = float(np.exp(-((distance / 1000.0) ** 3)))
    lo, hi = stats.binom.interval(0.99, n, pr)
    assert lo <= ok <= hi
    s = ch.stats
    assert (s.sent, s.lost, s.in_flight, s.delivered) == (n, n - ok, ok, 0)
    got = ch.receive("b", n)
    assert len(got) == ok and ch.stats.delivered == ok and ch.stats.in_flight == 0
    assert ch.stats.by_link[("a", "b")] == (n, ok, n - ok)


def test_building_between_uavs_cuts_link():
    scene = FakeScene([Building.cuboid((100.0, 0.0), (20.0, 20.0, 80.0))])
    ch = Channel(ChannelConfig(), TICK_HZ, np.random.default_rng(0), scene=scene)
    pos = {"a": np.array([0.0, 0.0, 50.0]), "b": np.array([200.0, 0.0, 50.0]), "c": np.array([100.0, 100.0, 50.0])}
    P = ch.link_matrix(("a", "b", "c"), pos, 0)
    assert P[0, 1] == 0.0 and P[1, 0] == 0.0
    assert P[0, 2] == pytest.approx(np.exp(-((np.hypot(100, 100) / 1000) ** 3)))
    assert not any(ch.send(msg("a", "b"), pos, t)["b"] for t in range(200))
    above = dict(pos, b=np.array([200.0, 0.0, 120.0]), a=np.array([0.0, 0.0, 120.0]))  # both fly over the roof
    assert ch.link_matrix(("a", "b"), above, 0)[0, 1] > 0.99


def test_hard_range_and_scheduled_outage():
    cfg = ChannelConfig(
        block_by_buildings=False,
        max_range=500.0,
        outages=(LinkOutage(node_a="u1", node_b="u3", start_s=150 * 0.5, end_s=200 * 0.5),),
    )
    ch = Channel(cfg, 2.0, np.random.default_rng(0))  # 2 Hz ticks: tick k is the paper's step k
    pos = {"u1": np.array([0.0, 0.0, 100.0]), "u3": np.array([10.0, 0.0, 110.0]), "u4": np.array([600.0, 0, 100])}
    nodes = ("u1", "u3", "u4")
    assert ch.link_matrix(nodes, pos, 149)[0, 1] > 0.99
    assert ch.link_matrix(nodes, pos, 150)[0, 1] == 0.0 and ch.link_matrix(nodes, pos, 150)[1, 0] == 0.0
    assert ch.link_matrix(nodes, pos, 199)[0, 1] == 0.0
    assert ch.link_matrix(nodes, pos, 200)[0, 1] > 0.99
    assert ch.link_matrix(nodes, pos, 0)[0, 2] == 0.0  # 600 m > max_range


def test_latency_in_ticks_and_broadcast():
    ch = Channel(ChannelConfig(block_by_buildings=False, latency_s=0.05), TICK_HZ, np.random.default_rng(0))
    assert ch.latency_ticks == 12
    pos = {n: np.array([10.0 * k, 0.0, 50.0]) for k, n in enumerate(("a", "b", "c"))}
    m = EstimateMessage(sender="a", receiver=None, t_sent=1.0, target_id=0, x=np.zeros(6), P=np.eye(6), t_estimate=1.0)
    sent = ch.send(m, pos, 240)
    assert sent == {"b": True, "c": True}
    assert ch.receive("b", 251) == []
    (env,) = ch.receive("b", 252)
    assert (
        env.message is m and env.tick_arrival == 252 and env.t_arrival == pytest.approx(1.05) and env.path == ("a", "b")
    )
    assert len(ch.receive("c", 1000)) == 1 and ch.stats.delivered == 2
    with pytest.raises(ValueError, match="latency_s"):
        Channel(ChannelConfig(block_by_buildings=False, latency_s=0.001), TICK_HZ, np.random.default_rng(0))


def test_minimum_spanning_tree_hand_example():
    # B at the origin; A1 400 m east; A2 800 m east; A3 600 m north of A1.
    # -ln Pr = (d/1 km)^3: B-A1 0.064, A1-A2 0.064, A1-A3 0.216, B-A3 (721 m) 0.375, A2-A3 (721 m) 0.375, B-A2 0.512
    pos = {"B": [0.0, 0, 0], "A1": [400.0, 0, 0], "A2": [800.0, 0, 0], "A3": [400.0, 600.0, 0]}
    ch = Channel(ChannelConfig(block_by_buildings=False), 1.0, np.random.default_rng(0))
    tree = ch.routing_tree(tuple(pos), {k: np.array(v) for k, v in pos.items()}, "B", 0)
    assert tree.parent == {"B": None, "A1": "B", "A2": "A1", "A3": "A1"}
    assert tree.path("A3") == ("A3", "A1", "B") and tree.hops("A2") == 2 and tree.hops("B") == 0
    assert tree.route_probability("A1") == pytest.approx(np.exp(-0.064))
    assert tree.route_probability("A2") == pytest.approx(np.exp(-0.128))
    assert tree.route_probability("A3") == pytest.approx(np.exp(-0.064 - 0.216))


def test_routed_delivery_rate_is_product_of_hops_and_cut_off_node_loses():
    P = np.array([[1.0, 0.9, 0.0, 0.0], [0.9, 1.0, 0.6, 0.0], [0.0, 0.6, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    tree = minimum_spanning_tree_routes(("B", "A1", "A2", "A3"), P, "B")
    assert tree.path("A3") == () and tree.route_probability("A3") == 0.0
    ch = Channel(ChannelConfig(block_by_buildings=False, latency_s=1.0), 1.0, np.random.default_rng(3))
    n = 3000
    ok = sum(
        ch.send_routed(
            InformationMessage(
                sender="A2",
                receiver="B",
                t_sent=0.0,
                target_id=0,
                info_vector=np.zeros(4),
                info_matrix=np.eye(4),
                t_info=0.0,
            ),
            tree,
            0,
        )
        for _ in range(n)
    )
    lo, hi = stats.binom.interval(0.99, n, 0.54)
    assert lo <= ok <= hi
    assert not ch.send_routed(msg("A3", "B"), tree, 0)
    arrived = ch.receive("B", 2)
    assert len(arrived) == ok and all(e.path == ("A2", "A1", "B") and e.tick_arrival == 2 for e in arrived)
    s = ch.stats
    assert s.sent == n + 1 and s.delivered == ok and s.lost == n + 1 - ok and s.in_flight == 0


def test_config_validation_names_field():
    with pytest.raises(ValueError, match="alpha"):
        ChannelConfig(alpha=0.0)
    with pytest.raises(ValueError, match="end_s"):
        LinkOutage(node_a="a", node_b="b", start_s=2.0, end_s=1.0)
    with pytest.raises(ValueError, match="scene"):
        Channel(ChannelConfig(), 240.0, np.random.default_rng(0))


def test_fixed_topology_cuts_unlisted_pairs_and_sampled_links_follow_the_probabilities():
    ring = (("a", "c"), ("c", "b"), ("b", "d"), ("d", "a"))
    cfg = ChannelConfig(block_by_buildings=False, links=ring,
                        outages=(LinkOutage(node_a="a", node_b="c", start_s=1.0, end_s=2.0),))
    ch = Channel(cfg, TICK_HZ, np.random.default_rng(7))
    nodes = ("a", "b", "c", "d")
    pos = {n: np.array([100.0 * k, 0.0, 50.0]) for k, n in enumerate(nodes)}
    P = ch.link_matrix(nodes, pos, 0)
    assert P[0, 1] == 0.0 and P[2, 3] == 0.0 and P[0, 2] > 0.99  # a-b and c-d are not links
    assert not ch.send(msg("a", "b"), pos, 0)["b"]
    n = 2000
    up = np.array([ch.sample_links(nodes, pos, tick) for tick in range(n)])
    assert (up == up.transpose(0, 2, 1)).all() and not up[:, [0, 1, 2, 3], [0, 1, 2, 3]].any()
    assert not up[:, 0, 1].any() and not up[:, 2, 3].any()
    lo, hi = stats.binom.interval(0.99, n, P[0, 3])
    assert lo <= up[:, 0, 3].sum() <= hi
    assert not ch.sample_links(nodes, pos, int(1.5 * TICK_HZ))[0, 2]  # the outage holds a-c down
    with pytest.raises(ValueError, match="links"):
        ChannelConfig(links=(("a", "a"),))


def test_scheduled_links_are_the_topology_less_the_outages_and_the_radio_applies_them():
    nodes = ("a", "b", "c")
    outages = [("c", "a", 10, 20)]
    assert outage_holds("a", "c", outages, 10) and not outage_holds("a", "c", outages, 20)
    assert not outage_holds("a", "b", outages, 15)
    every = scheduled_links(nodes, None, outages, 0)
    assert (every == ~np.eye(3, dtype=bool)).all()
    up = scheduled_links(nodes, [("a", "c"), ("b", "c")], outages, 15)
    assert up.tolist() == [[False, False, False], [False, False, True], [False, True, False]]
    ch = Channel(ChannelConfig(block_by_buildings=False, links=(("a", "c"), ("b", "c")),
                               outages=(LinkOutage(node_a="c", node_b="a", start_s=10 / TICK_HZ, end_s=20 / TICK_HZ),)),
                 TICK_HZ, np.random.default_rng(0))
    pos = {n: np.array([10.0 * k, 0.0, 50.0]) for k, n in enumerate(nodes)}
    for tick in (0, 15, 20):
        P = ch.link_matrix(nodes, pos, tick)
        off = ~np.eye(3, dtype=bool)
        assert ((P[off] > 0) == scheduled_links(nodes, ch.config.links, [("c", "a", 10, 20)], tick)[off]).all()


def test_messages_between_the_same_nodes_at_one_tick_cast_their_rays_once():
    class Counting(FakeScene):
        rays = 0

        def line_of_sight(self, a, b):
            Counting.rays += len(a)
            return super().line_of_sight(a, b)

    scene = Counting([Building.cuboid((100.0, 0.0), (20.0, 20.0, 80.0))])
    ch = Channel(ChannelConfig(), TICK_HZ, np.random.default_rng(0), scene=scene)
    pos = {"a": np.array([0.0, 0.0, 50.0]), "b": np.array([200.0, 0.0, 50.0]), "c": np.array([100.0, 100.0, 50.0])}
    ch.send(msg("a", None), pos, 3)
    ch.send(msg("a", None), pos, 3)  # the state and the estimate of one step
    assert Counting.rays == 2
    got = ch.send(msg("a", None), pos, 3)
    assert got["b"] is False  # behind the building, whichever message
    ch.send(msg("a", None), pos, 4)  # the next tick
    moved = {**pos, "c": np.array([100.0, 120.0, 50.0])}
    ch.send(msg("a", None), moved, 4)  # another position
    ch.send(msg("b", None), pos, 4)  # another sender
    assert Counting.rays == 8


def test_a_senders_scheduled_row_is_its_row_of_the_link_matrix():
    rng = np.random.default_rng(4)
    names = [f"u{k}" for k in range(7)]
    for _ in range(50):
        links = None if rng.random() < 0.3 else [tuple(rng.choice(names, 2, replace=False)) for _ in range(9)]
        outages = [(*rng.choice(names, 2, replace=False), int(rng.integers(0, 10)), int(rng.integers(5, 20)))
                   for _ in range(4)]
        sender, *targets = rng.permutation(names).tolist()
        tick = int(rng.integers(0, 20))
        want = scheduled_links((sender, *targets), links, outages, tick)[0, 1:]
        assert scheduled_row(sender, targets, links, outages, tick).tolist() == want.tolist()


def test_the_fixed_chain_relays_through_the_node_before_whatever_the_links():
    from autonomy.guidance.infoplan.routing import chain_route_probabilities

    rng = np.random.default_rng(12)
    channel = Channel(ChannelConfig(block_by_buildings=False), TICK_HZ, rng)
    nodes = ("base", "a", "b", "c")
    for _ in range(20):
        pos = {n: np.r_[rng.uniform(-900, 900, size=2), 50.0] for n in nodes}
        tree = channel.routing_tree(nodes, pos, "base", 0, chain=True)
        assert [tree.parent[n] for n in nodes] == [None, "base", "a", "b"]
        assert tree.path("c") == ("c", "b", "a", "base") and tree.hops("c") == 3
        P = channel.link_matrix(nodes, pos, 0)
        np.testing.assert_allclose([tree.route_probability(n) for n in nodes], chain_route_probabilities(P[None])[0],
                                   rtol=1e-12)
    mst = channel.routing_tree(nodes, pos, "base", 0)
    assert mst.parent == minimum_spanning_tree_routes(nodes, P, "base").parent
    with pytest.raises(ValueError, match="root"):
        chain_routes(nodes, P, "hub")


def test_link_matrices_are_the_link_matrix_of_each_tick():
    rng = np.random.default_rng(12)
    buildings = [Building.cuboid(rng.uniform(-300, 300, 2), (*rng.uniform(10, 40, 2), rng.uniform(20, 90)))
                 for _ in range(40)]
    cfg = ChannelConfig(links=(("a", "b"), ("b", "c"), ("c", "d"), ("a", "d"), ("a", "c")),
                        outages=(LinkOutage(node_a="c", node_b="a", start_s=0.2, end_s=0.6),))
    ch = Channel(cfg, TICK_HZ, np.random.default_rng(0), scene=FakeScene(buildings))
    nodes = ("a", "b", "c", "d")
    ticks = [int(k * 0.05 * TICK_HZ) for k in range(20)]
    pos = np.c_[rng.uniform(-350, 350, (20 * 4, 2)), rng.uniform(30, 100, 20 * 4)].reshape(20, 4, 3)
    batch = ch.link_matrices(nodes, pos, ticks)
    one = np.array([ch.link_matrix(nodes, dict(zip(nodes, p, strict=True)), tk) for p, tk in zip(pos, ticks,
                                                                                                 strict=True)])
    np.testing.assert_array_equal(batch, one)
    blocked = one[:, [0, 0, 1, 2], [1, 3, 2, 3]] == 0.0
    assert blocked.any() and not blocked.all()  # buildings cut some scheduled links, not all
    assert (one[4:12, 0, 2] == 0).all() and (one[:4, 0, 2] > 0).any()  # the outage of a-c from 0.2 to 0.6 s
