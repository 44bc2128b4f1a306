"""Aggregate a campaign's completed runs: per numeric metric the mean, standard deviation and a 95 % confidence interval
of the mean.

For the ``n`` values :math:`x_1 .. x_n` of one metric,

.. math::

    \\bar x = \\frac{1}{n}\\sum_i x_i, \\qquad s = \\sqrt{\\frac{1}{n-1}\\sum_i (x_i - \\bar x)^2}, \\qquad
    \\bar x \\pm t_{0.975,\\,n-1}\\,\\frac{s}{\\sqrt n}

with Student's t quantile (``scipy.stats.t.ppf``). With ``n = 1`` the deviation and interval are undefined (``None``).
Only runs with status ``completed`` count; booleans, strings and ``None`` values are left out, as are non-finite values.
Event counts (``events.*``) missing from a run's metrics are zero for that run (the run had no such event).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from simulator.campaign.config import FAILED, RunReport
from simulator.record import atomic_write_text

__all__ = ["CampaignSummary", "MetricStats", "format_table", "metric_stats", "summarize", "write_summary"]

CONFIDENCE = 0.95
"""Two-sided confidence level of the interval of the mean."""

ZERO_IF_ABSENT = ("events.",)
"""Metric-name prefixes that count occurrences: absent from a completed run means zero."""


@dataclass(frozen=True, kw_only=True)
class MetricStats:
    """Statistics of one metric over the completed runs.

    Attributes
    ----------
    name : str
        Dotted metric name.
    n : int
        Runs with a value.
    mean : float
        Sample mean, in the metric's unit.
    std : float | None
        Sample standard deviation (``ddof=1``); None when ``n < 2``.
    ci_low, ci_high : float | None
        95 % Student-t confidence interval of the mean; None when ``n < 2``.
    min, max : float
        Smallest and largest value.
    """

    name: str
    n: int
    mean: float
    std: float | None
    ci_low: float | None
    ci_high: float | None
    min: float
    max: float


def _numeric(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def metric_stats(name: str, values: Sequence[float], confidence: float = CONFIDENCE) -> MetricStats:
    """Mean, standard deviation and Student-t confidence interval of the mean of ``values`` (at least one)."""
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        raise ValueError(f"metric {name!r}: no values")
    mean = float(x.mean())
    std = low = high = None
    if x.size >= 2:
        std = float(x.std(ddof=1))
        half = float(stats.t.ppf(0.5 + confidence / 2.0, df=x.size - 1)) * std / math.sqrt(x.size)
        low, high = mean - half, mean + half
    return MetricStats(name=name, n=int(x.size), mean=mean, std=std, ci_low=low, ci_high=high,
                       min=float(x.min()), max=float(x.max()))


@dataclass(frozen=True, kw_only=True)
class CampaignSummary:
    """Counts and per-metric statistics of a campaign.

    Attributes
    ----------
    runs : int
        Runs recorded.
    completed, failed : int
        Runs with status ``completed`` / ``error``.
    metrics : tuple of MetricStats
        One entry per numeric metric, sorted by name.
    failures : tuple of (int, str)
        ``(index, error)`` of each failed run.
    """

    runs: int
    completed: int
    failed: int
    metrics: tuple[MetricStats, ...]
    failures: tuple[tuple[int, str], ...] = ()

    def get(self, name: str) -> MetricStats:
        """Statistics of metric ``name``; KeyError if no completed run has it."""
        for m in self.metrics:
            if m.name == name:
                return m
        raise KeyError(name)

    def to_json(self) -> dict[str, Any]:
        return {"runs": self.runs, "completed": self.completed, "failed": self.failed, "confidence": CONFIDENCE,
                "metrics": {m.name: {k: v for k, v in asdict(m).items() if k != "name"} for m in self.metrics},
                "failures": [{"index": i, "error": e} for i, e in self.failures]}


def summarize(reports: Iterable[RunReport] | Iterable[Mapping[str, Any]]) -> CampaignSummary:
    """Aggregate run reports (or plain ``{"status": ..., "metrics": {flat}}`` dicts)."""
    values: dict[str, list[float]] = {}
    runs = completed = 0
    failures: list[tuple[int, str]] = []
    counted: list[dict[str, Any]] = []
    for rep in reports:
        data = rep.to_json() if isinstance(rep, RunReport) else dict(rep)
        runs += 1
        if data.get("status") in FAILED:
            failures.append((int(data.get("index", runs - 1)), str(data.get("error"))))
        if data.get("status") != "completed":
            continue
        completed += 1
        counted.append(data.get("metrics") or {})
    event_keys = {k for m in counted for k in m if k.startswith(ZERO_IF_ABSENT)}
    for metrics in counted:
        filled = dict.fromkeys(event_keys, 0)
        filled.update(metrics)
        for key, raw in filled.items():
            value = _numeric(raw)
            if value is not None:
                values.setdefault(key, []).append(value)
    table = tuple(metric_stats(k, v) for k, v in sorted(values.items()))
    return CampaignSummary(runs=runs, completed=completed, failed=len(failures), metrics=table,
                           failures=tuple(sorted(failures)))


def _fmt(value: float | None) -> str:
    return "" if value is None else f"{value:.4g}"


def format_table(summary: CampaignSummary, markdown: bool = False) -> str:
    """The per-metric table as aligned text, or as a Markdown table."""
    head = ("metric", "mean", "std", "95% CI low", "95% CI high", "n")
    rows = [(m.name, _fmt(m.mean), _fmt(m.std), _fmt(m.ci_low), _fmt(m.ci_high), str(m.n)) for m in summary.metrics]
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
        return "\n".join(lines)
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]

    def fmt(r: tuple[str, ...]) -> str:
        return "  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True)))

    return "\n".join([fmt(head), *(fmt(r) for r in rows)])


def write_summary(summary: CampaignSummary, out_dir: Path, title: str = "") -> None:
    """Write ``summary.json`` and ``summary.md`` into ``out_dir``."""
    out_dir = Path(out_dir)
    atomic_write_text(out_dir / "summary.json", json.dumps(summary.to_json(), indent=2) + "\n")
    md = [f"# Campaign summary{': ' + title if title else ''}", "",
          f"{summary.runs} runs: {summary.completed} completed, {summary.failed} failed. "
          f"Statistics over the completed runs; interval: {CONFIDENCE:.0%} Student-t confidence interval of the mean.",
          "", format_table(summary, markdown=True), ""]
    if summary.failures:
        md += ["## Failed runs", "", *(f"- run {i}: {e}" for i, e in summary.failures), ""]
    atomic_write_text(out_dir / "summary.md", "\n".join(md))
