"""A multi-target estimator on the fake engine: its ``tracks`` rows and its identity and MOT metrics
(simulator.recording, simulator.summary), on a scripted tracker whose two tracks swap cars."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pytest

from autonomy.agent import Agent
from autonomy.diagnostics import HoldsTracks
from autonomy.sensing.measurement import Detection
from interfaces.state import TargetEstimate, TrackReport
from simulator.clock import Clock
from simulator.fake_engine import ScriptedCars, ScriptedUavs, fake_assembly
from simulator.record import RunRecorder
from simulator.runrecord import load_run
from simulator.slots import AgentSlot
from simulator.streams import STREAMS
from simulator.summary import MetricsTracker
from tests.simulator.fakes import HZ, LogEstimator, LogGuidance

CARS = np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0]])  # car "c0" (the designated target) and car "c1", standing
DIV = 3  # agent steps at ticks 3, 6, ... 36: t = 0.25 s ... 3 s, steps j = 0 ... 11
STEPS = 12
SWAP = 7  # from step 7 the tracker's tracks 1 and 2 sit on each other's car


class ScriptedTracker:
    """Steps 0-1: no track. Steps 2-6: track 1 (taken for the target) 2 m east of c0, track 2 3 m north of c1.
    From step 7 track 1 sits 2 m east of c1 and track 2 3 m north of c0 (a swap of identities the tracker does not
    see), plus a tentative track 3 far from both. The estimate returned is track 1's."""

    def __init__(self) -> None:
        self.j = -1
        self.reports: list[TrackReport] = []

    def step(self, t: float, detections: Sequence[Detection]) -> TargetEstimate | None:
        self.j += 1
        self.reports = []
        if self.j >= 2:
            one, two = (CARS[0], CARS[1]) if self.j < SWAP else (CARS[1], CARS[0])
            self.reports = [_report(1, t, one[:2] + [2.0, 0.0], 0.9, 1.5),
                            _report(2, t, two[:2] + [0.0, 3.0], 0.1, -2.0)]
            if self.j >= SWAP:
                self.reports.append(_report(3, t, np.array([50.0, 60.0]), 0.0, 0.0, confirmed=False))
        return self.reports[0].estimate if self.reports else None

    def track_reports(self) -> Sequence[TrackReport]:
        return list(self.reports)

    @property
    def target_track_id(self) -> int | None:
        return 1 if self.reports else None


def _report(tid: int, t: float, xy: np.ndarray, p: float, ev: float, confirmed: bool = True) -> TrackReport:
    P = np.diag([1.0 + tid, 2.0 + tid, 0.5, 0.5])
    P[0, 1] = P[1, 0] = 0.1 * tid
    est = TargetEstimate(t=t, p_W=np.asarray(xy, dtype=float), v_W=np.array([0.5, -0.5]), P=P)
    return TrackReport(track_id=tid, estimate=est, target_probability=p, evidence=ev, confirmed=confirmed)


def _run(tmp_path, ticks: int = DIV * STEPS, partial_at: Sequence[int] = (), tracker=None):
    uavs = ScriptedUavs(lambda k: np.array([[0.0, -50.0, 40.0], [10.0, -50.0, 40.0]]), HZ)
    cars = ScriptedCars(lambda k: CARS, HZ)
    tracker_est = ScriptedTracker() if tracker is None else tracker
    agents = [AgentSlot(uav=0, agent=Agent("a", tracker_est, LogGuidance()), divisor=DIV),
              AgentSlot(uav=1, agent=Agent("b", LogEstimator([], "b"), LogGuidance()), divisor=DIV)]
    recorder = RunRecorder(tmp_path, schemas=STREAMS)
    asm = fake_assembly(clock=Clock(physics_hz=HZ), recorder=recorder, uavs=uavs, uav_ids=["a", "b"], agents=agents,
                        methods=["none", "none"], cars=cars, car_ids=["c0", "c1"], record_div=DIV)
    metrics = MetricsTracker(seed=0, physics_hz=HZ, match_radius_m=20.0)
    metrics.attach(asm)
    partial = {}
    for tick in range(1, ticks + 1):
        asm.step(tick)
        metrics.observe(tick, asm)
        if tick in partial_at:
            partial[tick] = metrics.metrics(tick / HZ, 1.0, complete=False)
    recorder.close()
    return load_run(tmp_path), metrics.metrics(ticks / HZ, 1.0, complete=True), partial


