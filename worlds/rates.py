"""Rates as whole divisors of the physics rate: the one rule every multi-rate component is checked by.

The world loader (:mod:`worlds.checks`), the simulator's clock and the vehicles' fleets (quadrotor outer loops, car
drivers) all turn a rate in Hz into ticks between events with :func:`divisor` (or ask :func:`rate_divisor` whether
one exists), so that a rate is accepted or refused by one rule in one place.
"""

from __future__ import annotations

import math
from fractions import Fraction

__all__ = ["divisor", "divisors_text", "rate_divisor", "whole_ticks"]

MAX_DENOMINATOR = 10**6
"""A rate in Hz is read as the nearest fraction with a denominator up to this (0.5 Hz, 2.4 Hz, 1/3 Hz ...)."""

TICK_TOLERANCE = 1e-6
"""How far (in ticks) a duration may lie from a whole number of ticks and still count as whole (float rounding)."""


def rate_divisor(rate_hz: float, physics_hz: int) -> int | None:
    """Ticks between events of a component at ``rate_hz``, or None where ``rate_hz`` does not divide ``physics_hz``.

    Parameters
    ----------
    rate_hz : float
        The component's rate, Hz; finite and > 0 (anything else gives None).
    physics_hz : int
        The physics rate, Hz (> 0).

    Returns
    -------
    int | None
        ``physics_hz / rate_hz`` when that is a whole number >= 1, else None.
    """
    if isinstance(rate_hz, bool) or not isinstance(rate_hz, int | float) or not math.isfinite(rate_hz) \
            or rate_hz <= 0:
        return None
    rate = Fraction(rate_hz).limit_denominator(MAX_DENOMINATOR)
    if rate == 0:  # below 1e-6 Hz: no period of whole ticks worth the name
        return None
    ratio = Fraction(physics_hz) / rate
    if ratio.denominator != 1 or ratio.numerator < 1:
        return None
    return int(ratio.numerator)


def divisors_text(physics_hz: int, count: int = 12) -> str:
    """The largest rates (Hz) that divide ``physics_hz``, as text for an error message: ``"240, 120, 80, ..."``.

    The divisors come in pairs ``(d, physics_hz // d)`` with ``d <= sqrt(physics_hz)``, so the work grows with the
    square root of ``physics_hz`` (a prime near 1e9 takes milliseconds, not a loop to 1e9)."""
    if physics_hz < 1:
        return ""
    small = [d for d in range(1, math.isqrt(physics_hz) + 1) if physics_hz % d == 0]
    rates = sorted({physics_hz // d for d in small} | set(small), reverse=True)
    return ", ".join(str(r) for r in rates[:count])


def divisor(rate_hz: float, physics_hz: int, what: str = "rate_hz") -> int:
    """Ticks between events at ``rate_hz``.

    Raises
    ------
    ValueError
        Naming ``what`` (e.g. ``DriverConfig.rate_hz``) when ``rate_hz`` does not divide ``physics_hz`` into whole
        ticks.
    """
    d = rate_divisor(rate_hz, physics_hz)
    if d is None:
        raise ValueError(f"{what} = {rate_hz} Hz does not divide physics_hz = {physics_hz} Hz into whole ticks "
                         f"(e.g. {divisors_text(physics_hz)})")
    return d


def whole_ticks(seconds: float, physics_hz: int) -> int | None:
    """``seconds`` as a whole number of physics ticks, or None where it is not one (within :data:`TICK_TOLERANCE`)."""
    if not math.isfinite(seconds):
        return None
    ticks = seconds * physics_hz
    n = round(ticks)
    return n if abs(ticks - n) <= TICK_TOLERANCE else None
