"""Run a Monte Carlo campaign: validate once, resume what is recorded, run the rest, aggregate.

>>> from simulator.campaign.runner import CampaignConfig, run_campaign
>>> cfg = CampaignConfig(world="demo", runs=20, out_dir="runs/demo-mc", duration_s=30, workers=2)
>>> result = run_campaign(cfg)  # doctest: +SKIP
>>> result.summary.get("targets.car1.uav1.position_rmse_m").mean                                   # doctest: +SKIP

Campaign directory::

    campaign.json        world, resolved overrides, seed, duration, N (a resume must match them)
    campaign.jsonl       one line per finished run: index, seed, status, error, wall time, flat metrics, and the
                         size and SHA-256 of each file of its run directory (checked on resume: a damaged run is
                         run again)
    runs/run-00042/      the run directory of run 42 (see simulator.record)
    summary.json, summary.md
                         per-metric mean, standard deviation, 95 % confidence interval of the mean, n
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass
from pathlib import Path

from simulator.campaign.aggregate import CampaignSummary, summarize, write_summary
from simulator.campaign.backends import Backend, LocalPoolBackend, RayBackend
from simulator.campaign.config import (FAILED, CampaignConfig, CampaignParams, RunReport, RunTask, run_dir_name,
                                       run_seed)
from simulator.campaign.journal import CampaignJournal
from simulator.campaign.worker import run_one
from worlds.loader import load_world

__all__ = ["CampaignConfig", "CampaignResult", "run_campaign"]


@dataclass(frozen=True, kw_only=True)
class CampaignResult:
    """A campaign after :func:`run_campaign`.

    Attributes
    ----------
    out_dir : Path
        The campaign directory.
    params : CampaignParams
        World, overrides, seed, duration and N, as stored in ``campaign.json``.
    reports : tuple of RunReport
        Every recorded run (this call's and earlier ones'), by index.
    summary : CampaignSummary
        Aggregates over the completed runs (also in ``summary.json`` / ``summary.md``).
    ran : int
        Runs executed by this call (the others were recorded by an earlier, interrupted call).
    redone : dict[int, str]
        Runs journaled by an earlier call whose stored files were damaged, so this call ran them again: what was
        wrong with each, by index.
    """

    out_dir: Path
    params: CampaignParams
    reports: tuple[RunReport, ...]
    summary: CampaignSummary
    ran: int
    redone: dict[int, str] = dataclasses.field(default_factory=dict)

    @property
    def missing(self) -> list[int]:
        """Indices not recorded (a run interrupted from outside); they run on the next resume."""
        done = {r.index for r in self.reports}
        return [i for i in range(self.params.runs) if i not in done]

    @property
    def all_failed(self) -> bool:
        """True when no run completed."""
        return self.summary.completed == 0

    @property
    def seeds(self) -> dict[int, int]:
        """Run seed by index."""
        return {r.index: r.seed for r in self.reports}


def _backend(config: CampaignConfig, pending: int) -> Backend:
    if config.ray_address is not None:
        return RayBackend(config.ray_address, max_in_flight=config.workers, num_cpus=config.workers)
    workers = config.workers or os.cpu_count() or 1
    return LocalPoolBackend(max(1, min(workers, pending)))


def run_campaign(config: CampaignConfig) -> CampaignResult:
    """Run (or resume) the campaign ``config`` describes and aggregate it.

    Raises
    ------
    worlds.errors.WorldError
        The world or an override is invalid (checked once, before any run).
    CampaignError
        ``out_dir`` holds a campaign with other parameters, or Ray was asked for but is not installed.
    KeyboardInterrupt
        Interrupted (Ctrl-C / SIGTERM): finished runs are journaled; the next call resumes.
    """
    loaded = load_world(config.world, list(config.overrides))
    params = CampaignParams.resolve(config, loaded)
    run_fn = config.run_fn or run_one
    backend = _backend(config, config.runs)  # before touching the directory: a missing Ray fails here
    with CampaignJournal(config.out_dir, params) as journal:
        redone = journal.drop_damaged()
        pending = journal.pending()
        out = journal.out_dir.resolve()
        tasks = []
        for index in pending:
            journal.clear_run_dir(index)  # what a killed attempt left behind
            tasks.append(RunTask(index=index, seed=run_seed(params.seed, index), world=params.world_path,
                                 overrides=tuple(params.overrides), duration_s=params.duration_s,
                                 out_dir=str(out / run_dir_name(index))))
        ran = _execute(config, backend, tasks, journal, run_fn, loaded.name)
        reports = tuple(journal.ordered())
    summary = summarize(reports)
    write_summary(summary, config.out_dir, title=f"{loaded.name}, {params.runs} runs, seed {params.seed}")
    return CampaignResult(out_dir=config.out_dir, params=params, reports=reports, summary=summary, ran=ran,
                          redone=redone)


def _execute(config: CampaignConfig, backend: Backend, tasks: list[RunTask], journal: CampaignJournal,
             run_fn, name: str) -> int:  # noqa: ANN001 - RunFunction
    """Run ``tasks`` on ``backend``, journaling each report as it arrives; returns how many reported."""
    if not tasks:
        return 0
    from tqdm import tqdm

    counts = {"done": len(journal.finished()), "failed": sum(r.status in FAILED for r in journal.reports.values())}
    bar = tqdm(total=journal.params.runs, initial=counts["done"], unit="run", desc=f"campaign {name}",
               disable=not config.progress, dynamic_ncols=True)
    bar.set_postfix(failed=counts["failed"])
    ran = 0

    def on_report(report: RunReport) -> None:
        nonlocal ran
        ran += 1
        report = dataclasses.replace(report, run_dir=run_dir_name(report.index))
        journal.record(report)
        if report.finished:
            counts["done"] += 1
            counts["failed"] += report.status in FAILED
            bar.update(1)
            bar.set_postfix(failed=counts["failed"])

    try:
        backend.execute(tasks, run_fn, on_report)
    finally:
        bar.close()
    return ran
