"""The fake scene's line of sight: its bounding-box pre-filter gives the answers of the prism test on every building."""

from __future__ import annotations

import numpy as np

from autonomy.sensing.fake_scene import FakeScene, convex_prisms, segment_prism_interval
from worlds.geometry import Building


def _every_prism(buildings, a, b):
    clear = np.ones(len(a), dtype=bool)
    for building in buildings:
        for pr in convex_prisms(building):
            t_in, t_out = segment_prism_interval(a, b, pr)
            clear &= ~(t_in < t_out)
    return clear


def test_line_of_sight_answers_as_the_prism_test_on_every_building():
    rng = np.random.default_rng(3)
    buildings = [Building.cuboid(rng.uniform(-200, 200, 2), (*rng.uniform(5, 40, 2), rng.uniform(5, 60)),
                                 yaw=rng.uniform(0, np.pi)) for _ in range(60)]
    buildings.append(Building(footprint=np.array([[0.0, 0.0], [30.0, 0.0], [30.0, 30.0], [15.0, 10.0], [0.0, 30.0]]),
                              height=20.0))  # not convex: several prisms
    a = np.c_[rng.uniform(-250, 250, (400, 2)), rng.uniform(1, 70, 400)]
    b = np.c_[rng.uniform(-250, 250, (400, 2)), rng.uniform(1, 70, 400)]
    b[:40, :2] = a[:40, :2] + rng.normal(0, 2, (40, 2))  # short and vertical segments too
    b[40:50, :2] = a[40:50, :2]
    want = _every_prism(buildings, a, b)
    assert 50 < int((~want).sum()) < 350  # both answers occur
    scene = FakeScene(buildings)
    assert np.array_equal(scene.line_of_sight(a, b), want)
    assert np.array_equal(scene.line_of_sight(a[7], b[7]), want[7:8])  # one segment
    assert FakeScene().line_of_sight(a, b).all() and scene.line_of_sight(a[:0], b[:0]).shape == (0,)
