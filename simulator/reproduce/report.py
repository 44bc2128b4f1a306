"""What a paper's reproduction produces, and how it becomes ``report.md``.

A reproduction module ``simulator/reproduce/paper_NNN.py`` defines ``reproduce(ctx: ReproContext) -> PaperReport``. It
runs its experiments (campaigns of worlds, or the autonomy's closed loops), writes its figures into ``ctx.out_dir`` and
returns the tables (the paper's numbers beside ours, with confidence intervals and run counts), the figures and one
:class:`Finding` per claim of the paper. :func:`write_paper_report` turns that into ``ctx.out_dir / "report.md"``.

Every number in a report comes from the run of the command that wrote it; nothing is copied in by hand except the
paper's own figures, which are quoted as the paper prints them.
"""

from __future__ import annotations

import concurrent.futures as cf
import math
import os
import sys
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal, TypeVar

import numpy as np
from scipy import stats

from simulator.record import atomic_write_text
from simulator.reproduce.seeds import EVAL_SEED, PAPER_RUNS, TUNING_SEEDS

if TYPE_CHECKING:
    from simulator.campaign.runner import CampaignConfig, CampaignResult
    from simulator.reproduce.rules import Judgement

T = TypeVar("T")
R = TypeVar("R")

__all__ = ["Verdict", "Finding", "Table", "Figure", "PaperReport", "ReproContext", "MeanCI", "mean_ci",
           "write_paper_report", "paper_markdown",
           "verdicts_record", "EVAL_SEED", "TUNING_SEEDS", "PAPER_RUNS", "VERDICTS"]

Verdict = Literal["reproduced", "not reproduced", "inconclusive", "not comparable"]
VERDICTS: tuple[str, ...] = ("reproduced", "not reproduced", "inconclusive", "not comparable")
"""*inconclusive*: the 95 % interval straddles the claim's line (the runs cannot decide); *not comparable*: the claim
cannot be judged in our set-up (the reason is given)."""



@dataclass(frozen=True, kw_only=True)
class MeanCI:
    """Mean of ``n`` values and the half-width of its 95 % Student-t confidence interval (None for n < 2)."""

    mean: float
    half: float | None
    n: int

    def text(self, digits: int = 3) -> str:
        """``mean ± half`` with ``digits`` significant digits (``mean`` alone when the interval is undefined)."""
        if not math.isfinite(self.mean):
            return "–"
        m = f"{self.mean:.{digits}g}"
        return m if self.half is None else f"{m} ± {self.half:.2g}"


def mean_ci(values: Sequence[float] | np.ndarray, confidence: float = 0.95) -> MeanCI:
    """Mean and Student-t confidence half-width of the finite entries of ``values``.

    Equal values (a deterministic quantity over seeds) have a half-width of exactly 0: their floating-point mean can
    differ from them in the last bit, and the interval would otherwise print as ``± 8.4e-17``."""
    x = np.asarray(values, dtype=float).ravel()
    x = x[np.isfinite(x)]
    if x.size == 0:
        return MeanCI(mean=float("nan"), half=None, n=0)
    half = None
    if x.size >= 2 and np.all(x == x[0]):
        return MeanCI(mean=float(x[0]), half=0.0, n=int(x.size))
    if x.size >= 2:
        half = float(stats.t.ppf(0.5 + confidence / 2.0, df=x.size - 1) * x.std(ddof=1) / math.sqrt(x.size))
    return MeanCI(mean=float(x.mean()), half=half, n=int(x.size))


