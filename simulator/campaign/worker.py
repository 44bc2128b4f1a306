"""What a campaign worker process does: run whole runs through :func:`simulator.api.run` and report them.

Workers are started with the ``spawn`` context (a PyBullet client must never be forked mid-use), run one run at a
time, and never write the campaign journal — they return a :class:`RunReport` to the parent.
"""

from __future__ import annotations

import os
import signal
import threading
import time
import traceback
from collections.abc import Mapping
from typing import Any

from simulator.campaign.config import RunReport, RunTask

__all__ = ["flatten_metrics", "init_worker", "run_one"]

PARENT_POLL_S = 0.5
"""How often a worker checks that the campaign process still exists, s."""


def flatten_metrics(metrics: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested ``metrics.json`` → one level with dotted keys.

    ``{"targets": {"car1": {"uav1": {"position_rmse_m": 2.3}}}}`` → ``{"targets.car1.uav1.position_rmse_m": 2.3}``.
    Lists are kept as values.
    """
    out: dict[str, Any] = {}
    for key, value in metrics.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(flatten_metrics(value, prefix=name + "."))
        else:
            out[name] = value
    return out


def _raise_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def _watch_parent(parent_pid: int) -> None:
    while True:
        if os.getppid() != parent_pid:  # the campaign process died: stop writing into its directory
            os._exit(70)
        time.sleep(PARENT_POLL_S)


def init_worker(parent_pid: int) -> None:
    """Worker-process initialiser: SIGTERM ends the current run as ``interrupted`` (its record is flushed), and the
    worker exits within :data:`PARENT_POLL_S` of its campaign process dying (so a killed campaign leaves no writer)."""
    signal.signal(signal.SIGTERM, _raise_interrupt)
    threading.Thread(target=_watch_parent, args=(parent_pid,), daemon=True, name="campaign-parent-watch").start()


def run_one(task: RunTask) -> RunReport:
    """Run ``task`` in this process and report it; an exception outside the run loop is reported as ``error``."""
    from simulator.api import run

    t0 = time.perf_counter()
    try:
        result = run(task.world, duration=task.duration_s, seed=task.seed, overrides=task.overrides,
                     out_dir=task.out_dir, progress=False, plots=False)
        status, error, metrics = result.status, result.error, flatten_metrics(result.metrics)
    except Exception as exc:  # e.g. a bad plugin failing at build time: the campaign records it and goes on
        status, error, metrics = "error", f"{type(exc).__name__}: {exc}", {}
        os.makedirs(task.out_dir, exist_ok=True)
        with open(os.path.join(task.out_dir, "campaign_error.txt"), "w", encoding="utf-8") as f:
            f.write(traceback.format_exc())
    return RunReport(index=task.index, seed=task.seed, status=status, error=error,
                     wall_time_s=time.perf_counter() - t0, metrics=metrics, run_dir="")
