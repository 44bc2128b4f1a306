"""The radio links of a recorded run, per record tick: every UAV pair's delivery probability from the run's own channel
model (:func:`simulator.factories.build_channel`, as a replay draws them in :mod:`simulator.render.world_marks`).

A channel that buildings block asks its scene whether each link has line of sight. The replay's
:class:`~autonomy.sensing.fake_scene.FakeScene` tests every segment against every building prism; on a city map
(1,500 buildings) that costs about a second per record tick, so an export would take longer than the run. The scene
here gives the same answers from the same prism test, run only on the buildings whose footprint's bounding box
overlaps a segment's: a segment can only cross a prism whose box it overlaps.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from autonomy.sensing.fake_scene import convex_prisms, segment_prism_interval
from worlds.geometry import Building

__all__ = ["BoxFilteredScene", "link_samples"]


class BoxFilteredScene:
    """Line of sight among ``buildings``, with the answers of ``FakeScene(buildings).line_of_sight`` (module
    docstring)."""

    def __init__(self, buildings: Sequence[Building]) -> None:
        self.buildings = tuple(buildings)
        self._prisms = [convex_prisms(b) for b in self.buildings]
        fp = [np.asarray(b.footprint, dtype=float) for b in self.buildings]
        self._lo = np.array([f.min(axis=0) for f in fp]).reshape(-1, 2)
        self._hi = np.array([f.max(axis=0) for f in fp]).reshape(-1, 2)

    def line_of_sight(self, from_W: np.ndarray, to_W: np.ndarray) -> np.ndarray:
        """(N,) bool: whether each segment ``from_W[i]`` -> ``to_W[i]`` (N, 3) m misses every building."""
        a = np.atleast_2d(np.asarray(from_W, dtype=float))
        b = np.atleast_2d(np.asarray(to_W, dtype=float))
        clear = np.ones(len(a), dtype=bool)
        if not self.buildings or not len(a):
            return clear
        seg_lo, seg_hi = np.minimum(a, b)[:, :2], np.maximum(a, b)[:, :2]
        overlap = np.all((self._lo[:, None] <= seg_hi[None]) & (seg_lo[None] <= self._hi[:, None]), axis=2)
        for k in np.flatnonzero(overlap.any(axis=1)):
            rows = np.flatnonzero(overlap[k])
            for pr in self._prisms[k]:
                t_in, t_out = segment_prism_interval(a[rows], b[rows], pr)
                clear[rows] &= ~(t_in < t_out)
        return clear


def link_samples(world: Any, buildings: Sequence[Building], names: list[str], t: np.ndarray,
                 positions: np.ndarray) -> list[tuple[float, list[tuple[str, str, np.ndarray, np.ndarray, float]]]]:
    """``(t, [(uav a, uav b, p_a, p_b, Pr), ...])`` per sample of the UAVs' positions (N, U, 3) m at times (N,) s;
    ``[]`` for a perfect radio, fewer than two UAVs, or UAVs that are not the world's."""
    from simulator.factories import build_channel

    if len(names) < 2 or [u.id for u in world.uavs] != list(names):
        return []
    hz = world.sim.physics_hz
    channel = build_channel(world, hz, np.random.default_rng(0), BoxFilteredScene(buildings))
    if channel is None:
        return []
    pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))]
    out = []
    for tk, pos in zip(t, positions, strict=True):
        P = channel.link_matrix(list(names), dict(zip(names, pos, strict=True)), int(round(float(tk) * hz)))
        out.append((float(tk), [(names[i], names[j], pos[i], pos[j], float(P[i, j])) for i, j in pairs]))
    return out
