"""Run metrics (simulator.summary) on a fake assembly: per-UAV entries follow each agent slot's ``uav``."""

from types import SimpleNamespace

from simulator.summary import MetricsTracker


def _slot(uav: int, hcmci: bool) -> SimpleNamespace:
    return SimpleNamespace(uav=uav, divisor=1, hcmci=hcmci, agent=SimpleNamespace(guidance=None, fusion=None))


def test_consensus_metrics_go_to_the_uav_of_the_agent_slot_not_its_position():
    # slots listed in another order than the UAVs; only "b" (UAV 1) is in the HCMCI team
    asm = SimpleNamespace(recorder=SimpleNamespace(event_counts={}), target_index=None, uav_ids=["a", "b"],
                          event_counts_by_uav={}, agents=[_slot(1, True), _slot(0, False)],
                          consensus_linked_steps={1: 7}, consensus_links=[1, 1], hcmci=SimpleNamespace(steps=2),
                          channel=None, world_spec=None, quads=None, record_div=1)
    tracker = MetricsTracker(seed=0, physics_hz=240)
    tracker.attach(asm)
    uavs = tracker.metrics(1.0, 1.0, complete=True)["uavs"]
    assert uavs["b"]["consensus_linked_steps"] == 7
    assert "consensus_linked_steps" not in uavs["a"]
