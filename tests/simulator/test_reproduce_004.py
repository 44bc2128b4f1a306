"""Paper 004's verdict logic: constructed summaries that meet and that violate each rule, the decoy-provenance
tracker on a scripted mission, and the physics cross-check's verdicts."""

from types import SimpleNamespace

import numpy as np
import pytest
import shapely

from simulator.reproduce.paper_004_decoys import CENSOR_STEPS, DecoyEpisodes, DecoyProvenance
from simulator.reproduce.paper_004_findings import Results, findings
from simulator.reproduce.paper_004_physics import physics_findings
from simulator.reproduce.paper_004_runs import SENS_RUNS, VARIANTS, RunSummary

N = 20
STEPS = 400
SWEEP = 5520.0


def _summary(i: int, good: bool, name: str = "paper") -> RunSummary:
    jitter = 1e-4 * (i % 5)
    xbar = np.linspace(1.0, 0.0, STEPS)
    x = np.full(STEPS, 0.035 + jitter)
    if good:
        xbar[299:] = 0.001 + jitter
    else:
        xbar[:] = 0.5 + jitter
        x[:] = 0.5 + jitter
    if name == "random":  # the baseline: better than the MPC when the MPC is bad, worse when it is good
        xbar[299] = 0.8 + jitter if good else 0.1 + jitter
    dec = (DecoyEpisodes(started=2, judged=2, erased=2, durations=(5, 9), boxes=4, entered=2) if good
           else DecoyEpisodes(started=0, judged=0, erased=0) if i % 2 else
           DecoyEpisodes(started=3, judged=3, erased=0, boxes=3, entered=3))
    if not good and i == 0:
        dec = DecoyEpisodes(started=0, judged=0, erased=0)
    return RunSummary(xbar=xbar, x=x, guarantee=1.0 if good or i else 0.999, min_obs=12.0 if good or i else 2.0,
                      close_steps=0 if good or i else 3, unsafe=0, cpu_s=50.0 + i if good else 3000.0 + i,
                      decoys=dec, regrowth=1500.0 + i if good else 6000.0 + i)


def _results(good: bool) -> Results:
    runs = {v.name: [_summary(i, good, v.name) for i in range(N if v.name == "paper" else 10)] for v in VARIANTS}
    if not good:  # decoys: none taken for a target in most runs, none erased
        for v in VARIANTS:
            runs[v.name] = [r if i % 4 == 0 else RunSummary(**{**r.__dict__, "decoys": DecoyEpisodes(
                started=0, judged=0, erased=0)}) for i, r in enumerate(runs[v.name])]
    return Results(runs=runs, labels={v.name: v.label for v in VARIANTS}, steps=STEPS, sweep=SWEEP)


def _by_claim(fs, start: str, faithful: bool = True) -> list:
    return [f for f in fs if f.claim.startswith(start) and f.paper_faithful == faithful]


CLAIMS = ("Every true target is inside", "X̄ is very close to empty", "φ(X)/φ(X0) is 0.035",
          "A decoy is taken for a target", "The decoy-born subsets of X are erased", "No UAV comes within")


@pytest.mark.parametrize("claim", CLAIMS)
def test_each_paper_claim_is_reproduced_when_its_rule_is_met(claim):
    fs = findings(_results(good=True))
    (f,) = _by_claim(fs, claim)
    assert f.verdict == "reproduced", f
    assert f.rule and f.ours and f.paper and f.paper_claim and f.paper_faithful


@pytest.mark.parametrize("claim", CLAIMS)
def test_each_paper_claim_is_not_reproduced_when_its_rule_is_violated(claim):
    fs = findings(_results(good=False))
    (f,) = _by_claim(fs, claim)
    assert f.verdict == "not reproduced", f


def test_rules_and_figures_of_the_paper_claims():
    fs = findings(_results(good=True))
    assert _by_claim(fs, "X̄ is very close to empty")[0].rule == "95 % interval of the mean below 0.01"
    assert _by_claim(fs, "φ(X)/φ(X0) is 0.035")[0].rule == (
        "95 % interval of the paired difference ours − paper's 0.035 inside ±0.0175")
    erased = _by_claim(fs, "The decoy-born subsets")[0]
    assert erased.rule == "Clopper–Pearson 95 % interval of the rate ≥ 0.5"
    assert erased.ours.startswith(f"{2 * N}/{2 * N} = 1")
    assert "median 7 steps from birth to erasure" in erased.why
    assert _by_claim(fs, "A decoy is taken")[0].ours.startswith(f"{N}/{N} = 1")
    assert "0.035 at k = 400" in _by_claim(fs, "φ(X)/φ(X0) is 0.035")[0].paper
    assert "regrows" not in _by_claim(fs, "X̄ is very close to empty")[0].why
    bad = _by_claim(findings(_results(good=False)), "X̄ is very close to empty")[0].why
    assert "X̄ regrows by 6010 m²/s on average while the four footprints sweep 5520 m²/s" in bad


