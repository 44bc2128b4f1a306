"""The physics-floor benchmark: both measurements taken, the ratio made of them."""

import pytest

from simulator.bench.bench_floor import FloorMeasure, floor_records, measure_against_floor


def _measure(world_cpu: float, floor_cpu: float, world_wall: float = 4.0, floor_wall: float = 1.0) -> FloorMeasure:
    return FloorMeasure(sim_s=10.0, world_cpu_s=world_cpu, world_wall_s=world_wall, setup_wall_s=2.0,
                        floor_cpu_s=floor_cpu, floor_wall_s=floor_wall,
                        phases_wall_s={"setup": 2.0, "physics": 1.5, "autonomy": 0.5})


def test_ratio_is_world_rtf_over_floor_rtf():
    m = _measure(world_cpu=5.0, floor_cpu=2.0)
    assert m.world_cpu_rtf == 2.0 and m.floor_cpu_rtf == 5.0
    assert m.cpu_ratio == pytest.approx(0.4, rel=1e-15)
    assert m.wall_ratio == pytest.approx(0.25, rel=1e-15)
    assert m.loop_wall_ratio == pytest.approx(0.5, rel=1e-15)  # the floor's 1 s over the loop's 4 - 2 s
    assert m.ceiling_wall_ratio == pytest.approx(1.0 / 3.5, rel=1e-15)  # over the setup's 2 s and the step's 1.5 s


def test_a_measure_without_time_is_refused():
    with pytest.raises(ValueError, match=r"FloorMeasure.floor_cpu_s must be > 0 s, got 0.0"):
        _measure(world_cpu=5.0, floor_cpu=0.0)


def test_records_are_medians_of_the_per_repeat_ratios():
    runs = [_measure(5.0, 2.0), _measure(4.0, 2.0), _measure(10.0, 1.0)]  # ratios 0.4, 0.5, 0.1
    recs = {r.name: r for r in floor_records("w", runs)}
    assert sorted(recs) == ["w_cpu_rtf", "w_floor_cpu_rtf", "w_floor_loop_ratio_wall", "w_floor_ratio",
                            "w_floor_ratio_ceiling_wall", "w_floor_ratio_wall", "w_floor_wall_rtf", "w_wall_rtf"]
    head = recs["w_floor_ratio"]
    assert head.value == pytest.approx(0.4) and head.target == 0.5 and head.meets_target is False
    assert recs["w_floor_cpu_rtf"].value == 5.0  # median of 5, 5, 10
    assert recs["w_cpu_rtf"].value == 2.0  # median of 2, 2.5, 1


def test_a_tiny_worlds_ratio_is_made_of_its_run_and_its_floor():
    m = measure_against_floor("demo", duration_s=1.0, seed=3)
    assert m.sim_s == 1.0
    assert set(m.phases_wall_s) == {"setup", "vehicles", "physics", "sensors", "autonomy", "record", "other"}
    assert m.cpu_ratio == pytest.approx(m.floor_cpu_s / m.world_cpu_s, rel=1e-12)
    assert 0.0 < m.cpu_ratio <= 1.5
    assert 0.0 < m.wall_ratio <= 1.5
    assert m.wall_ratio < m.ceiling_wall_ratio  # the rest of the loop costs something