@dataclass(frozen=True, kw_only=True)
class Finding:
    """One claim of the paper and what our runs say of it.

    Attributes
    ----------
    claim : str
        The paper's claim, in one sentence.
    verdict : {"reproduced", "not reproduced", "not comparable"}
        Decided by the reproduction code from the measured numbers, never set by hand.
    why : str
        The measured numbers behind the verdict, and for "not comparable" the reason.
    rule : str
        The rule that decided the verdict, in words (as strict as the claim).
    ours : str
        Our figure the rule judged.
    paper : str
        The paper's figure or wording for the claim ("" when the paper gives no number).
    runs : int
        Runs behind the verdict.
    paper_faithful : bool
        True when judged on the paper's own configuration; False when on ours with our additions.
    paper_claim : bool
        True for a claim the paper makes; False for our extension (listed apart, never in the paper's tallies).
    """

    claim: str
    verdict: Verdict
    why: str
    rule: str = ""
    ours: str = ""
    paper: str = ""
    runs: int = 0
    paper_faithful: bool = True
    paper_claim: bool = True

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            raise ValueError(f"Finding.verdict must be one of {VERDICTS}, got {self.verdict!r}")

    @classmethod
    def judged(cls, claim: str, judgement: "Judgement", *, paper: str, why: str = "", paper_faithful: bool = True,
               paper_claim: bool = True) -> "Finding":
        """A finding whose verdict, rule, figure and run count come from a rule of :mod:`simulator.reproduce.rules`."""
        return cls(claim=claim, verdict=judgement.verdict, why=why or judgement.ours, rule=judgement.rule,
                   ours=judgement.ours, paper=paper, runs=judgement.runs, paper_faithful=paper_faithful,
                   paper_claim=paper_claim)

    def record(self) -> dict:
        """The finding as one entry of ``verdicts.json``."""
        return {"claim": self.claim, "verdict": self.verdict, "rule": self.rule, "ours": self.ours,
                "paper": self.paper, "runs": self.runs, "paper_faithful": self.paper_faithful,
                "paper_claim": self.paper_claim, "why": self.why}


@dataclass(frozen=True, kw_only=True)
class Table:
    """A table of the paper next to ours: already formatted cells, one header row."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    note: str = ""

    def __post_init__(self) -> None:
        for r in self.rows:
            if len(r) != len(self.columns):
                raise ValueError(f"table {self.title!r}: row {r!r} has {len(r)} cells for {len(self.columns)} columns")

    def markdown(self) -> str:
        esc = lambda c: str(c).replace("|", "\\|")  # noqa: E731
        lines = ["| " + " | ".join(esc(c) for c in self.columns) + " |",
                 "|" + "---|" * len(self.columns)]
        lines += ["| " + " | ".join(esc(c) for c in r) + " |" for r in self.rows]
        return "\n".join(lines)


@dataclass(frozen=True, kw_only=True)
class Figure:
    """A PNG written into the paper's output folder (``path`` relative to it) and its caption."""

    path: str
    caption: str


