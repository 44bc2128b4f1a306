"""Marks a replay derives from the world file rather than from the record: each radar's field of regard on the
ground, and the radio links between UAVs with their delivery probability.

Field of regard: the ground outline of what a radar may see — the ring of its maximum range for an all-round
radar, or the sector between its azimuth limits (measured in the world, heading or body frame as the world file
says) out to the maximum range; radars without a maximum range get no outline.

Radio links: for a ``rayleigh`` channel, every UAV pair's delivery probability at the frame's positions from the
same :class:`~autonomy.sensing.channel.Channel` model the run used (distance law, hard range, blockage by the
recorded buildings — exact prism intersection through :class:`~autonomy.sensing.fake_scene.FakeScene`, since the
replay's buildings are visual only — and scheduled outages), so a link that a building cuts is drawn at 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from worlds.schema import FovSpec, World

__all__ = ["RegardOutline", "radar_regards", "RadioLinks", "probability_rgb"]

_ARC_POINTS = 48


@dataclass(frozen=True)
class RegardOutline:
    """One radar's field of regard: UAV index, frame, azimuth limits (rad) and maximum range (m)."""

    uav: int
    frame: str
    azimuth_limits: tuple[float, float]
    max_range: float

    def outline(self, p_W: np.ndarray, yaw: float, z: float) -> np.ndarray:
        """Closed ground outline (K, 3) m around the UAV at ``p_W`` with yaw ``yaw`` rad, at height ``z``."""
        c = np.asarray(p_W[:2], dtype=float)
        if self.frame == "all_round":
            a = np.linspace(0.0, 2.0 * np.pi, 2 * _ARC_POINTS, endpoint=False)
            xy = c + self.max_range * np.c_[np.cos(a), np.sin(a)]
        else:
            lo, hi = self.azimuth_limits
            span = (hi - lo) % (2.0 * np.pi) or 2.0 * np.pi
            base = lo + (0.0 if self.frame == "world" else yaw)
            a = base + np.linspace(0.0, span, _ARC_POINTS)
            xy = np.vstack([c, c + self.max_range * np.c_[np.cos(a), np.sin(a)]])
        return np.c_[xy, np.full(len(xy), z)]


def radar_regards(world: World) -> list[RegardOutline]:
    """The fields of regard of every radar with a maximum range in the (validated) world."""
    out = []
    for u, spec in enumerate(world.uavs):
        for s in spec.sensors:
            if s.type != "radar" or s.max_range is None:
                continue
            fov = s.fov if s.fov is not None else FovSpec()
            lim = fov.azimuth_limits_deg
            out.append(RegardOutline(uav=u, frame=str(fov.frame),
                                     azimuth_limits=(float(np.deg2rad(lim[0])), float(np.deg2rad(lim[1]))),
                                     max_range=float(s.max_range)))
    return out


def probability_rgb(pr: float) -> tuple[float, float, float]:
    """Colour of a delivery probability in [0, 1]: red at 0, yellow at 0.5, green at 1 (RGB in [0, 1])."""
    pr = float(np.clip(pr, 0.0, 1.0))
    return (min(1.0, 2.0 * (1.0 - pr)), min(1.0, 2.0 * pr), 0.1)


class RadioLinks:
    """Delivery probabilities between the UAVs of a replayed run.

    Parameters
    ----------
    world : World
        The run's validated world.
    buildings : sequence of Building
        The run's buildings (``geometry.npz``); they block links when the world says so.
    """

    def __init__(self, world: World, buildings: Any) -> None:
        from autonomy.sensing.fake_scene import FakeScene
        from simulator.factories import build_channel

        self.names = [u.id for u in world.uavs]
        self.physics_hz = world.sim.physics_hz
        self.channel = build_channel(world, self.physics_hz, np.random.default_rng(0), FakeScene(buildings))

    @property
    def active(self) -> bool:
        """False for a perfect channel (nothing to draw)."""
        return self.channel is not None and len(self.names) > 1

    def at(self, t: float, positions: list[np.ndarray]) -> list[tuple[np.ndarray, np.ndarray, float]]:
        """``(p_a, p_b, Pr)`` of every UAV pair at time ``t`` s from their positions (3,) m, in UAV order."""
        if not self.active:
            return []
        tick = int(round(t * self.physics_hz))
        P = self.channel.link_matrix(self.names, dict(zip(self.names, positions, strict=True)), tick)
        n = len(self.names)
        return [(positions[i], positions[j], float(P[i, j])) for i in range(n) for j in range(i + 1, n)]

    def series(self, t: np.ndarray, positions: np.ndarray) -> np.ndarray:
        """(T, pairs) delivery probabilities of every UAV pair (in :meth:`at`'s order) at times ``t`` (T,) s from the
        positions (T, N, 3) m, in one batch (:meth:`~autonomy.sensing.channel.Channel.link_matrices`)."""
        n = len(self.names)
        if not self.active:
            return np.zeros((len(t), n * (n - 1) // 2))
        ticks = [int(round(float(tk) * self.physics_hz)) for tk in t]
        P = self.channel.link_matrices(self.names, positions, ticks)
        iu, ju = np.triu_indices(n, k=1)
        return P[:, iu, ju]
