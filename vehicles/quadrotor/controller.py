"""Base class of the flight-control cascade: each stage turns one set-point type into the next."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Generic, TypeVar

from vehicles.quadrotor.state import FleetState

__all__ = ["Controller"]

SetpointIn = TypeVar("SetpointIn")
SetpointOut = TypeVar("SetpointOut")


class Controller(ABC, Generic[SetpointIn, SetpointOut]):
    """One stage of the cascade, vectorised over the N UAVs of a fleet."""

    @abstractmethod
    def update(self, setpoint: SetpointIn, state: FleetState) -> SetpointOut:
        """Turn ``setpoint`` into the next stage's set-point given the current ``state``."""

    def reset(self) -> None:  # noqa: B027 - stateless stages need no reset
        """Clear internal state (integrators); stateless stages do nothing."""