@dataclass(frozen=True, kw_only=True)
class ReproContext:
    """Where and how much to reproduce.

    Attributes
    ----------
    out_dir : Path
        This paper's output folder (created by the caller).
    runs : int
        Monte Carlo runs per configuration, >= 1.
    workers : int | None
        Worker processes for campaigns (None: all cores).
    seed : int
        Base seed of the evaluation runs (:meth:`run_seeds`); :data:`EVAL_SEED` by default.
    progress : bool
        Show progress bars.
    quick : bool
        Shortened experiments (fewer steps) for smoke tests; the report says so.
    """

    out_dir: Path
    runs: int
    workers: int | None = None
    seed: int = EVAL_SEED
    progress: bool = True
    quick: bool = False
    reused: dict[str, tuple[int, int]] = field(default_factory=dict, compare=False)
    """Per store of :meth:`map`: (jobs taken from it, jobs asked), filled as the reproduction runs."""
    codes: Counter = field(default_factory=Counter, compare=False)
    """Completed physics runs of :meth:`campaign` by the source version that made them
    (:func:`simulator.provenance.code_versions`): a campaign resumed or extended after the code changed holds runs
    of several versions, and the report says so."""

    def __post_init__(self) -> None:
        if self.runs < 1:
            raise ValueError(f"ReproContext.runs must be >= 1, got {self.runs}")

    def run_seeds(self, runs: int | None = None) -> list[int]:
        """Seeds of runs ``0 … runs − 1`` (default ``self.runs``), the same for every variant of every experiment
        (common random numbers: a variant never enters a run's seed, so differences between variants are paired):
        ``SeedSequence(seed, spawn_key=(r,))``, as a campaign of base ``seed`` seeds its run ``r``."""
        from simulator.campaign.config import run_seed

        return [run_seed(self.seed, r) for r in range(self.runs if runs is None else runs)]

    def seeds_text(self) -> str:
        """The seed declaration of a report: evaluation base, and whether it is disjoint from the tuning seeds."""
        tuned = " — **the tuning base: these runs are not an evaluation**" if self.seed == 1 else ""
        return (f"Evaluation seeds: base {self.seed} (run r: `SeedSequence({self.seed}, spawn_key=(r,))`, the same "
                f"for every variant){tuned}. Tuning and development seeds: {TUNING_SEEDS}.")

    def campaign(self, config: CampaignConfig) -> CampaignResult:
        """:func:`simulator.campaign.runner.run_campaign` of ``config``, counting its completed runs' source versions
        in :attr:`codes`."""
        from simulator.campaign.runner import run_campaign
        from simulator.provenance import code_versions

        res = run_campaign(config)
        self.codes.update(code_versions(res.out_dir / r.run_dir for r in res.reports
                                        if r.status == "completed" and r.run_dir))
        return res

    def map(self, fn: Callable[[T], R], jobs: Sequence[T], chunksize: int = 1, store: str | None = None,
            types: Sequence[type] = ()) -> list[R]:
        """``[fn(j) for j in jobs]``, on a pool of ``workers`` processes (all cores by default) unless one suffices;
        ``fn`` and the jobs must be picklable (module-level functions, plain values).

        With ``store`` (a name), each result is kept in ``out_dir/campaigns/<store>`` as it finishes
        (:class:`simulator.reproduce.stored.JobStore`, decoding only the dataclasses ``types``) and a job already
        stored there by the same code is not run again, so an interrupted reproduction resumes. Quick mode never
        stores."""
        if store is None or self.quick:
            return self._run(fn, jobs, chunksize)
        from simulator.reproduce.stored import JobStore, code_fingerprint

        code = code_fingerprint(fn.__module__)
        with JobStore(self.out_dir / "campaigns" / store, types, code) as st:
            todo = [j for j in jobs if j not in st]
            self.reused[store] = (len(jobs) - len(todo), len(jobs))
            if len(todo) < len(jobs):
                print(f"{store}: {len(jobs) - len(todo)} of {len(jobs)} jobs reused from {st.path}", file=sys.stderr)
            self._run(fn, todo, 1, on_result=st.put)
            return [st.get(j) for j in jobs]

    def _run(self, fn: Callable[[T], R], jobs: Sequence[T], chunksize: int,
             on_result: Callable[[T, R], None] | None = None) -> list[R]:
        workers = min(self.workers or os.cpu_count() or 1, len(jobs))
        if workers <= 1 or self.quick:
            out = []
            for j in jobs:
                out.append(fn(j))
                if on_result is not None:
                    on_result(j, out[-1])
            return out
        with cf.ProcessPoolExecutor(workers) as pool:
            if on_result is None:
                return list(pool.map(fn, jobs, chunksize=chunksize))
            futures = {pool.submit(fn, j): i for i, j in enumerate(jobs)}
            res: list = [None] * len(jobs)
            try:
                for fut in cf.as_completed(futures):  # stored as each finishes, whatever the order
                    i = futures[fut]
                    res[i] = fut.result()
                    on_result(jobs[i], res[i])
            except BaseException:
                pool.shutdown(wait=False, cancel_futures=True)
                raise
            return res


@dataclass(frozen=True, kw_only=True)
class PaperReport:
    """A paper's reproduction: what was run, the tables, the figures and the verdicts."""

    paper: str
    title: str
    runs: int
    setup: str
    tables: tuple[Table, ...] = ()
    figures: tuple[Figure, ...] = ()
    findings: tuple[Finding, ...] = ()
    deviations: tuple[str, ...] = ()
    seeds: str = ""
    wall_time_s: float = float("nan")
    quick: bool = False
    reused: dict[str, tuple[int, int]] = field(default_factory=dict)
    codes: dict[str, int] = field(default_factory=dict)
    extra: dict = field(default_factory=dict)


