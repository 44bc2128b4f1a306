"""The loop's real-time factor and the ceiling made of its phases (simulator.bench.scaling)."""

import pytest
import yaml

from simulator.bench.scaling import PHASES, ceiling_rtf, loop_rtf
from worlds.loader import shipped_worlds


def _row(wall_s: float, sim_s: float = 10.0, **phase_s: float) -> dict:
    row = {"sim_s": sim_s, "wall_s": wall_s, "rtf": sim_s / wall_s, **dict.fromkeys(PHASES, 0.0)}
    row.update({p: s / sim_s for p, s in phase_s.items()})  # loop_rtf gives phases per simulated second
    return row


def test_the_ceiling_is_the_loop_without_the_free_phases():
    row = _row(8.0, autonomy=3.0, sensors=1.0, physics=2.0)
    assert ceiling_rtf(row) == pytest.approx(10.0 / 5.0, rel=1e-15)  # 8 s less the agents' 3 s
    assert ceiling_rtf(row, ("autonomy", "sensors")) == pytest.approx(10.0 / 4.0, rel=1e-15)
    assert ceiling_rtf(row, ()) == pytest.approx(row["rtf"], rel=1e-15)  # nothing free: the run itself
    assert ceiling_rtf(_row(8.0)) == pytest.approx(row["rtf"], rel=1e-15)  # agents that cost nothing: no headroom


def test_a_ceiling_of_no_loop_or_of_an_unknown_phase_is_refused():
    with pytest.raises(ValueError, match=r"ceiling_rtf: \['agents'\] are not phases of a run"):
        ceiling_rtf(_row(8.0, autonomy=3.0), ("agents",))
    with pytest.raises(ValueError, match=r"take 8.000 s of a loop of 8.000 s wall"):
        ceiling_rtf(_row(8.0, autonomy=8.0))


def test_a_tiny_worlds_ceiling_lies_above_its_run():
    raw = yaml.safe_load(shipped_worlds()["demo"].read_text(encoding="utf-8"))
    raw["sim"]["duration_s"] = 1.0
    row = loop_rtf(raw)
    assert row["sim_s"] == 1.0 and row["wall_s"] > 0 and row["rtf"] == pytest.approx(1.0 / row["wall_s"])
    assert row["autonomy"] > 0.0
    assert ceiling_rtf(row) > row["rtf"]  # the agents cost something, so freeing them raises the figure
