"""Verdict rules of the reproductions: each says "reproduced" on a constructed result that meets it, "not reproduced"
on one that violates it, and "inconclusive" where the interval straddles the line."""

import json

import numpy as np
import pytest

from simulator.reproduce.cli import _read_verdicts, _write_index
from simulator.reproduce.report import Finding, PaperReport, ReproContext, paper_markdown, verdicts_record
from simulator.reproduce.rules import (all_at_least, all_below, clopper_pearson, mean_at_least, mean_below,
                                       paired_less, paired_reduction_at_least, paired_within, rate_at_least)


def _noise(n: int, sigma: float, seed: int = 3) -> np.ndarray:
    return np.random.default_rng(seed).normal(0.0, sigma, n)


def test_all_below_judges_the_worst_value_not_the_mean():
    # the paper's "errors below 0.05 m": a mean of 0.02 with one step at 0.18 m must fail
    x = np.full(1000, 0.02)
    assert all_below(x, 0.05).verdict == "reproduced"
    x[500] = 0.18
    j = all_below(x, 0.05, " m")
    assert j.verdict == "not reproduced" and "0.18" in j.ours and j.runs == 1000
    assert all_below([np.nan], 1.0).verdict == "not comparable"


def test_all_at_least_judges_the_smallest_value():
    assert all_at_least([10.2, 11.0, 30.0], 10.0).verdict == "reproduced"
    assert all_at_least([10.2, 9.99, 30.0], 10.0).verdict == "not reproduced"


def test_a_worst_value_next_to_the_line_prints_the_digits_that_decide_it():
    short = all_at_least([12.0, 9.99957], 10.0, " m")
    assert short.verdict == "not reproduced" and "smallest 9.9996 m" in short.ours
    assert "smallest 10 m" in all_at_least([10.0, 12.0], 10.0, " m").ours
    assert "largest 0.178 m" in all_below([0.1781234], 0.05, " m").ours


@pytest.mark.parametrize("mean,verdict", [(0.8, "reproduced"), (1.2, "not reproduced"), (1.0, "inconclusive")])
def test_mean_below_uses_both_ends_of_the_interval(mean, verdict):
    x = mean + _noise(50, 0.2)
    assert mean_below(x, 1.0).verdict == verdict
    assert mean_at_least(x, 1.0).verdict == {"reproduced": "not reproduced", "not reproduced": "reproduced",
                                             "inconclusive": "inconclusive"}[verdict]


def test_one_run_decides_no_interval_claim():
    assert mean_below([0.1], 1.0).verdict == "inconclusive"
    assert paired_less([0.1], [5.0]).verdict == "inconclusive"


@pytest.mark.parametrize("shift,verdict", [(-0.5, "reproduced"), (0.5, "not reproduced"), (0.0, "inconclusive")])
def test_paired_less_is_judged_on_the_paired_differences(shift, verdict):
    # a large common per-run spread that pairing removes: unpaired means could not tell 0.5 apart
    base = 10.0 + _noise(40, 5.0, seed=1)
    a = base + shift + _noise(40, 0.3, seed=2)
    assert paired_less(a, base).verdict == verdict


def test_paired_rules_drop_unfinished_pairs_and_refuse_unequal_lengths():
    j = paired_less([1.0, np.nan, 1.0, 1.1], [2.0, 0.0, 2.1, 2.0])
    assert j.runs == 3 and j.verdict == "reproduced"
    with pytest.raises(ValueError, match="equal lengths"):
        paired_less([1.0, 2.0], [1.0])


def test_paired_reduction_needs_the_whole_interval_past_the_fraction():
    b = 10.0 + _noise(100, 1.0, seed=4)
    assert paired_reduction_at_least(0.6 * b + _noise(100, 0.2, 5), b, 0.3).verdict == "reproduced"  # 40 %
    assert paired_reduction_at_least(0.75 * b + _noise(100, 0.2, 5), b, 0.3).verdict == "not reproduced"  # 25 %
    e = _noise(50, 2.0, 5)
    j = paired_reduction_at_least(0.7 * b + np.concatenate([e, -e]), b, 0.3)  # exactly 30 % on average, with noise
    assert j.verdict == "inconclusive" and "reduction" in j.ours


def test_paired_within_is_two_one_sided_tests():
    b = 5.0 + _noise(60, 1.0, seed=6)
    assert paired_within(b + 0.05 + _noise(60, 0.1, 7), b, 0.5).verdict == "reproduced"
    assert paired_within(b + 1.5 + _noise(60, 0.1, 7), b, 0.5).verdict == "not reproduced"
    assert paired_within(b + 0.5 + _noise(60, 0.3, 7), b, 0.5).verdict == "inconclusive"