def paper_markdown(rep: PaperReport, command: str) -> str:
    """The Markdown text of ``report.md`` for one paper."""
    md = [f"# Reproduction of paper {rep.paper}: {rep.title}", "",
          f"Generated by `{command}` ({rep.runs} run{'s' if rep.runs != 1 else ''} per configuration"
          + (f", {rep.wall_time_s:.0f} s wall time" if math.isfinite(rep.wall_time_s) else "") + ")."
          + (" **Quick mode: shortened experiments, not a reproduction.**" if rep.quick else "")
          + _runs_warning(rep) + _reused_text(rep) + _codes_text(rep), "",
          "## Set-up", "", rep.setup.strip(), ""]
    if rep.seeds:
        md += [rep.seeds, ""]
    if rep.deviations:
        md += ["## Deviations from the paper", "", *(f"- {d}" for d in rep.deviations), ""]
    esc = lambda c: str(c).replace("|", "\\|")  # noqa: E731
    for title, keep in (("Findings: the paper's claims, on the paper's configuration",
                         lambda f: f.paper_claim and f.paper_faithful),
                        ("Findings: the paper's claims, on our configuration (with our additions)",
                         lambda f: f.paper_claim and not f.paper_faithful),
                        ("Our extensions (not claims of the paper)", lambda f: not f.paper_claim)):
        rows = [f for f in rep.findings if keep(f)]
        if not rows:
            continue
        md += [f"## {title}", "", "| claim | verdict | rule | ours | paper | runs | evidence |",
               "|---|---|---|---|---|---:|---|"]
        md += [f"| {esc(f.claim)} | **{f.verdict}** | {esc(f.rule)} | {esc(f.ours)} | {esc(f.paper)} | {f.runs} | "
               f"{esc(f.why)} |" for f in rows]
        md.append("")
    for t in rep.tables:
        md += [f"## {t.title}", "", t.markdown(), ""]
        if t.note:
            md += [t.note, ""]
    for fig in rep.figures:
        md += [f"![{fig.caption}]({fig.path})", "", f"*{fig.caption}*", ""]
    return "\n".join(md)


def _reused_text(rep: PaperReport) -> str:
    done = {k: v for k, v in rep.reused.items() if v[0]}
    if not done:
        return ""
    parts = ", ".join(f"{k}: {n} of {m}" for k, (n, m) in done.items())
    return (f" Resumed: jobs taken from results stored by an earlier run of the same code ({parts}); the wall time "
            "covers only the rest.")


def _codes_text(rep: PaperReport) -> str:
    """Which versions of the source made the physics runs, in bold unless all came from this one (a campaign resumed
    after a change holds several)."""
    from simulator.provenance import source_fingerprint, versions_text

    text = versions_text(Counter(rep.codes))
    if not text:
        return ""
    mixed = set(rep.codes) != {source_fingerprint()}  # several versions, or only another one
    return (f" {'**' if mixed else ''}Provenance: {text}{'**' if mixed else ''}"
            + (" (each campaign keeps its finished runs; rerun a campaign in a fresh `--out` for one version)."
               if mixed else "."))


def _runs_warning(rep: PaperReport) -> str:
    want = PAPER_RUNS.get(rep.paper)
    if want is None or rep.runs >= want or rep.quick:
        return ""
    return f" **Preliminary: {rep.runs} runs per configuration where the reproduction asks for {want}.**"


def verdicts_record(rep: PaperReport, command: str) -> dict:
    """The content of ``verdicts.json``: every claim with its verdict, rule, figures, runs and faithfulness, and the
    tallies (``paper``: the paper's claims judged on its configuration; ``ours``: its claims on ours;
    ``extensions``: our own claims)."""
    def tally(keep: Callable[[Finding], bool]) -> dict[str, int]:
        return {v: sum(1 for f in rep.findings if keep(f) and f.verdict == v) for v in VERDICTS}

    return {"paper": rep.paper, "title": rep.title, "command": command, "runs": rep.runs,
            "runs_asked": PAPER_RUNS.get(rep.paper), "quick": rep.quick, "seeds": rep.seeds,
            "claims": [f.record() for f in rep.findings],
            "tally": {"paper": tally(lambda f: f.paper_claim and f.paper_faithful),
                      "ours": tally(lambda f: f.paper_claim and not f.paper_faithful),
                      "extensions": tally(lambda f: not f.paper_claim)},
            "deviations": list(rep.deviations),
            "physics_runs_by_code": dict(sorted(rep.codes.items()))}


def write_paper_report(rep: PaperReport, out_dir: Path, command: str) -> Path:
    """Write ``out_dir / "report.md"``; returns its path."""
    path = Path(out_dir) / "report.md"
    atomic_write_text(path, paper_markdown(rep, command))
    return path
