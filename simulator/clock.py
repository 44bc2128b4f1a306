"""The multi-rate clock: an integer tick counter at the physics rate; every other rate is a whole divisor of it."""

from __future__ import annotations

from dataclasses import dataclass

from worlds.rates import divisor

__all__ = ["Clock", "MAX_DURATION_S"]

MAX_DURATION_S = 1e9
"""Longest run (s, about 32 years): its tick count stays an exact integer in a float at any physics rate up to
9 MHz."""


@dataclass(frozen=True, kw_only=True)
class Clock:
    """Integer physics ticks.

    Attributes
    ----------
    physics_hz : int
        Physics steps per second (Hz). Time at tick ``k`` is ``k / physics_hz`` s, computed, never accumulated.
    """

    physics_hz: int

    def __post_init__(self) -> None:
        if not isinstance(self.physics_hz, int) or self.physics_hz <= 0:
            raise ValueError(f"Clock.physics_hz must be a positive integer (Hz), got {self.physics_hz!r}")

    @property
    def dt(self) -> float:
        """Physics step, s."""
        return 1.0 / self.physics_hz

    def time(self, tick: int) -> float:
        """Simulated time at ``tick``, s."""
        return tick / self.physics_hz

    def ticks(self, seconds: float) -> int:
        """Whole ticks in ``seconds`` (rounded to the nearest tick)."""
        return int(round(seconds * self.physics_hz))

    def divisor(self, rate_hz: float, what: str = "rate_hz") -> int:
        """Ticks between events at ``rate_hz``; raises ``ValueError`` naming ``what`` if it does not divide the physics
        rate (the one rule of :func:`worlds.rates.divisor`, by which the loader checks every rate of a world)."""
        return divisor(rate_hz, self.physics_hz, what)
