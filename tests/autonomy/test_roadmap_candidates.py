"""RoadMap.candidates: the one-pass box test keeps exactly the roads (and their order) of a test per road."""

import numpy as np
import pytest

from autonomy.estimation.road.constraint import RoadConstraintParams
from autonomy.estimation.road.roadmap import RoadCandidate, RoadMap
from worlds.town import TownConfig, generate_town


def _per_road(rmap: RoadMap, p: np.ndarray, max_excess: float) -> list[RoadCandidate]:
    """The reference: every road's box tested on its own, in the network's order."""
    out = []
    for rid, road in rmap.network.roads.items():
        lo, hi = road.samples.min(axis=0), road.samples.max(axis=0)
        margin = max_excess + road.lanes * road.lane_width
        if np.any(p < lo - margin) or np.any(p > hi + margin):
            continue
        s, lat, ex = rmap.excess(road, p)
        if ex <= max_excess:
            out.append(RoadCandidate(rid, s, lat, ex))
    return out


@pytest.fixture(scope="module")
def town_map() -> RoadMap:
    town = generate_town(TownConfig(extent=(400.0, 400.0), block_size=100.0), np.random.default_rng(2))
    return RoadMap(town.network, RoadConstraintParams())


def test_candidates_equal_the_per_road_test(town_map):
    rng = np.random.default_rng(7)
    found = 0
    for p in rng.uniform(-250.0, 250.0, size=(200, 2)):
        for max_excess in (0.0, 5.0, 30.0):
            got = town_map.candidates(p, max_excess)
            assert got == _per_road(town_map, p, max_excess)
            found += len(got)
    assert found > 100  # the points do meet roads


def test_a_point_far_from_every_road_has_no_candidate(town_map):
    assert town_map.candidates(np.array([5000.0, 5000.0]), 10.0) == []
