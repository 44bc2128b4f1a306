"""``skytrack reproduce``: reports with the paper's numbers beside ours and a computed verdict per finding."""

import re

import numpy as np
import pytest

from simulator.cli import main
from simulator.reproduce.report import Finding, MeanCI, Table, mean_ci

PHYSICS_WORLDS = {"001": "relay_tracking", "003": "formation_imm"}
VERDICT = re.compile(r"\| \*\*(reproduced|not reproduced|inconclusive|not comparable)\*\* \|")


def test_mean_ci_is_students_t_interval():
    ci = mean_ci([1.0, 2.0, 3.0, 4.0])
    # t_{0.975, 3} = 3.182446; s = 1.290994; half = t s / 2
    assert ci.mean == pytest.approx(2.5) and ci.half == pytest.approx(3.182446 * 1.290994 / 2, rel=1e-6)
    assert mean_ci([5.0]) == MeanCI(mean=5.0, half=None, n=1)
    assert mean_ci([float("nan"), 1.0, 3.0]).n == 2


def test_mean_ci_of_equal_values_is_exact():
    # ten copies of 0.95: numpy's mean is off in the last bit and the sample deviation came out as ~1e-16
    assert np.mean([0.95] * 10) != 0.95
    ci = mean_ci([0.95] * 10)
    assert ci == MeanCI(mean=0.95, half=0.0, n=10) and ci.text() == "0.95 ± 0"


def test_report_parts_validate():
    with pytest.raises(ValueError, match="verdict must be one of"):
        Finding(claim="x", verdict="maybe", why="")
    with pytest.raises(ValueError, match="has 1 cells for 2 columns"):
        Table(title="t", columns=("a", "b"), rows=(("1",),))


@pytest.mark.parametrize("paper,runs", [("000", 2), ("001", 2), ("002", 1), ("003", 2), ("004", 2)])
def test_quick_reproduction_writes_a_report(tmp_path, paper, runs):
    code = main(["reproduce", paper, "--runs", str(runs), "--quick", "--quiet", "--out", str(tmp_path),
                 "--workers", "1"])
    assert code == 0
    text = (tmp_path / paper / "report.md").read_text()
    assert "Quick mode" in text and "## Findings" in text
    assert len(VERDICT.findall(text)) >= 3
    for png in re.findall(r"\]\(([^)]+\.png)\)", text):
        assert (tmp_path / paper / png).stat().st_size > 5000
    index = (tmp_path / "report.md").read_text()
    assert f"[{paper}/report.md]({paper}/report.md)" in index
    if paper in PHYSICS_WORLDS:  # the cross-check on quadrotors ran its campaigns and judged them
        assert f"`worlds/{PHYSICS_WORLDS[paper]}.yaml`" in text and "On quadrotors" in text
        assert "Provenance: all " in text and "physics runs by this source" in text  # the runs say their code


def test_unknown_paper_and_bad_runs_are_input_errors(tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        main(["reproduce", "007", "--out", str(tmp_path)])
    assert info.value.code == 2
    assert main(["reproduce", "003", "--runs", "0", "--out", str(tmp_path)]) == 2
    assert "--runs must be >= 1" in capsys.readouterr().err
