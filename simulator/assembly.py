"""A world, built: the names a run needs, gathered from where they live.

- :mod:`simulator.tick`: :class:`Assembly` and the tick;
- :mod:`simulator.prepare`: :func:`prepare` and :func:`build_assembly`;
- :mod:`simulator.comms`, :mod:`simulator.recording`, :mod:`simulator.truth`, :mod:`simulator.streams`: the parts.
"""

from simulator.prepare import Prepared, build_assembly, prepare
from simulator.slots import AgentSlot, SensorSlot
from simulator.tick import WALL_PHASES, Assembly
from worlds.build import build_geometry

__all__ = ["WALL_PHASES", "AgentSlot", "Assembly", "Prepared", "SensorSlot", "build_assembly", "build_geometry",
           "prepare"]
