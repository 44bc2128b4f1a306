"""Which junctions a map's traffic signals control: the rule of worlds.roads.signals on a hand-made network."""

from __future__ import annotations

import numpy as np
import pytest

from worlds.roads.network import RoadNetwork
from worlds.roads.signals import JOIN_M, junctions, signalised_junctions


def _network() -> RoadNetwork:
    """A four-way junction C (100 m two-way legs to N, E, S, W), a T junction T on the east leg's far side (legs to
    E, TN, TS), and a bend B (two neighbours) on the way from TN."""
    nodes = {"C": [0, 0], "N": [0, 100], "E": [100, 0], "S": [0, -100], "W": [-100, 0], "T": [200, 0],
             "TN": [200, 100], "TS": [200, -100], "B": [260, 100]}
    streets = [{"id": f"c{k}", "nodes": ["C", k]} for k in ("N", "E", "S", "W")]
    streets += [{"id": "et", "nodes": ["E", "T"]}, {"id": "tn", "nodes": ["T", "TN"]},
                {"id": "ts", "nodes": ["T", "TS"]}, {"id": "nb", "nodes": ["TN", "B"]}]
    return RoadNetwork.from_spec({"nodes": nodes, "streets": streets})


NET = _network()


def test_junctions_are_nodes_with_three_neighbours_or_more() -> None:
    assert set(junctions(NET)) == {"C", "T"}  # E and TN have two neighbours each (bends), N, S, W and B one
    assert junctions(NET)["C"] == {"N", "E", "S", "W"}


def test_a_signal_on_a_junction_lights_it_and_one_on_a_bend_or_dead_end_does_not() -> None:
    assert signalised_junctions(NET, np.array([[0.5, -0.5]])) == ("C",)
    assert signalised_junctions(NET, np.array([[100.0, 0.0], [0.0, 100.0], [260.0, 100.0]])) == ()
    assert signalised_junctions(NET, np.zeros((0, 2))) == ()


@pytest.mark.parametrize(("legs", "lit"), [(("N",), False), (("N", "E"), True), (("N", "S", "W"), True)])
def test_signals_on_half_of_the_approaches_light_the_junction(legs, lit) -> None:
    """Signals 10 m before C on some of its four legs: at least two of four light it, one (a crossing) does not."""
    unit = {"N": (0, 1), "E": (1, 0), "S": (0, -1), "W": (-1, 0)}
    pts = np.array([[10.0 * unit[k][0], 10.0 * unit[k][1]] for k in legs])
    assert signalised_junctions(NET, pts) == (("C",) if lit else ())


def test_a_t_junction_needs_two_of_its_three_approaches() -> None:
    one = np.array([[200.0, 15.0]])  # on the leg from TN, 15 m before T
    assert signalised_junctions(NET, one) == ()
    assert signalised_junctions(NET, np.vstack([one, [[185.0, 0.0]]])) == ("T",)  # and on the leg from E


def test_signals_too_far_along_or_off_the_road_do_not_count() -> None:
    far = np.array([[0.0, JOIN_M + 5.0], [JOIN_M + 5.0, 0.0]])  # 30 m before C on two legs
    assert signalised_junctions(NET, far) == ()
    assert signalised_junctions(NET, far, join_m=JOIN_M + 6.0) == ("C",)
    off = np.array([[5.0, 10.0], [10.0, -5.0]])  # 10 m before C, 5 m beside the centre-lines of N and E
    assert signalised_junctions(NET, off) == ()
    assert signalised_junctions(NET, off, on_road_m=5.5) == ("C",)


def test_bad_arguments_are_refused() -> None:
    with pytest.raises(ValueError, match="join_m must be finite and > 0 m, got 0"):
        signalised_junctions(NET, np.zeros((1, 2)), join_m=0)
    with pytest.raises(ValueError, match="on_road_m must be finite and > 0 m, got nan"):
        signalised_junctions(NET, np.zeros((1, 2)), on_road_m=float("nan"))
    with pytest.raises(ValueError, match="signal positions must be finite"):
        signalised_junctions(NET, np.array([[np.inf, 0.0]]))
