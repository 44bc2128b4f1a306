"""The tick on the fake engine (no PyBullet): the order of its phases, which component runs at which tick, the
inbox under perfect comms and over a radio (latency, outages), the sharing of detections and estimates."""

from __future__ import annotations

import json

import numpy as np
import pytest

from autonomy.agent import Agent
from autonomy.fusion.track_fusion import TrackFusion, TrackFusionConfig
from autonomy.sensing.channel import Channel, ChannelConfig, LinkOutage
from simulator.clock import Clock
from simulator.fake_engine import FakePhysics, ScriptedUavs, fake_assembly
from simulator.record import RunRecorder
from simulator.runrecord import load_run
from simulator.slots import AgentSlot, SensorSlot
from simulator.streams import STREAMS
from tests.simulator.fakes import HZ, LogEstimator, LogGuidance, LogSensor

IDS = ["a", "b"]


def _positions(tick: int) -> np.ndarray:
    """Two UAVs 10 m apart, flying east at 1.2 m/s (0.1 m a tick)."""
    return np.array([[0.1 * tick, 0.0, 50.0], [0.1 * tick, 10.0, 50.0]])


def _run(tmp_path, ticks: int, *, methods=("none", "none"), sensor_div=2, agent_div=3, latency_s=0.0,
         channel=None, comms=None, outages=(), fusion=None, record_div=4):
    log: list = []
    uavs = ScriptedUavs(_positions, HZ, log)
    estimators = [LogEstimator(log, u) for u in IDS]
    laws = [LogGuidance() for _ in IDS]
    sensors = [SensorSlot(uav=i, sensor=LogSensor(f"{u}/s", log, latency_s), divisor=sensor_div,
                          rng=np.random.default_rng(i), name=f"{u}/s") for i, u in enumerate(IDS)]
    agents = [AgentSlot(uav=i, agent=Agent(u, estimators[i], laws[i], fusion=fusion), divisor=agent_div)
              for i, u in enumerate(IDS)]
    recorder = RunRecorder(tmp_path, schemas=STREAMS)
    asm = fake_assembly(clock=Clock(physics_hz=HZ), recorder=recorder, uavs=uavs, uav_ids=IDS, agents=agents,
                        methods=list(methods), sensors=sensors, channel=channel, comms=comms, outages=list(outages),
                        physics=FakePhysics(log), record_div=record_div)
    for tick in range(1, ticks + 1):
        asm.step(tick)
    recorder.close()
    return asm, log, estimators, laws, uavs


def test_phases_run_in_the_order_of_the_design_and_each_component_at_its_rate(tmp_path):
    asm, log, est, laws, uavs = _run(tmp_path, 12)
    assert log[:3] == [("uavs.actuation", 1), ("physics", 1), ("uavs.after_step", 1)]  # tick 1: nothing due
    at6 = [e for e in log if e[1] == 6]
    assert at6 == [("uavs.actuation", 6), ("physics", 6), ("uavs.after_step", 6), ("sensor a/s", 6),
                   ("sensor b/s", 6), ("estimate a", 6), ("uavs.command", 6), ("estimate b", 6),
                   ("uavs.command", 6)]
    assert [k for name, k in log if name == "sensor a/s"] == [2, 4, 6, 8, 10, 12]
    assert [k for name, k in log if name == "estimate b"] == [3, 6, 9, 12]
    assert [(k, i) for k, i, _ in uavs.commands] == [(k, i) for k in (3, 6, 9, 12) for i in (0, 1)]
    rec = load_run(tmp_path)
    assert rec.streams["uav_truth"]["tick"].tolist() == [4, 4, 8, 8, 12, 12]
    assert rec.streams["uav_truth"]["x"].tolist() == pytest.approx([0.4, 0.4, 0.8, 0.8, 1.2, 1.2])
    assert rec.streams["estimates"]["tick"].tolist() == [3, 3, 6, 6, 9, 9, 12, 12]
    assert len(rec.streams["detections"]["tick"]) == 12
    assert "fused_estimates" not in rec.streams and "measurement_sharing" not in rec.streams
    assert set(rec.streams) == {"uav_truth", "estimates", "commands", "detections"} <= set(STREAMS)


