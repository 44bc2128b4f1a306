"""The reproductions' job store: results survive an interruption, come back equal, and untrusted lines are dropped."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import pytest

from simulator.reproduce.report import ReproContext
from simulator.reproduce.stored import JobStore, StoreError, decode, encode


@dataclass(frozen=True, kw_only=True)
class Inner:
    counts: tuple[int, ...]
    share: float


@dataclass(frozen=True, kw_only=True)
class Summary:
    series: np.ndarray
    flags: np.ndarray
    inner: Inner
    table: dict
    note: str = ""


def _summary(x: float) -> Summary:
    return Summary(series=np.array([[x, math.nan], [math.inf, -0.1]]), flags=np.array([True, False]),
                   inner=Inner(counts=(1, 2, 3), share=1 / 3), table={(1, "a"): [x, None], "b": -math.inf}, note="ü")


def _equal(a: Summary, b: Summary) -> bool:
    return (np.array_equal(a.series, b.series, equal_nan=True) and a.series.dtype == b.series.dtype
            and np.array_equal(a.flags, b.flags) and a.flags.dtype == b.flags.dtype and a.inner == b.inner
            and a.note == b.note and a.table.keys() == b.table.keys() and a.table[(1, "a")] == b.table[(1, "a")]
            and a.table["b"] == b.table["b"])


def test_a_result_comes_back_equal_through_strict_json() -> None:
    s = _summary(0.1 + 0.2)
    text = json.dumps(encode(s), allow_nan=False)  # strict JSON: non-finite floats are tagged, not NaN literals
    back = decode(json.loads(text), (Summary, Inner))
    assert isinstance(back, Summary) and isinstance(back.inner.counts, tuple)
    assert _equal(back, s)
    assert back.series[0, 0] == 0.1 + 0.2  # bit-exact, not rounded


def test_decoding_builds_only_the_named_dataclasses_and_checks_their_fields() -> None:
    data = encode(_summary(1.0))
    with pytest.raises(ValueError, match="not one this reproduction reads"):
        decode(data, (Summary,))  # Inner not allowed
    bad = json.loads(json.dumps(data))
    bad["fields"]["extra"] = 1
    with pytest.raises(ValueError, match="has fields"):
        decode(bad, (Summary, Inner))
    with pytest.raises(ValueError, match="not allowed"):
        decode({"__ndarray__": "|O", "shape": [1], "data": [1]})
    with pytest.raises(ValueError, match="has 2 values"):
        decode({"__ndarray__": "<f8", "shape": [3], "data": [1.0, 2.0]})
    with pytest.raises(ValueError, match="unexpected stored"):
        decode({"__tuple__": [1], "smuggled": 2})
    with pytest.raises(TypeError):
        encode(object())


def test_the_store_keeps_results_across_processes_and_drops_what_it_cannot_trust(tmp_path) -> None:
    with JobStore(tmp_path, (Summary, Inner)) as st:
        st.put(("a", 1), _summary(1.0))
        st.put(("a", 2), _summary(2.0))
        code = st.code
        with pytest.raises(StoreError, match="in use by another reproduction"):
            JobStore(tmp_path, (Summary, Inner))
    path = tmp_path / "results.jsonl"
    good = path.read_text(encoding="utf-8").splitlines()
    other = json.loads(good[1])
    other["code"] = "0" * 16
    other["job"] = encode(("a", 3))
    path.write_text("\n".join([good[0], "garbage{", json.dumps(other), good[1], '{"code": "' + code]),
                    encoding="utf-8")  # the last line torn, as by a kill mid-write
    with JobStore(tmp_path, (Summary, Inner)) as st:
        assert len(st) == 2 and st.stale == 1
        assert ("a", 1) in st and ("a", 3) not in st
        assert _equal(st.get(("a", 2)), _summary(2.0))
    rejected = (tmp_path / "results.rejected.jsonl").read_text(encoding="utf-8").splitlines()
    assert len(rejected) == 3  # the garbage, the other code's line and the torn line, kept apart for inspection
    assert path.read_text(encoding="utf-8").splitlines() == good


_CALLS: list[int] = []


def _square(j: int) -> tuple[int, float]:
    _CALLS.append(j)
    if j == 99:
        raise RuntimeError("interrupted")
    return j, float(j) ** 2


def test_an_interrupted_map_resumes_with_only_the_unfinished_jobs(tmp_path) -> None:
    ctx = ReproContext(out_dir=tmp_path, runs=1, workers=1)
    _CALLS.clear()
    with pytest.raises(RuntimeError, match="interrupted"):
        ctx.map(_square, [0, 1, 2, 99, 3], store="squares")
    assert _CALLS == [0, 1, 2, 99]
    _CALLS.clear()
    assert ctx.map(_square, [0, 1, 2, 3, 4], store="squares") == [(j, float(j) ** 2) for j in range(5)]
    assert _CALLS == [3, 4]  # 0–2 came from the store
    _CALLS.clear()
    assert ctx.map(_square, [4, 0], store="squares") == [(4, 16.0), (0, 0.0)]
    assert _CALLS == []
    quick = ReproContext(out_dir=tmp_path, runs=1, workers=1, quick=True)
    assert quick.map(_square, [0], store="squares") == [(0, 0.0)] and _CALLS == [0]  # quick mode never reads it


def test_a_pool_stores_every_result_as_it_finishes(tmp_path) -> None:
    ctx = ReproContext(out_dir=tmp_path, runs=1, workers=2)
    assert ctx.map(_square, [5, 6, 7], store="squares") == [(5, 25.0), (6, 36.0), (7, 49.0)]
    from simulator.reproduce.stored import code_fingerprint

    with JobStore(tmp_path / "campaigns" / "squares", code=code_fingerprint(_square.__module__)) as st:
        assert len(st) == 3 and st.get(6) == (6, 36.0)


def test_a_resumed_report_says_how_many_jobs_it_took_from_the_store(tmp_path) -> None:
    from simulator.reproduce.report import PaperReport, paper_markdown

    ctx = ReproContext(out_dir=tmp_path, runs=1, workers=1)
    ctx.map(_square, [1, 2], store="squares")
    fresh = paper_markdown(PaperReport(paper="x", title="t", runs=1, setup="s", reused=dict(ctx.reused)), "cmd")
    assert "Resumed" not in fresh
    again = ReproContext(out_dir=tmp_path, runs=1, workers=1)
    again.map(_square, [1, 2, 3], store="squares")
    md = paper_markdown(PaperReport(paper="x", title="t", runs=1, setup="s", reused=dict(again.reused)), "cmd")
    assert "Resumed: jobs taken from results stored by an earlier run of the same code (squares: 2 of 3)" in md


def _same(a: object, b: object) -> bool:
    """Deep equality with NaN equal to NaN (results hold NaN figures)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype
                and np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if hasattr(a, "__dataclass_fields__"):
        return type(a) is type(b) and all(_same(getattr(a, f), getattr(b, f)) for f in a.__dataclass_fields__)
    return a == b


