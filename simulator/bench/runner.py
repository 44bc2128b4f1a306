"""Discover and run the registered benchmarks (``simulator/bench/bench_*.py``)."""

from __future__ import annotations

import importlib
import pkgutil
import re
import traceback

from simulator.bench import registry
from simulator.bench.registry import BenchRecord

__all__ = ["discover", "run_benchmarks"]


def discover() -> dict[str, registry.Benchmark]:
    """Import every ``simulator.bench.bench_*`` module and return the registry."""
    import simulator.bench as pkg

    for mod in pkgutil.iter_modules(pkg.__path__):
        if mod.name.startswith("bench_"):
            importlib.import_module(f"simulator.bench.{mod.name}")
    return registry.registered()


def run_benchmarks(only: re.Pattern | None = None,
                   progress: bool = True) -> tuple[list[BenchRecord], list[tuple[str, str]]]:
    """Run the benchmarks whose name or record names match ``only``; returns (records, failures)."""
    records: list[BenchRecord] = []
    failures: list[tuple[str, str]] = []
    for name, bench in discover().items():
        if only is not None and not (only.search(name) or any(only.search(n) for n in bench.produces)):
            continue
        if progress:
            print(f"running {name} ...", flush=True)
        try:
            recs = list(bench.fn())
        except Exception as exc:  # a failing benchmark is reported, the others still run
            failures.append((name, f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}"))
            continue
        if only is not None and not only.search(name):
            recs = [r for r in recs if only.search(r.name)]
        records.extend(recs)
    return records, failures
