"""Run metrics (simulator.summary) on a fake assembly: per-UAV entries follow each agent slot's ``uav``."""

from types import SimpleNamespace

from autonomy.fusion.hcmci_team import HcmciConfig
from autonomy.team.hcmci import HcmciConsensusTeam
from simulator.summary import MetricsTracker


def _slot(uav: int, divisor: int = 1) -> SimpleNamespace:
    return SimpleNamespace(uav=uav, divisor=divisor, agent=SimpleNamespace(guidance=None, fusion=None))


def _assembly(teams=(), **fields) -> SimpleNamespace:
    team_of = {u: team for team in teams for u in team.members}
    return SimpleNamespace(recording=SimpleNamespace(recorder=SimpleNamespace(event_counts={}), event_counts_by_uav={}),
                           teams=list(teams), team_of=team_of.get, channel=None, world_spec=None, quads=None, **fields)


def test_consensus_metrics_go_to_the_uav_of_the_agent_slot_not_its_position():
    # slots listed in another order than the UAVs; only "b" (UAV 1) is in the HCMCI team
    team = HcmciConsensusTeam([1], HcmciConfig())
    team.linked_steps[1] = 7
    team.active_links.extend([1, 1])
    team.fusion.steps = 2
    asm = _assembly(teams=[team], target_index=None, uav_ids=["a", "b"], agents=[_slot(1), _slot(0)], record_div=1)
    tracker = MetricsTracker(seed=0, physics_hz=240)
    tracker.attach(asm)
    out = tracker.metrics(1.0, 1.0, complete=True)
    uavs = out["uavs"]
    assert uavs["b"]["consensus_linked_steps"] == 7
    assert "consensus_linked_steps" not in uavs["a"]
    assert out["consensus"] == {"team_steps": 2, "active_links_mean": 1.0}


def test_errors_are_observed_at_every_agent_step_and_nowhere_else():
    """The tracker skips ticks where no agent is due and nothing is recorded (divisors 4 and 6, records every 10:
    it looks at even ticks only), and still scores every agent step."""
    import numpy as np

    from interfaces.state import TargetEstimate

    truth = SimpleNamespace(p_W=np.array([[10.0, 0.0, 0.5]]), v_W=np.zeros((1, 3)))
    asm = _assembly(target_index=0, uav_ids=["a", "b"], car_ids=["car"], agents=[_slot(0, 4), _slot(1, 6)],
                    record_div=10, cars=SimpleNamespace(state=truth),
                    latest_local={0: TargetEstimate(t=0.0, p_W=np.array([13.0, 4.0]), v_W=np.zeros(2)), 1: None})
    tracker = MetricsTracker(seed=0, physics_hz=240)
    tracker.attach(asm)
    for tick in range(1, 121):
        tracker.observe(tick, asm)
    targets = tracker.metrics(1.0, 1.0, complete=True)["targets"]["car"]
    assert tracker.errors[0].steps == 30 and tracker.errors[1].steps == 20
    assert targets["a"]["position_error_mean_m"] == 5.0 and targets["b"]["estimate_fraction"] == 0.0
