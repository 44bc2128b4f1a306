"""The radio links of a recorded run, per record tick: every UAV pair's delivery probability from the run's own channel
model (:func:`simulator.factories.build_channel`, as a replay draws them in :mod:`simulator.render.world_marks`).

A channel that buildings block asks its scene whether each link has line of sight: the replay's
:class:`~autonomy.sensing.fake_scene.FakeScene`, which runs its prism test on the buildings whose footprint's bounding
box a link's overlaps (on a city map of 1,500 buildings, a few per link).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from autonomy.sensing.fake_scene import FakeScene
from worlds.geometry import Building

__all__ = ["link_samples"]


def link_samples(world: Any, buildings: Sequence[Building], names: list[str], t: np.ndarray,
                 positions: np.ndarray) -> list[tuple[float, list[tuple[str, str, np.ndarray, np.ndarray, float]]]]:
    """``(t, [(uav a, uav b, p_a, p_b, Pr), ...])`` per sample of the UAVs' positions (N, U, 3) m at times (N,) s;
    ``[]`` for a perfect radio, fewer than two UAVs, or UAVs that are not the world's."""
    from simulator.factories import build_channel

    if len(names) < 2 or [u.id for u in world.uavs] != list(names):
        return []
    hz = world.sim.physics_hz
    channel = build_channel(world, hz, np.random.default_rng(0), FakeScene(buildings))
    if channel is None:
        return []
    pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))]
    Ps = channel.link_matrices(list(names), positions, [int(round(float(tk) * hz)) for tk in t])
    return [(float(tk), [(names[i], names[j], pos[i], pos[j], float(P[i, j])) for i, j in pairs])
            for tk, pos, P in zip(t, positions, Ps, strict=True)]