def _paper_jobs():  # (job function, one short job, the types the paper's reproduce() hands its store)
    from simulator.kinematic.consensus import ConsensusLoopResult
    from simulator.kinematic.formation import FormationLoopResult
    from simulator.reproduce import paper_000_loop, paper_001, paper_003_runs, paper_004_runs, road_replay
    from simulator.reproduce.paper_001_loop import LoopResult
    from simulator.reproduce.paper_004_decoys import DecoyEpisodes

    yield "000", paper_000_loop.run_job, paper_000_loop.jobs_for([7], 12, 4)[0], (paper_000_loop.RunSummary,
                                                                               ConsensusLoopResult)
    yield "001", paper_001._one, paper_001._Job("1", "A", 7, 5), (paper_001._Job, LoopResult)
    yield "002", road_replay.run_job, road_replay.ReplayJob("curve", seed=7, duration=20.0,
                                                            filters=road_replay.PAPER_FILTERS), ()
    yield "003", paper_003_runs._one, (1, paper_003_runs.variants(1)[0], 7, True), (FormationLoopResult,)
    yield "004", paper_004_runs.run_one, ("paper", 7, True), (paper_004_runs.RunSummary, DecoyEpisodes)


@pytest.mark.parametrize("paper", ["000", "001", "002", "003", "004"])
def test_each_papers_results_come_back_from_the_store_equal(paper: str, tmp_path) -> None:
    fn, job, types = next((f, j, t) for p, f, j, t in _paper_jobs() if p == paper)
    result = fn(job)
    with JobStore(tmp_path, types) as st:
        st.put(job, result)
    with JobStore(tmp_path, types) as st:
        assert job in st
        assert _same(st.get(job), result)


def test_the_code_fingerprint_covers_what_a_job_imports_and_not_how_reports_are_judged() -> None:
    from simulator.provenance import ROOT
    from simulator.reproduce.stored import _closure, code_fingerprint

    files = {str(p.relative_to(ROOT)) for p in _closure("simulator.reproduce.paper_004_runs")}
    # imported through the mission, the planner and a function-level import of the run's on_step hook
    assert {"simulator/kinematic/search_mission.py", "autonomy/guidance/search/planner.py",
            "autonomy/estimation/setmem/polygons.py", "autonomy/__init__.py"} <= files
    assert "simulator/reproduce/rules.py" not in files and "simulator/reproduce/paper_004_findings.py" not in files
    a, b = (code_fingerprint(f"simulator.reproduce.{m}") for m in ("paper_004_runs", "paper_000_loop"))
    assert a != b
