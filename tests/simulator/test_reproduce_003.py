"""Paper 003's verdict logic: the findings functions fed constructed results that meet and that violate each rule,
and the experiment's seeding (common random numbers across variants and cases)."""

import numpy as np
import pytest

from simulator.reproduce.paper_003_findings import BASELINES, GAP_LIMIT, every, kinematic_findings
from simulator.reproduce.paper_003_physics import CASE_SETS, formation_overrides, physics_findings
from simulator.reproduce.paper_003_runs import (FORMATIONS, MISMATCHED_RATES, PAPER, RANGE_M, _config,
                                                random_bearings, variants)
from simulator.reproduce.rules import Judgement

N = 40  # Clopper–Pearson: 40 of 40 puts the lower end of the switching rate above 0.9
SENS = tuple(f"{PAPER}@{w:g}" for w in MISMATCHED_RATES)
CLAIMS = ("ordering", "bound", "case4", *(f"case4 {v}" for v in SENS), *(f"vs {b}" for b in BASELINES))


def _noise(seed: int, scale: float = 0.05) -> np.ndarray:
    return scale * np.random.default_rng(seed).normal(size=N)


def _results(good: bool, runs: int = N) -> dict:
    """Results that meet every kinematic rule (``good``) or violate every one, with small run-to-run noise."""
    s = 1.0 if good else -1.0
    res: dict = {}
    for case in (1, 2, 3, 4):
        res[(case, PAPER)] = {"error": 3.0 + (0.0 if case == 1 else s * 1.0) + _noise(case),
                              "gap": (0.02 if good else 0.5) + np.abs(_noise(10 + case, 0.005))}
        res[(case, "optimal")] = {"error": 3.0 + _noise(20 + case)}
        for k, base in enumerate(BASELINES):
            res[(case, base)] = {"error": 3.0 + s * 1.0 + _noise(30 + 4 * case + k)}
    for k, var in enumerate((PAPER, *SENS)):
        for j in (1, 2):
            res.setdefault((1, var), {})[f"turn{j}_early"] = 3.0 + _noise(50 + 2 * k + j)
            res.setdefault((4, var), {}).update({
                f"turn{j}_early": 3.0 + s * 2.0 + _noise(60 + 2 * k + j),
                f"turn{j}_late": 3.0 + s * 2.0 - s * 1.5 + _noise(70 + 2 * k + j),
                f"turn{j}_switched": np.ones(N) if good else np.zeros(N)})
    return {key: {name: x[:runs] for name, x in row.items()} for key, row in res.items()}


def _verdicts(findings) -> dict[str, str]:
    assert len(findings) == len(CLAIMS)
    return dict(zip(CLAIMS, (f.verdict for f in findings), strict=True))


def test_constructed_results_that_meet_every_rule_are_reproduced():
    findings = kinematic_findings(_results(good=True))
    assert _verdicts(findings) == dict.fromkeys(CLAIMS, "reproduced")
    for f in findings:
        assert f.rule and f.ours and f.paper and f.runs == N
    flags = {c: (f.paper_faithful, f.paper_claim) for c, f in zip(CLAIMS, findings, strict=True)}
    assert flags["ordering"] == flags["bound"] == flags["case4"] == (True, True)
    assert all(flags[f"case4 {v}"] == (False, True) for v in SENS)
    assert all(flags[f"vs {b}"] == (False, False) for b in BASELINES)
    assert findings[1].rule.endswith(f"95 % interval of the mean below {GAP_LIMIT:.3g}")
    assert "e(case 1) − e(turn)" in findings[2].ours and "Clopper–Pearson" in findings[2].rule


def test_constructed_results_that_violate_every_rule_are_not_reproduced():
    assert _verdicts(kinematic_findings(_results(good=False))) == dict.fromkeys(CLAIMS, "not reproduced")


def test_one_run_decides_nothing():
    verdicts = _verdicts(kinematic_findings(_results(good=True, runs=1)))
    paired = [c for c in CLAIMS if c != "bound"]
    # a paired difference or a mean from one run has no interval; one switching run cannot show a 90 % rate
    assert {verdicts[c] for c in paired} == {"inconclusive"}
    assert verdicts["bound"] == "inconclusive"