def test_an_agent_takes_the_detections_that_have_arrived_by_its_step(tmp_path):
    """Scans every 2 ticks arriving 1 tick later; agent steps every 3 ticks: a scan taken at the step's tick has not
    arrived yet and waits for the next step."""
    _, _, est, _, _ = _run(tmp_path, 12, latency_s=1 / HZ)
    assert est[0].steps == [(3, [("a/s", 2)]), (6, [("a/s", 4)]), (9, [("a/s", 6), ("a/s", 8)]),
                            (12, [("a/s", 10)])]


def test_perfect_comms_give_true_teammate_states_at_once(tmp_path):
    _, _, _, laws, _ = _run(tmp_path, 6)
    assert [(k, mates) for k, mates, _ in laws[1].calls] == [(3, [(0, 3)]), (6, [(0, 6)])]


def _radio(latency_s=0.0, outages=()) -> Channel:
    """A radio that delivers every packet (huge transmit power) after ``latency_s``."""
    cfg = ChannelConfig(transmit_power_dbm=400.0, block_by_buildings=False, latency_s=latency_s,
                        outages=tuple(outages))
    return Channel(cfg, HZ, np.random.default_rng(0))


def test_a_radio_delivers_teammate_states_after_its_latency_and_none_during_an_outage(tmp_path):
    outage = LinkOutage(node_a="a", node_b="b", start_s=4 / HZ, end_s=7 / HZ)  # ticks 4, 5, 6 down
    _, _, _, laws, _ = _run(tmp_path, 12, agent_div=1, channel=_radio(2 / HZ, [outage]))
    heard = {k: mates for k, mates, _ in laws[1].calls}
    assert heard[1] == [] and heard[2] == []
    assert heard[3] == [(0, 1)] and heard[4] == [(0, 2)] and heard[5] == [(0, 3)]  # sent 2 ticks before
    assert heard[6] == [(0, 3)] and heard[8] == [(0, 3)]  # sent at ticks 4, 5, 6: lost; the last heard stays
    assert heard[9] == [(0, 7)] and heard[12] == [(0, 10)]


def test_shared_detections_reach_the_teammates_outside_scheduled_outages(tmp_path):
    """Fusion method measurements under perfect comms: each scan goes to the teammate at once, except while a
    scheduled outage holds the link down (ticks 4 to 7); the outage is logged as events."""
    _, _, est, _, _ = _run(tmp_path, 12, methods=("measurements", "measurements"), outages=[("a", "b", 4, 8)])
    got = [d for _, dets in est[1].steps for d in dets]
    assert [k for s, k in got if s == "a/s"] == [2, 8, 10, 12]
    assert [k for s, k in got if s == "b/s"] == [2, 4, 6, 8, 10, 12]
    rec = load_run(tmp_path)
    share = rec.streams["measurement_sharing"]
    assert share["uav"].tolist() == [0, 1] * 4
    assert share["received"].tolist()[-2:] == [4, 4] and share["mates_used"].tolist()[-2:] == [4, 4]
    events = [json.loads(line) for line in (tmp_path / "events.jsonl").read_text().splitlines()]
    assert [(e["type"], e["tick"]) for e in events] == [("link_outage_start", 4), ("link_outage_end", 8)]


def test_track_fusion_shares_local_estimates_and_records_the_fused_ones(tmp_path):
    fusion = TrackFusion(TrackFusionConfig(method="convex"))
    asm, _, _, laws, _ = _run(tmp_path, 6, methods=("convex", "convex"), fusion=fusion)
    rec = load_run(tmp_path)
    assert rec.streams["fused_estimates"]["tick"].tolist() == [3, 3, 6, 6]
    # at tick 6 UAV b fuses its own estimate (y = 10) with a's of this tick (y = 0): equal covariances, the middle
    _, _, target = laws[1].calls[-1]
    assert target.p_W[1] == pytest.approx(5.0)
    assert asm.latest_local[1].p_W[1] == pytest.approx(10.0)
