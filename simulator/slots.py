"""What the tick steps for each UAV: its sensors and its agent, each with the rate divisor it runs at."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from autonomy.agent import Agent
from autonomy.sensing.measurement import Sensor

__all__ = ["AgentSlot", "SensorSlot"]


@dataclass
class SensorSlot:
    """One sensor of UAV ``uav``: it measures at the ticks that ``divisor`` divides, drawing from ``rng``."""

    uav: int
    sensor: Sensor
    divisor: int
    rng: np.random.Generator
    name: str


@dataclass
class AgentSlot:
    """The agent of UAV ``uav``: it steps at the ticks that ``divisor`` divides (a :class:`~autonomy.team.base.
    TeamMember`)."""

    uav: int
    agent: Agent
    divisor: int
