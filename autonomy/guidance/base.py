"""The guidance role: one base class and the statistics every guidance law keeps.

A guidance law turns the UAV's own state, the (fused) target estimate and what teammates share into a set-point
(:mod:`interfaces.setpoints`) for the quadrotor's controllers.
"""

from __future__ import annotations

import abc
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from interfaces.setpoints import Setpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState

__all__ = ["Guidance", "GuidanceStats"]


@dataclass(kw_only=True)
class GuidanceStats:
    """Counters and solve times of one guidance instance, read by the recorder and the metrics.

    Attributes
    ----------
    calls : int
        Number of ``command`` calls.
    solves : int
        Number of optimiser calls (0 for closed-form laws).
    failures : int
        Optimiser calls that failed (solver status not successful, exception, non-finite output, injected failure).
    fallbacks_shifted : int
        Commands taken from the previous plan shifted in time after a failure.
    fallbacks_vector_field : int
        Commands taken from the vector-field fallback after a failure.
    inexact : int
        Solves stopped by the iteration cap whose iterate was feasible and was used.
    overruns : int
        Solves whose wall time exceeded the configured budget.
    retries : int
        Failed fast solves retried with a more robust solver (a retry that succeeds is not a failure).
    solve_times_s : list[float]
        Wall time of every optimiser call (s).
    solve_cpu_times_s : list[float]
        CPU (thread) time of every optimiser call (s): robust to other load on a shared machine.
    iterations : list[int]
        Optimiser iterations of every call (-1 if unknown).
    last_status : str
        Status string of the last optimiser call.
    """

    calls: int = 0
    solves: int = 0
    failures: int = 0
    fallbacks_shifted: int = 0
    fallbacks_vector_field: int = 0
    inexact: int = 0
    overruns: int = 0
    retries: int = 0
    solve_times_s: list[float] = field(default_factory=list)
    solve_cpu_times_s: list[float] = field(default_factory=list)
    iterations: list[int] = field(default_factory=list)
    last_status: str = ""

    @property
    def fallbacks(self) -> int:
        """Total number of fallback commands."""
        return self.fallbacks_shifted + self.fallbacks_vector_field

    def solve_time_percentile(self, q: float) -> float:
        """Percentile ``q`` in [0, 100] of the solve times (s); NaN before any solve."""
        if not self.solve_times_s:
            return float("nan")
        return float(np.percentile(self.solve_times_s, q))

    def summary(self) -> dict[str, float]:
        """Flat dictionary for metrics files: counts and solve-time p50 / p95 / max (ms)."""
        return {
            "calls": self.calls,
            "solves": self.solves,
            "failures": self.failures,
            "fallbacks_shifted": self.fallbacks_shifted,
            "fallbacks_vector_field": self.fallbacks_vector_field,
            "inexact": self.inexact,
            "overruns": self.overruns,
            "retries": self.retries,
            "solve_ms_p50": 1e3 * self.solve_time_percentile(50),
            "solve_ms_p95": 1e3 * self.solve_time_percentile(95),
            "solve_ms_max": 1e3 * (max(self.solve_times_s) if self.solve_times_s else float("nan")),
        }


class Guidance(abc.ABC):
    """Base class of guidance laws: one main method, :meth:`command`."""

    def __init__(self) -> None:
        self.stats = GuidanceStats()

    @abc.abstractmethod
    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> Setpoint:
        """Set-point for the UAV at time ``t`` (s) from its own state, the target estimate and the teammates."""

    def planned_path(self) -> np.ndarray | None:
        """(K, 2) horizontal positions (m) the UAV plans to pass at the law's step after the last command, or ``None``.

        Shared with teammates as ``TeammateState.plan_p_W`` by laws that plan over a horizon.
        """
        return None

    def plan_step_s(self) -> float:
        """Time between the points of :meth:`planned_path` (s): the law's step; 1 s for laws without one."""
        return 1.0
