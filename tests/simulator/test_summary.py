"""Run metrics (simulator.summary) on a fake assembly: per-UAV entries follow each agent slot's ``uav``."""

from types import SimpleNamespace

from simulator.summary import MetricsTracker


def _slot(uav: int, hcmci: bool, divisor: int = 1) -> SimpleNamespace:
    return SimpleNamespace(uav=uav, divisor=divisor, hcmci=hcmci, search=False,
                           agent=SimpleNamespace(guidance=None, fusion=None))


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


def test_errors_are_observed_at_every_agent_step_and_nowhere_else():
    """The tracker skips ticks where no agent is due and nothing is recorded (divisors 4 and 6, records every 10:
    it looks at even ticks only), and still scores every agent step."""
    import numpy as np

    from interfaces.state import TargetEstimate

    truth = SimpleNamespace(p_W=np.array([[10.0, 0.0, 0.5]]), v_W=np.zeros((1, 3)))
    asm = SimpleNamespace(recorder=SimpleNamespace(event_counts={}), target_index=0, uav_ids=["a", "b"],
                          car_ids=["car"], event_counts_by_uav={}, agents=[_slot(0, False, 4), _slot(1, False, 6)],
                          channel=None, world_spec=None, quads=None, record_div=10, cars=SimpleNamespace(state=truth),
                          latest_local={0: TargetEstimate(t=0.0, p_W=np.array([13.0, 4.0]), v_W=np.zeros(2)),
                                        1: None})
    tracker = MetricsTracker(seed=0, physics_hz=240)
    tracker.attach(asm)
    for tick in range(1, 121):
        tracker.observe(tick, asm)
    targets = tracker.metrics(1.0, 1.0, complete=True)["targets"]["car"]
    assert tracker.errors[0].steps == 30 and tracker.errors[1].steps == 20
    assert targets["a"]["position_error_mean_m"] == 5.0 and targets["b"]["estimate_fraction"] == 0.0
