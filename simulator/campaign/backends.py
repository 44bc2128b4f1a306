"""Where a campaign's runs execute: a local pool of spawned worker processes, or a Ray cluster.

Both backends take the runs still to do and hand each :class:`RunReport` to a callback in the parent as soon as the run
ends, so the parent journals it at once. A run whose worker dies is reported as ``error`` and the campaign goes on:

- locally, a dying worker breaks the whole ``ProcessPoolExecutor`` and fails every run in flight with
  ``BrokenProcessPool``. At most ``workers`` runs are in flight, so those are the suspects: a lone suspect is the
  culprit; several are re-run one at a time in a one-worker pool, where the culprit breaks it again and the others
  complete. Then a fresh pool takes the remaining runs.
- on Ray, tasks are submitted with ``max_retries=0``; a task error or a crashed worker comes back as a ``RayError``.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from simulator.campaign.config import CampaignError, RunFunction, RunReport, RunTask
from simulator.campaign.worker import init_worker

__all__ = ["Backend", "LocalPoolBackend", "RayBackend", "import_ray"]

Callback = Callable[[RunReport], None]

WORKER_DIED = "WorkerDied: the worker process died while running this run (BrokenProcessPool)"


def _error_report(task: RunTask, error: str) -> RunReport:
    return RunReport(index=task.index, seed=task.seed, status="error", error=error, wall_time_s=0.0)


class Backend:
    """Runs tasks somewhere and reports each one to the parent as it ends."""

    def execute(self, tasks: Sequence[RunTask], run_fn: RunFunction, on_report: Callback) -> None:
        """Run every task with ``run_fn`` and call ``on_report`` once per task, in the parent, in completion order."""
        raise NotImplementedError


class LocalPoolBackend(Backend):
    """``ProcessPoolExecutor`` over ``workers`` processes started with the ``spawn`` context.

    Parameters
    ----------
    workers : int
        Worker processes (>= 1).
    """

    def __init__(self, workers: int) -> None:
        if workers < 1:
            raise ValueError(f"workers must be >= 1, got {workers}")
        self.workers = workers
        self._context = multiprocessing.get_context("spawn")

    def _pool(self, workers: int) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(max_workers=workers, mp_context=self._context, initializer=init_worker,
                                   initargs=(os.getpid(),))

    def execute(self, tasks: Sequence[RunTask], run_fn: RunFunction, on_report: Callback) -> None:
        queue = deque(tasks)
        while queue:
            suspects = self._run_pool(queue, run_fn, on_report, self.workers)
            if len(suspects) == 1:
                on_report(_error_report(suspects[0], WORKER_DIED))
            else:
                for task in suspects:  # one at a time: only the culprit breaks its pool again
                    if self._run_pool(deque([task]), run_fn, on_report, 1):
                        on_report(_error_report(task, WORKER_DIED))

    def _run_pool(self, queue: deque[RunTask], run_fn: RunFunction, on_report: Callback,
                  workers: int) -> list[RunTask]:
        """Run tasks from ``queue`` until it is empty or the pool breaks; return the tasks in flight at a break."""
        pool = self._pool(min(workers, len(queue)))
        in_flight: dict[Future, RunTask] = {}
        broken: list[RunTask | None] = []
        reported = 0
        try:
            while queue or in_flight:
                while queue and len(in_flight) < workers and not broken:
                    try:
                        fut = pool.submit(run_fn, queue[0])
                    except BrokenProcessPool:  # broke since the last wait: the runs in flight tell which
                        broken.append(None)
                        break
                    in_flight[fut] = queue.popleft()
                if not in_flight:
                    break
                done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
                for fut in done:
                    task = in_flight.pop(fut)
                    try:
                        on_report(fut.result())
                        reported += 1
                    except BrokenProcessPool:
                        broken.append(task)
                    except Exception as exc:  # run_fn raised, or its result could not be pickled
                        on_report(_error_report(task, f"{type(exc).__name__}: {exc}"))
                if broken and not in_flight:
                    break
        except BaseException:
            for proc in list((getattr(pool, "_processes", None) or {}).values()):
                proc.terminate()  # SIGTERM: a run ends as "interrupted" with its record flushed
            pool.shutdown(wait=True, cancel_futures=True)
            raise
        pool.shutdown(wait=True, cancel_futures=True)
        suspects = sorted((t for t in broken if t is not None), key=lambda t: t.index)
        if broken and not suspects and not reported:
            raise CampaignError("the local worker pool broke before running anything (do worker processes start?)")
        return suspects


def import_ray():  # noqa: ANN201 - the ray module
    """Import Ray, or raise :class:`CampaignError` saying how to install it."""
    try:
        import ray
    except ImportError:
        raise CampaignError("--ray needs Ray, which is not installed: pip install 'skytrack[cluster]' "
                            "(the 'cluster' extra, ray>=2.9)") from None
    return ray


class RayBackend(Backend):
    """Runs tasks as Ray tasks (one CPU each, no retries).

    Parameters
    ----------
    address : str
        ``"auto"``: connect to a running local Ray instance, or start a local one if there is none; otherwise a Ray
        address (``ray://host:10001`` or ``host:6379``) passed to ``ray.init``.
    max_in_flight : int | None
        Most tasks submitted at once (None = all; Ray queues them by available CPUs).
    num_cpus : int | None
        CPUs of a local Ray instance this backend starts (None = all cores).
    """

    def __init__(self, address: str, max_in_flight: int | None = None, num_cpus: int | None = None) -> None:
        self.address = address
        self.max_in_flight = max_in_flight
        self.num_cpus = num_cpus
        self.ray = import_ray()

    def _init(self) -> bool:
        """Connect; True when this call started Ray (and so must shut it down)."""
        ray = self.ray
        if ray.is_initialized():
            return False
        quiet = {"logging_level": logging.WARNING, "log_to_driver": False}
        if self.address == "auto":
            try:
                ray.init(address="auto", **quiet)
            except ConnectionError:  # no running instance: start a local one
                ray.init(num_cpus=self.num_cpus, include_dashboard=False, **quiet)
        else:
            ray.init(address=self.address, **quiet)
        return True

    def execute(self, tasks: Sequence[RunTask], run_fn: RunFunction, on_report: Callback) -> None:
        ray = self.ray
        started = self._init()
        remote = ray.remote(num_cpus=1, max_retries=0)(run_fn)
        queue = deque(tasks)
        limit = self.max_in_flight or len(queue)
        in_flight: dict = {}
        try:
            while queue or in_flight:
                while queue and len(in_flight) < limit:
                    task = queue.popleft()
                    in_flight[remote.remote(task)] = task
                ready, _ = ray.wait(list(in_flight), num_returns=1)
                for ref in ready:
                    task = in_flight.pop(ref)
                    try:
                        report = ray.get(ref)
                    except ray.exceptions.RayError as exc:  # task raised, worker crashed, node lost
                        report = _error_report(task, f"{type(exc).__name__}: {str(exc).strip().splitlines()[-1]}")
                    on_report(report)
        except BaseException:
            for ref in in_flight:
                ray.cancel(ref, force=True)
            raise
        finally:
            if started:
                ray.shutdown()
