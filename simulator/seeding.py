"""Run randomness: one ``numpy.random.SeedSequence`` per run, one child ``Generator`` per named component.

Children are derived from the component's *name* (``"radar/uav1/0"``), not from the order components are built in, so
adding a component never changes the random streams of the others. Same world + same seed => identical streams.
"""

from __future__ import annotations

import zlib

import numpy as np

__all__ = ["RunSeeds"]


class RunSeeds:
    """Named random streams of one run.

    Parameters
    ----------
    seed : int
        The run's seed (``sim.seed`` or ``--seed``), >= 0.
    """

    def __init__(self, seed: int) -> None:
        if seed < 0:
            raise ValueError(f"seed must be >= 0, got {seed}")
        self.seed = int(seed)
        self._issued: set[str] = set()

    def sequence(self, name: str) -> np.random.SeedSequence:
        """The SeedSequence of component ``name`` (a name may be issued once per run)."""
        if name in self._issued:
            raise ValueError(f"random stream {name!r} requested twice; give each component its own name")
        self._issued.add(name)
        key = tuple(zlib.crc32(part.encode()) for part in name.split("/"))
        return np.random.SeedSequence(self.seed, spawn_key=key)

    def generator(self, name: str) -> np.random.Generator:
        """A fresh ``Generator`` (PCG64) for component ``name``."""
        return np.random.Generator(np.random.PCG64(self.sequence(name)))
