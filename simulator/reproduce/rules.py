"""Verdict rules: how a paper's claim is judged from our runs, as strictly as the paper states it.

Each rule takes the measured numbers (one value per run, or paired values per run seed) and returns a
:class:`Judgement`: the verdict, the rule in words and our figure in words. A claim of the form "A is below B" is
*reproduced* only when the 95 % interval says so, *not reproduced* when the interval says the opposite, and
*inconclusive* when the interval straddles the line (the runs cannot decide; more runs might). Claims about every run
or every step ("the error stays below 0.05 m") are judged on the worst value, never on a mean.

The rules are pure functions of their inputs; ``tests/simulator/test_reproduce_rules.py`` feeds each a constructed
result that meets it and one that violates it.

Notes
-----
Intervals: Student-t for means and paired differences (:func:`simulator.reproduce.report.mean_ci`), Clopper–Pearson for
rates (exact binomial). A paired rule drops a pair where either value is not finite and says how many pairs it used.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

from simulator.reproduce.report import VERDICTS, Verdict, mean_ci

__all__ = ["Judgement", "every", "all_below", "all_at_least", "mean_below", "mean_at_least", "paired_less",
           "paired_reduction_at_least", "paired_within", "rate_at_least", "clopper_pearson"]

ArrayLike = Sequence[float] | np.ndarray


@dataclass(frozen=True, kw_only=True)
class Judgement:
    """A rule's outcome: ``verdict``, ``rule`` (the rule in words) and ``ours`` (the measured figure in words)."""

    verdict: Verdict
    rule: str
    ours: str
    runs: int

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            raise ValueError(f"Judgement.verdict must be one of {VERDICTS}, got {self.verdict!r}")


def _finite(values: ArrayLike) -> np.ndarray:
    x = np.asarray(values, dtype=float).ravel()
    return x[np.isfinite(x)]


def _empty(rule: str) -> Judgement:
    return Judgement(verdict="not comparable", rule=rule, ours="no finite value", runs=0)


def _g(x: float, digits: int = 3) -> str:
    return f"{x:.{digits}g}"


def _beside(x: float, line: float) -> str:
    """``x`` with 3 significant digits, or as many more as it takes not to print it as ``line`` when it is not (a
    smallest distance of 9.9996 m judged against 10 m reads "9.9996", not "10")."""
    for digits in range(3, 13):
        if x == line or _g(x, digits) != _g(line, digits):
            return _g(x, digits)
    return repr(x)


def _worst(values: ArrayLike, limit: float, unit: str, below: bool) -> Judgement:
    """Every value past ``limit`` (below it, or at least it), judged on the worst value."""
    rule = f"largest value < {_g(limit)}{unit}" if below else f"smallest value ≥ {_g(limit)}{unit}"
    x = _finite(values)
    if x.size == 0:
        return _empty(rule)
    worst = float(x.max() if below else x.min())
    ok = worst < limit if below else worst >= limit
    return Judgement(verdict="reproduced" if ok else "not reproduced", rule=rule,
                     ours=f"{'largest' if below else 'smallest'} {_beside(worst, limit)}{unit} over {x.size} values",
                     runs=int(x.size))


def all_below(values: ArrayLike, limit: float, unit: str = "") -> Judgement:
    """Every value is strictly below ``limit`` (a claim about every run or step: judged on the largest value)."""
    return _worst(values, limit, unit, below=True)


def all_at_least(values: ArrayLike, limit: float, unit: str = "") -> Judgement:
    """Every value is at least ``limit`` (judged on the smallest value)."""
    return _worst(values, limit, unit, below=False)


def _interval_verdict(lo: float, hi: float, limit: float, below: bool) -> Verdict:
    if below:
        return "reproduced" if hi < limit else ("not reproduced" if lo >= limit else "inconclusive")
    return "reproduced" if lo >= limit else ("not reproduced" if hi < limit else "inconclusive")


