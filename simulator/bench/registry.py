"""Registry of benchmarks run by ``skytrack bench``.

A benchmark is a function that measures something and returns one or more :class:`BenchRecord`. Modules in
``simulator/bench/`` named ``bench_*.py`` register theirs with the :func:`benchmark` decorator; the CLI imports
them all, filters by name (``--only REGEX``) and prints a table or JSON.

Rules for benchmark authors (the machines are shared and noisy):

- repeat the measurement and report the **median** (``median_of``);
- where a target is absolute, also measure a reference in the same run and report the ratio when it helps;
- keep one benchmark under about a minute of wall time.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass
from typing import Literal

__all__ = ["BenchRecord", "Benchmark", "benchmark", "registered", "median_of", "time_call"]


@dataclass(frozen=True, kw_only=True)
class BenchRecord:
    """One measured figure.

    Attributes
    ----------
    name : str
        What it measures, e.g. ``quad_physics_rtf_10uav`` or ``nmpc_solve_ms_p95``.
    value : float
        The measured figure (a median over repeats unless the name says otherwise).
    unit : str
        Unit of ``value`` (``"x"`` for real-time factors, ``"ms"``, ``"us"``, ``"fps"``, ``"s"``).
    target : float | None
        The figure an issue asks for, if any.
    better : {"higher", "lower"}
        Which direction is better.
    """

    name: str
    value: float
    unit: str
    target: float | None = None
    better: Literal["higher", "lower"] = "higher"

    @property
    def meets_target(self) -> bool | None:
        if self.target is None:
            return None
        return self.value >= self.target if self.better == "higher" else self.value <= self.target

    def to_json(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Benchmark:
    """A registered benchmark function and the record names it produces."""

    name: str
    fn: Callable[[], Iterable[BenchRecord]]
    produces: tuple[str, ...]


_REGISTRY: dict[str, Benchmark] = {}


def benchmark(name: str, produces: Iterable[str] = ()) -> Callable:
    """Register ``fn`` as benchmark ``name``; ``produces`` lists the record names (used by ``--only``)."""

    def deco(fn: Callable[[], Iterable[BenchRecord]]) -> Callable[[], Iterable[BenchRecord]]:
        if name in _REGISTRY:
            raise ValueError(f"benchmark {name!r} registered twice")
        _REGISTRY[name] = Benchmark(name, fn, tuple(produces) or (name,))
        return fn

    return deco


def registered() -> dict[str, Benchmark]:
    """All registered benchmarks, by name (import the ``bench_*`` modules first)."""
    return dict(_REGISTRY)


def time_call(fn: Callable[[], object]) -> float:
    """Wall time of one call of ``fn`` in seconds (``time.perf_counter``)."""
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def median_of(fn: Callable[[], float], repeats: int = 5) -> float:
    """Median of ``repeats`` values returned by ``fn`` (e.g. ``lambda: time_call(step)``)."""
    return float(statistics.median(fn() for _ in range(repeats)))