def test_clopper_pearson_matches_the_closed_form_ends():
    # 0 of n: upper end 1 − (α/2)^(1/n); n of n: lower end (α/2)^(1/n)
    lo, hi = clopper_pearson(0, 20)
    assert lo == 0.0 and hi == pytest.approx(1 - 0.025 ** (1 / 20), rel=1e-9)
    lo, hi = clopper_pearson(20, 20)
    assert hi == 1.0 and lo == pytest.approx(0.025 ** (1 / 20), rel=1e-9)
    with pytest.raises(ValueError):
        clopper_pearson(3, 2)


def test_rate_at_least():
    assert rate_at_least(99, 100, 0.9).verdict == "reproduced"
    assert rate_at_least(70, 100, 0.9).verdict == "not reproduced"
    assert rate_at_least(9, 10, 0.9).verdict == "inconclusive"


def _report(findings: tuple[Finding, ...], runs: int = 100) -> PaperReport:
    return PaperReport(paper="003", title="t", runs=runs, setup="s", findings=findings, deviations=("d1",),
                       seeds="Evaluation seeds: base 9.")


def test_verdicts_json_and_report_separate_paper_claims_from_extensions(tmp_path):
    findings = (
        Finding.judged("errors below 1 m", all_below([0.5, 0.7], 1.0), paper="< 1 m"),
        Finding.judged("A beats B (ours)", paired_less([1.0, 1.1, 0.9], [2.0, 2.1, 2.0]), paper="A < B",
                       paper_faithful=False),
        Finding.judged("our own claim", all_below([3.0], 1.0), paper="", paper_claim=False),
    )
    rec = verdicts_record(_report(findings), "skytrack reproduce 003")
    assert rec["tally"]["paper"]["reproduced"] == 1 and rec["tally"]["ours"]["reproduced"] == 1
    assert rec["tally"]["extensions"]["not reproduced"] == 1
    c = rec["claims"][0]
    assert set(c) >= {"claim", "verdict", "rule", "ours", "paper", "runs", "paper_faithful"}
    assert c["rule"].startswith("largest value") and c["runs"] == 2
    md = paper_markdown(_report(findings, runs=10), "cmd")
    assert "Preliminary: 10 runs per configuration where the reproduction asks for 100" in md
    assert md.index("paper's configuration") < md.index("our configuration") < md.index("Our extensions")
    assert "Evaluation seeds: base 9." in md and "- d1" in md

    (tmp_path / "003").mkdir()
    (tmp_path / "003" / "verdicts.json").write_text(json.dumps(rec))
    (tmp_path / "004").mkdir()
    (tmp_path / "004" / "verdicts.json").write_text('{"runs": 10, "reproduced": 3}')  # an old or edited file
    _write_index(tmp_path)
    index = (tmp_path / "report.md").read_text()
    assert "| 1 / 0 / 0 / 0 | 1 / 0 / 0 / 0 | 0 / 1 / 0 / 0 |" in index
    assert "unreadable `004/verdicts.json`" in index
    assert _read_verdicts(tmp_path / "004" / "verdicts.json") is None


def test_run_seeds_are_common_to_variants_and_off_the_tuning_base(tmp_path):
    ctx = ReproContext(out_dir=tmp_path, runs=5)
    assert ctx.run_seeds() == ctx.run_seeds() and len(set(ctx.run_seeds())) == 5
    assert ctx.run_seeds(3) == ctx.run_seeds()[:3]
    assert ctx.seed != 1 and "not an evaluation" not in ctx.seeds_text()
    assert "not an evaluation" in ReproContext(out_dir=tmp_path, runs=1, seed=1).seeds_text()


def test_every_part_must_hold_and_one_failed_part_fails_the_claim():
    from simulator.reproduce.rules import Judgement, every

    def j(v: str) -> Judgement:
        return Judgement(verdict=v, rule="r", ours=v, runs=4)

    assert every({"a": j("reproduced"), "b": j("reproduced")}).verdict == "reproduced"
    assert every([j("reproduced"), j("inconclusive")], "both").verdict == "inconclusive"
    # a failed part fails the claim even where another part could not be judged
    assert every([j("not comparable"), j("not reproduced")], "both").verdict == "not reproduced"
    assert every([j("reproduced"), j("not comparable")], "both").verdict == "not comparable"
    assert every([], "none").verdict == "not comparable"
    named = every({"case 1": j("reproduced"), "case 2": j("inconclusive")})
    assert named.rule == "in every one of case 1, case 2: r"
    assert named.ours == "case 1: reproduced; case 2: inconclusive"