def _bounds(x: np.ndarray) -> tuple[float, float, str]:
    ci = mean_ci(x)
    half = 0.0 if ci.half is None else ci.half
    if ci.half is None:  # one run: no interval; the value itself decides nothing beyond itself
        half = math.inf
    return ci.mean - half, ci.mean + half, ci.text()


def _mean(values: ArrayLike, limit: float, unit: str, below: bool) -> Judgement:
    rule = f"95 % interval of the mean {'below' if below else '≥'} {_g(limit)}{unit}"
    x = _finite(values)
    if x.size == 0:
        return _empty(rule)
    lo, hi, text = _bounds(x)
    return Judgement(verdict=_interval_verdict(lo, hi, limit, below=below), rule=rule,
                     ours=f"{text}{unit} over {x.size} runs", runs=int(x.size))


def mean_below(values: ArrayLike, limit: float, unit: str = "") -> Judgement:
    """The mean over runs is below ``limit``: reproduced when the 95 % interval's upper end is below it, not
    reproduced when its lower end is at or above it, inconclusive otherwise (and with one run)."""
    return _mean(values, limit, unit, below=True)


def mean_at_least(values: ArrayLike, limit: float, unit: str = "") -> Judgement:
    """The mean over runs is at least ``limit`` (the mirror of :func:`mean_below`)."""
    return _mean(values, limit, unit, below=False)


