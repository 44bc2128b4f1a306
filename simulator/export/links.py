"""The radio links of a recorded run, per record tick: every UAV pair's delivery probability from the run's own channel
model (:func:`simulator.factories.build_channel`, as a replay draws them in :mod:`simulator.render.world_marks`).

The replay's :class:`~simulator.render.world_marks.RadioLinks` computes them; a channel that buildings block asks
its :class:`~autonomy.sensing.fake_scene.FakeScene`, which runs its prism test on the buildings whose footprint's
bounding box a link's overlaps (on a city map of 1,500 buildings, a few per link).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from worlds.geometry import Building

__all__ = ["link_samples"]


def link_samples(world: Any, buildings: Sequence[Building], names: list[str], t: np.ndarray,
                 positions: np.ndarray) -> list[tuple[float, list[tuple[str, str, np.ndarray, np.ndarray, float]]]]:
    """``(t, [(uav a, uav b, p_a, p_b, Pr), ...])`` per sample of the UAVs' positions (N, U, 3) m at times (N,) s;
    ``[]`` for a perfect radio, fewer than two UAVs, or UAVs that are not the world's."""
    from simulator.render.world_marks import RadioLinks

    if len(names) < 2 or [u.id for u in world.uavs] != list(names):
        return []
    links = RadioLinks(world, buildings)
    if not links.active:
        return []
    pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))]
    pr = links.series(t, positions)  # the pairs in this order
    return [(float(tk), [(names[i], names[j], pos[i], pos[j], float(p[k])) for k, (i, j) in enumerate(pairs)])
            for tk, pos, p in zip(t, positions, pr, strict=True)]