def test_sensitivity_findings_are_not_paper_faithful_and_extensions_not_paper_claims():
    fs = findings(_results(good=True))
    other = [f for f in fs if not f.paper_faithful]
    names = {v.label for v in VARIANTS if v.name not in ("paper", "random")}
    assert {lab for lab in names if any(lab in f.claim for f in other)} == names
    assert len(_by_claim(fs, "No UAV comes within", faithful=False)) == 1  # the safe-loiter column
    ext = {f.claim.split(" (")[0].split(":")[0]: f.verdict for f in fs if not f.paper_claim}
    assert ext == {"The search MPC shrinks X̄ faster than random turns": "reproduced",
                   "A 400-step mission costs less CPU time than the paper's 2700 s": "reproduced",
                   "X̄'s regrowth is a limit of the planner, not of the geometry": "reproduced"}
    bad = {f.claim.split(" (")[0].split(":")[0]: f.verdict for f in findings(_results(good=False)) if not f.paper_claim}
    assert set(bad.values()) == {"not reproduced"}


def test_short_missions_are_not_comparable_at_steps_300_and_400():
    res = _results(good=True)
    short = Results(runs={k: [RunSummary(**{**r.__dict__, "xbar": r.xbar[:20], "x": r.x[:20]}) for r in v]
                          for k, v in res.runs.items()}, labels=res.labels, steps=20, sweep=SWEEP)
    fs = findings(short)
    for claim in ("X̄ is very close to empty", "φ(X)/φ(X0) is 0.035"):
        (f,) = _by_claim(fs, claim)
        assert f.verdict == "not comparable" and f.why == "the missions end at step 20" and f.rule and f.paper


def test_sensitivity_runs_are_the_first_seeds_of_the_paper_configuration():
    assert SENS_RUNS <= 100 and VARIANTS[0].name == "paper"
    assert len({v.name for v in VARIANTS}) == len(VARIANTS)


class _Est:
    def __init__(self, X):
        self.estimate = SimpleNamespace(X=X)


def _scan(boxes_xy, tids):
    dets = [SimpleNamespace(z=np.array(z, float), bound=np.array([5.0, 5.0])) for z in boxes_xy]
    return SimpleNamespace(detections=dets, truth_ids=np.array(tids, dtype=int),
                           extras={"observed_region": shapely.box(0, 0, 100, 100)})


def _mission(k, X, scans):
    return SimpleNamespace(k=k, movers=SimpleNamespace(is_target=np.array([True, False])),
                           last_scans=scans, estimators=[_Est(X)])


def test_decoy_provenance_counts_a_box_entering_x_and_its_erasure():
    tr = DecoyProvenance(steps=100, radius=1.39)
    X_with = shapely.box(40, 40, 60, 60)
    # step 1: the decoy (mover 1) is seen at (50, 50); a true target's box (mover 0) does not count
    tr.observe(_mission(1, X_with, [_scan([(50, 50), (20, 20)], [1, 0])]))
    tr.observe(_mission(2, X_with, [_scan([], [])]))
    tr.observe(_mission(3, shapely.box(0, 0, 10, 10), [_scan([], [])]))  # a later view erased it
    # step 80: seen again over ground proven free (not in X): a box, no episode
    tr.observe(_mission(80, shapely.Polygon(), [_scan([(50, 50)], [1])]))
    r = tr.result()
    assert r == DecoyEpisodes(started=1, judged=1, erased=1, durations=(2,), boxes=2, entered=1)


def test_decoy_provenance_censors_late_and_open_episodes():
    tr = DecoyProvenance(steps=100, radius=1.39)
    X = shapely.box(40, 40, 60, 60)
    tr.observe(_mission(10, X, [_scan([(50, 50)], [1])]))  # never erased: judged, not erased
    r = tr.result()
    assert (r.started, r.judged, r.erased) == (1, 1, 0)
    late = DecoyProvenance(steps=100, radius=1.39)
    late.observe(_mission(100 - CENSOR_STEPS + 1, X, [_scan([(50, 50)], [1])]))
    assert (late.result().started, late.result().judged) == (1, 0)


def _phys(good: bool) -> dict:
    n = 5
    return {"violations": np.zeros(n) if good else np.array([0, 1, 0, 0, 0.0]), "checks": np.full(n, 3200.0),
            "xbar_mid": np.full(n, 0.002) + 1e-4 * np.arange(n) if good else np.full(n, 0.7) + 1e-3 * np.arange(n),
            "decoy_seen": np.ones(n), "min_obs": np.full(n, 9.0) if good else np.array([9, 9, 4, 9, 9.0]),
            "collisions": np.zeros(n), "unsafe": np.zeros(n), "deviation_p95": np.full(n, 3.0)}


def test_physics_findings_meet_and_violate_their_rules():
    good, bad = physics_findings(_phys(True), True), physics_findings(_phys(False), True)
    assert [f.verdict for f in good] == ["reproduced", "reproduced", "not comparable", "reproduced"]
    assert [f.verdict for f in bad] == ["not reproduced", "not reproduced", "not comparable", "not reproduced"]
    assert all(f.rule and f.paper and not f.paper_faithful for f in good)