def _pairs(a: ArrayLike, b: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    x, y = np.asarray(a, dtype=float).ravel(), np.asarray(b, dtype=float).ravel()
    if x.shape != y.shape:
        raise ValueError(f"paired values need equal lengths, got {x.size} and {y.size}")
    keep = np.isfinite(x) & np.isfinite(y)
    return x[keep], y[keep]


def paired_less(a: ArrayLike, b: ArrayLike, unit: str = "", names: tuple[str, str] = ("A", "B")) -> Judgement:
    """``a`` is below ``b``, paired by run (common random numbers): the 95 % interval of the mean of ``a − b`` lies
    below 0 (reproduced), at or above 0 (not reproduced), or contains 0 (inconclusive)."""
    rule = f"95 % interval of the paired difference {names[0]} − {names[1]} below 0"
    x, y = _pairs(a, b)
    if x.size == 0:
        return _empty(rule)
    lo, hi, text = _bounds(x - y)
    return Judgement(verdict=_interval_verdict(lo, hi, 0.0, below=True), rule=rule,
                     ours=f"{names[0]} − {names[1]} = {text}{unit} over {x.size} paired runs", runs=int(x.size))


def paired_reduction_at_least(a: ArrayLike, b: ArrayLike, fraction: float,
                              names: tuple[str, str] = ("A", "B")) -> Judgement:
    """``a`` reduces ``b`` by at least ``fraction`` (e.g. 0.3 for "30 % lower"), judged on the ratio of means
    ``1 − mean(a)/mean(b)``: reproduced when the 95 % interval of the paired ``a − (1 − fraction)·b`` lies below 0, not
    reproduced when it lies at or above 0, inconclusive otherwise.

    ``mean(a) ≤ (1 − f)·mean(b)`` is the claim itself, so testing the paired linear combination (Fieller's construction
    for a ratio of paired means) needs no delta-method approximation of the ratio."""
    rule = f"reduction 1 − mean({names[0]})/mean({names[1]}) ≥ {fraction:.0%}: 95 % interval of " \
           f"{names[0]} − {1.0 - fraction:.2g}·{names[1]} below 0 (paired)"
    x, y = _pairs(a, b)
    if x.size == 0 or not np.mean(y) > 0:
        return _empty(rule)
    lo, hi, _ = _bounds(x - (1.0 - fraction) * y)
    red = 1.0 - float(np.mean(x) / np.mean(y))
    return Judgement(verdict=_interval_verdict(lo, hi, 0.0, below=True), rule=rule,
                     ours=f"reduction {red:.1%} over {x.size} paired runs", runs=int(x.size))


def paired_within(a: ArrayLike, b: ArrayLike, margin: float, unit: str = "",
                  names: tuple[str, str] = ("A", "B")) -> Judgement:
    """``a`` and ``b`` are equivalent within ``margin`` (a claim like "barely affected"): two one-sided tests — the
    95 % interval of the mean paired difference lies inside (−margin, margin) (reproduced), entirely outside it (not
    reproduced), or across one of its ends (inconclusive)."""
    rule = f"95 % interval of the paired difference {names[0]} − {names[1]} inside ±{_g(margin)}{unit}"
    x, y = _pairs(a, b)
    if x.size == 0:
        return _empty(rule)
    lo, hi, text = _bounds(x - y)
    if -margin < lo and hi < margin:
        verdict: Verdict = "reproduced"
    elif hi <= -margin or lo >= margin:
        verdict = "not reproduced"
    else:
        verdict = "inconclusive"
    return Judgement(verdict=verdict, rule=rule, runs=int(x.size),
                     ours=f"{names[0]} − {names[1]} = {text}{unit} over {x.size} paired runs")


def clopper_pearson(successes: int, trials: int, confidence: float = 0.95) -> tuple[float, float]:
    """Exact (Clopper–Pearson) two-sided interval of a binomial proportion."""
    if trials < 1 or not 0 <= successes <= trials:
        raise ValueError(f"need 0 <= successes <= trials and trials >= 1, got {successes}/{trials}")
    a = 1.0 - confidence
    lo = 0.0 if successes == 0 else float(stats.beta.ppf(a / 2, successes, trials - successes + 1))
    hi = 1.0 if successes == trials else float(stats.beta.ppf(1 - a / 2, successes + 1, trials - successes))
    return lo, hi


def rate_at_least(successes: int, trials: int, rate: float) -> Judgement:
    """A proportion is at least ``rate``: reproduced when the Clopper–Pearson 95 % interval's lower end is at or above
    it, not reproduced when its upper end is below it, inconclusive otherwise."""
    rule = f"Clopper–Pearson 95 % interval of the rate ≥ {rate:.3g}"
    if trials < 1:
        return _empty(rule)
    lo, hi = clopper_pearson(successes, trials)
    return Judgement(verdict=_interval_verdict(lo, hi, rate, below=False), rule=rule,
                     ours=f"{successes}/{trials} = {successes / trials:.3g} (95 % {lo:.3g}–{hi:.3g})", runs=int(trials))


_WORST_FIRST = ("not reproduced", "not comparable", "inconclusive", "reproduced")


def every(parts: Mapping[str, Judgement] | Sequence[Judgement], rule: str | None = None) -> Judgement:
    """A claim that must hold in every part (case, turn, scenario): reproduced only when every part is; not reproduced
    when any part is (whatever the others); else not comparable, else inconclusive. No parts: not comparable.

    ``parts`` named (a mapping) give ``ours`` as ``name: figure`` and a default rule naming them; unnamed (a sequence)
    give ``figure (verdict)`` per part and need ``rule``."""
    named = isinstance(parts, Mapping)
    items = list(parts.items()) if named else [(None, j) for j in parts]
    if not items:
        return Judgement(verdict="not comparable", rule=rule or "every part", ours="no part was run", runs=0)
    verdict = min((j.verdict for _, j in items), key=_WORST_FIRST.index)
    if rule is None:
        texts = list(dict.fromkeys(j.rule for _, j in items if j.rule != "—")) or ["—"]
        rule = "in every one of " + ", ".join(str(k) for k, _ in items) + ": " + "; ".join(texts)
    ours = "; ".join(f"{k}: {j.ours}" if named else f"{j.ours} ({j.verdict})" for k, j in items)
    return Judgement(verdict=verdict, rule=rule, ours=ours, runs=min(j.runs for _, j in items))