def test_the_estimator_is_a_multi_target_tracker():
    assert isinstance(ScriptedTracker(), HoldsTracks)
    assert not isinstance(LogEstimator([], "x"), HoldsTracks)


def test_one_tracks_row_per_live_track_of_the_multi_target_uav_only(tmp_path):
    rec, _, _ = _run(tmp_path)
    tr = rec.streams["tracks"]
    assert tuple(tr) == STREAMS["tracks"].columns
    # steps 2-6: tracks 1, 2; steps 7-11: tracks 1, 2, 3 (tentative ones too); all from UAV 0
    ticks = [DIV * (j + 1) for j in range(2, STEPS) for _ in range(2 if j < SWAP else 3)]
    assert tr["tick"].tolist() == ticks and set(tr["uav"].tolist()) == {0}
    assert tr["t"] == pytest.approx(np.array(ticks) / HZ)
    assert tr["track"].tolist() == [1, 2] * (SWAP - 2) + [1, 2, 3] * (STEPS - SWAP)
    assert tr["is_target"].tolist() == [t == 1 for t in tr["track"].tolist()]
    assert tr["confirmed"].tolist() == [t != 3 for t in tr["track"].tolist()]
    first, after = slice(0, 2), slice(2 * (SWAP - 2), 2 * (SWAP - 2) + 3)
    assert tr["x"][first].tolist() == [2.0, 100.0] and tr["y"][first].tolist() == [0.0, 3.0]
    assert tr["x"][after].tolist() == [102.0, 0.0, 50.0] and tr["y"][after].tolist() == [0.0, 3.0, 60.0]
    assert tr["vx"][first].tolist() == [0.5, 0.5] and tr["vy"][first].tolist() == [-0.5, -0.5]
    assert tr["pxx"][first].tolist() == [2.0, 3.0] and tr["pyy"][first].tolist() == [3.0, 4.0]
    assert tr["pxy"][first] == pytest.approx([0.1, 0.2])
    assert tr["p_target"][first].tolist() == [0.9, 0.1] and tr["evidence"][first].tolist() == [1.5, -2.0]


def test_identity_metrics_of_the_believed_target_estimate(tmp_path):
    """Track 1's estimate is on c0 at steps 2-6 and on c1 (102 m from c0) at steps 7-11: 5 of 12 steps on the target,
    acquired at step 2 (0.5 s after step 0), one switch of car (c0 → c1), one loss never recovered. Position error
    2 m at steps 2-6 and 102 m at 7-11."""
    _, m, _ = _run(tmp_path)
    a = m["targets"]["c0"]["a"]
    assert a["estimate_fraction"] == pytest.approx(10 / 12)
    assert a["position_error_mean_m"] == pytest.approx((5 * 2.0 + 5 * 102.0) / 10)
    assert a["identity_fraction"] == pytest.approx(5 / 12)
    assert a["id_switches"] == 1 and a["losses"] == 1 and a["unrecovered_losses"] == 1
    assert a["time_to_acquire_s"] == pytest.approx(2 * DIV / HZ)
    assert a["time_to_reacquire_mean_s"] is None and a["time_to_reacquire_max_s"] is None
    b = m["targets"]["c0"]["b"]  # never an estimate
    assert b["estimate_fraction"] == 0.0 and b["identity_fraction"] == 0.0 and b["time_to_acquire_s"] is None


