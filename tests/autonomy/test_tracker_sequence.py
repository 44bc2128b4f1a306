"""The composed tracker makes exactly what the monolithic tracker made of a recorded sequence.

The digests below were recorded with the single-class ``SingleTargetTracker`` and ``RoadConstrainedTracker`` that
preceded :mod:`autonomy.estimation.tracking` (every estimate's bytes, the road held and the counters,
:func:`tests.autonomy.tracker_sequence.digest`); like the golden records they hold on one machine. On a machine
whose digests differ (another CPU rounds differently), what the trackers make is held instead to the summaries in
``tracker_sequence_values.json`` (:mod:`tests.numeric_record`: estimates to a relative 1e-6, which steps had one,
the roads held and the counters exactly), written by ``python -m tests.autonomy.test_tracker_sequence`` on a machine
where the digests held or, where none is at hand, from the same code on another. The sequence has initiation from
bearings, radars with clutter and boxes, a loss after coasting, a restart after divergence and a car leaving the road.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from autonomy.estimation.road.config import RoadFilterConfig
from autonomy.estimation.road.tracker import RoadConstrainedTracker, RoadTrackerConfig
from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig
from tests.autonomy.tracker_sequence import digest, record, road_network
from tests.numeric_record import differences

VALUES_FILE = Path(__file__).with_name("tracker_sequence_values.json")

CASES = {
    "ekf_cv": {},
    "ukf_singer_3fix": {"filter": "ukf", "model": "singer", "confirm_fixes": 3},
    "ckf_no_prior": {"filter": "ckf", "initial_speed_sigma": None, "max_missed_scans": 2},
    "imm_stacked": {"filter": "imm", "q": 0.5, "stack_scans": True},
    "ekf_stacked": {"stack_scans": True, "lost_after_s": 5.0},
    "scif_info": {"filter": "scif", "model": "singer", "singer_alpha": 0.6, "singer_sigma_a": 0.67},
}
RECORDED = {
    ("ekf_cv", 0): "2e2e2b12aa4f46a49913",
    ("ukf_singer_3fix", 0): "b7e13f5fd336d8b22c0e",
    ("ckf_no_prior", 0): "eec886a28ef65ec0f8a0",
    ("imm_stacked", 0): "3e6a93c6a9925c6bc30c",
    ("ekf_stacked", 0): "c04fd4f6ea1197bb195e",
    ("scif_info", 0): "2b181f681872810523a3",
    ("road_maekf", 0): "d341dddc9fa114699d19",
    ("road_ecukf", 0): "e75420cfc3a96e835292",
    ("ekf_cv", 1): "c4be822a05e91a8b3e0c",
    ("ukf_singer_3fix", 1): "5e367236756b3e0812c7",
    ("ckf_no_prior", 1): "2fdcd4245defe8d67794",
    ("imm_stacked", 1): "94ef0f4fb9d90acb5c67",
    ("ekf_stacked", 1): "b08ec1f36479a7040291",
    ("scif_info", 1): "9b0b09a4f110abe1f453",
    ("road_maekf", 1): "664a9610a1aa51b26abc",
    ("road_ecukf", 1): "a6cde7a9758a4078b462",
}


def _tracker(case: str):
    if case.startswith("road_"):
        variant = case.removeprefix("road_")
        return RoadConstrainedTracker(RoadTrackerConfig(road=RoadFilterConfig(variant=variant)), road_network())
    return SingleTargetTracker(TrackerConfig(**CASES[case]))


def _check(case: str, seed: int) -> None:
    got, values = record(_tracker(case), seed, information=case.endswith("info"))
    if got == RECORDED[(case, seed)]:
        return
    want = json.loads(VALUES_FILE.read_text(encoding="utf-8"))[f"{case}/{seed}"]
    differs = differences(want, values)
    assert not differs, f"{case} seed {seed}: digest {got} is not the recorded one and these differ: {differs}"


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("case", sorted(CASES))
def test_tracker_reproduces_the_recorded_sequence(case, seed):
    _check(case, seed)


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("variant", ["maekf", "ecukf"])
def test_road_tracker_reproduces_the_recorded_sequence(variant, seed):
    _check(f"road_{variant}", seed)


def test_the_sequence_exercises_loss_divergence_and_every_sensor():
    tracker = SingleTargetTracker(TrackerConfig())
    digest(tracker, 0)
    assert tracker.initiations == 3 and tracker.dropped_diverged == 1  # started, lost in the gap, diverged at 36 s
    assert set(tracker.used_by_sensor) == {"uav1/camera", "uav2/bearing", "uav1/radar", "uav2/radar", "uav3/box"}
    assert tracker.gated_out > 0


def main() -> int:
    """Write ``tracker_sequence_values.json`` from what the trackers make here."""
    out = {f"{case}/{seed}": record(_tracker(case), seed, information=case.endswith("info"))[1]
           for case, seed in sorted(RECORDED)}
    VALUES_FILE.write_text(json.dumps(out, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
