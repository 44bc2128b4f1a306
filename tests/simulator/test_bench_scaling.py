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


@pytest.mark.parametrize("sumo", [False, True])
def test_the_sweep_warms_each_engine_with_a_discarded_run_first(monkeypatch, sumo):
    import simulator.bench.scaling as scaling
    import vehicles.sumo

    calls = []

    def fake_loop(raw):
        calls.append((raw["traffic"]["engine"], raw["traffic"]["cars"], len(raw["uavs"]), raw["sim"]["duration_s"]))
        return _row(1.0, sim_s=raw["sim"]["duration_s"], autonomy=0.1)

    monkeypatch.setattr(scaling, "loop_rtf", fake_loop)
    monkeypatch.setattr(vehicles.sumo, "sumo_available", lambda: sumo)
    rows = scaling.sweep(duration_s=15.0, uav_duration_s=10.0)
    warm = [("builtin", 0, 3, scaling.WARM_S)] + ([("sumo", 200, 3, scaling.WARM_S)] if sumo else [])
    assert calls[:len(warm)] == warm  # first, and not among the rows
    measured = calls[len(warm):]
    assert len(rows) == len(measured) == 4 + 2 * sumo + 3
    assert [(r["engine"], r["cars"], r["uavs"]) for r in rows] == [c[:3] for c in measured]
    assert all(c[3] == (10.0 if r["sweep"] == "uavs" else 15.0) for r, c in zip(rows, measured, strict=True))