def test_mot_metrics_of_the_confirmed_tracks_against_every_car(tmp_path):
    """12 steps × 2 cars = 24 truth instances. Steps 0-1: 4 misses. Steps 2-6: c0-1 at 2 m, c1-2 at 3 m. At step 7
    both old pairs are 100 m apart: c0-2 and c1-1, two ID switches; the tentative track 3 is no false positive.
    MOTA = 1 − (4 + 0 + 2) / 24 = 0.75, MOTP = 2.5 m. IDF1: the best trajectory assignment gets IDTP = 10 of 24 truth
    and 20 track instances: 2·10 / (2·10 + 14 + 10) = 20/44. Each car matched at 10 of 12 steps (≥ 80 %): both mostly
    tracked. GOSPA (c = 20 m): (2 c²/2)^½ = 20 m at steps 0-1, (2² + 3²)^½ after."""
    _, m, _ = _run(tmp_path)
    mot = m["uavs"]["a"]["mot"]
    assert "mot" not in m["uavs"]["b"]
    assert mot["steps"] == 12 and mot["truth_instances"] == 24 and mot["matches"] == 20
    assert (mot["misses"], mot["false_positives"], mot["num_switches"]) == (4, 0, 2)
    assert mot["mota"] == pytest.approx(0.75) and mot["motp_m"] == pytest.approx(2.5)
    assert mot["idf1"] == pytest.approx(20 / 44)
    assert (mot["mostly_tracked"], mot["mostly_lost"]) == (2, 0)
    assert mot["gospa_mean_m"] == pytest.approx((2 * 20.0 + 10 * math.sqrt(13.0)) / 12)
    assert mot["match_radius_m"] == 20.0


def test_partial_metrics_are_safe_and_rescored_as_the_steps_grow(tmp_path):
    # steps done by tick: 3 → 1, 6 → 2 (< 4 · 1: kept), 12 → 4 (rescored), 24 → 8, 27 → 9 and 30 → 10 (< 4 · 4: kept)
    _, final, partial = _run(tmp_path, partial_at=(2, 3, 6, 12, 24, 27, 30))
    assert "targets" not in partial[2] and "mot" not in partial[2]["uavs"]["a"]  # before any agent step
    assert partial[3]["targets"]["c0"]["a"]["identity_fraction"] == 0.0
    assert partial[3]["uavs"]["a"]["mot"]["steps"] == 1 and partial[3]["uavs"]["a"]["mot"]["mota"] == 0.0
    assert [partial[k]["uavs"]["a"]["mot"]["steps"] for k in (6, 12, 24, 27, 30)] == [1, 4, 4, 4, 4]
    assert partial[24]["targets"]["c0"]["a"]["losses"] == 1  # step 7 (tick 24) already off the target
    assert final["uavs"]["a"]["mot"]["steps"] == 12 and final["targets"]["c0"]["a"]["identity_fraction"] == 5 / 12


def test_steps_without_a_track_write_no_rows_and_count_misses(tmp_path):
    rec, m, _ = _run(tmp_path, ticks=DIV * 2)  # only steps without any track
    assert "tracks" not in rec.streams
    assert m["uavs"]["a"]["mot"]["misses"] == 4


class SwitchingTracker(ScriptedTracker):
    """:class:`ScriptedTracker`'s tracks, but it takes track 2 for the target at steps 8-9, and from step 10 holds
    track 2 alone (track 1 ended) and takes none."""

    def step(self, t: float, detections: Sequence[Detection]) -> TargetEstimate | None:
        super().step(t, detections)
        if self.j >= 10:
            self.reports = [r for r in self.reports if r.track_id == 2]
        return None

    @property
    def target_track_id(self) -> int | None:
        if not self.reports or self.j >= 10:
            return None
        return 2 if self.j >= 8 else 1


def test_a_change_of_the_target_track_is_an_event(tmp_path):
    rec, m, _ = _run(tmp_path, tracker=SwitchingTracker())
    changes = [e for e in rec.events if e["type"] == "target_track_changed"]
    assert [(e["tick"], e["uav"], e["from_track"], e["to_track"], e["from_alive"]) for e in changes] == [
        (DIV * 3, 0, None, 1, False),  # acquired at step 2
        (DIV * 9, 0, 1, 2, True),  # step 8: another live track
        (DIV * 11, 0, 2, None, True)]  # step 10: none (track 2 still lives)
    assert changes[0]["p"] == 0.9 and (changes[0]["x"], changes[0]["y"]) == (2.0, 0.0)
    assert changes[1]["p"] == 0.1 and (changes[1]["x"], changes[1]["y"]) == (0.0, 3.0)  # track 2 on c0 since step 7
    assert changes[2]["p"] is None and changes[2]["x"] is None
    assert m["uavs"]["a"]["target_track_changes"] == 3 and "target_track_changes" not in m["uavs"]["b"]
    assert m["events"]["target_track_changed"] == 3