def test_one_violated_case_or_turn_fails_the_claim():
    res = _results(good=True)
    res[(3, "trail")]["error"] = res[(3, "optimal")]["error"] - 1.0  # trail better in case 3 only
    res[(4, PAPER)]["turn2_switched"] = np.r_[np.ones(10), np.zeros(N - 10)]  # the IMM switches in half the runs
    v = _verdicts(kinematic_findings(res))
    assert v["vs trail"] == "not reproduced" and v["vs fixed"] == "reproduced"
    assert v["case4"] == "not reproduced" and v[f"case4 {SENS[0]}"] == "reproduced"


def test_missing_cases_are_not_comparable():
    res = {k: v for k, v in _results(good=True).items() if k[0] in (1, 2)}  # a quick run
    v = _verdicts(kinematic_findings(res))
    assert v["ordering"] == v["bound"] == v["case4"] == v["vs random"] == "not comparable"


def test_every_takes_the_worst_part():
    def j(verdict: str) -> Judgement:
        return Judgement(verdict=verdict, rule="r", ours=verdict, runs=5)

    assert every({"a": j("reproduced"), "b": j("reproduced")}).verdict == "reproduced"
    assert every({"a": j("reproduced"), "b": j("inconclusive")}).verdict == "inconclusive"
    assert every({"a": j("inconclusive"), "b": j("not comparable")}).verdict == "not comparable"
    assert every({"a": j("not comparable"), "b": j("not reproduced")}).verdict == "not reproduced"
    assert every({}).verdict == "not comparable"
    combined = every({"case 1": j("reproduced"), "case 2": j("inconclusive")})
    assert combined.rule == "in every one of case 1, case 2: r"
    assert combined.ours == "case 1: reproduced; case 2: inconclusive"


@pytest.mark.parametrize("good,expected", [(True, "reproduced"), (False, "not reproduced")])
def test_physics_findings(good, expected):
    s = 1.0 if good else -1.0
    phys = {(c, f): {"gap": (0.05 if f == "optimal" else 0.05 + s) + _noise(c, 0.01),
                     "error": (4.0 if f == "optimal" else 4.0 + s * 2) + _noise(10 + c, 0.2)}
            for c in CASE_SETS for f in ("optimal", "trail")}
    findings = physics_findings(phys)
    assert [f.verdict for f in findings] == [expected, expected]
    assert all(not f.paper_faithful and not f.paper_claim and f.runs == N for f in findings)
    phys[(2, "trail")]["error"][3] = np.nan  # a failed run drops its pair only
    assert physics_findings(phys)[1].runs == N - 1
    del phys[(4, "trail")]  # a missing case leaves the claim undecided, unless another case already refutes it
    assert [f.verdict for f in physics_findings(phys)] == ["not comparable" if good else "not reproduced"] * 2


def test_every_formation_flies_the_same_range_and_the_paper_variant_keeps_algorithm_1():
    b = random_bearings(123)
    assert b == random_bearings(123) and b != random_bearings(124) and len(b) == 3
    for form in FORMATIONS:
        cfg = _config(4, form, False, b)
        assert cfg.ranges == (RANGE_M,) * 3
    assert _config(4, "random", False, b).fixed_bearings == b and _config(4, "random", False, b).formation == "fixed"
    assert _config(4, "fixed", False, b).fixed_bearings is None
    paper = _config(4, f"{PAPER}@0.5", False, b)
    assert paper.ranges is None and paper.formation == "optimal" and paper.turn_rate == 0.5
    assert variants(4) == (PAPER, *FORMATIONS, *SENS) and variants(2) == (PAPER, *FORMATIONS)
    assert formation_overrides("trail", 2) == tuple(
        f"uavs[{i}].autonomy.guidance.formation={{geometry: trail, ranges: [95, 95]}}" for i in (0, 1))
