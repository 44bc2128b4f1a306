"""Team protocols (autonomy.team) on a fake context: what each one shares, when it runs its team-level work, and
that the HCMCI protocol is exactly the HCMCI team step it wraps."""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pytest

from autonomy.agent import Agent
from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig
from autonomy.fusion.hcmci_team import HcmciConfig, HcmciTeam, pair_adjacency
from autonomy.fusion.track_fusion import TrackFusion, TrackFusionConfig
from interfaces.setpoints import VelocitySetpoint
from interfaces.state import OwnState, TargetEstimate
from autonomy.team.base_station import BaseStationTeam
from autonomy.team.hcmci import HcmciConsensusTeam, is_information_tracker
from autonomy.team.independent import IndependentTeam, MeasurementSharingTeam, TrackFusionTeam
from autonomy.team.set_fusion import SetFusionTeam
from tests.autonomy.test_hcmci_team import _radar

CFG = TrackerConfig(filter="scif", model="singer", singer_alpha=0.6, singer_sigma_a=0.67)


@dataclass
class Ctx:
    """A :class:`~autonomy.team.base.TeamContext` with scripted links; it keeps which links were asked for."""

    t: float
    tick: int
    links: np.ndarray
    asked: list[list[int]] = field(default_factory=list)

    def own_state(self, uav: int) -> OwnState:
        return OwnState(t=self.t, p_W=np.array([10.0 * uav, 0.0, 50.0]), v_W=np.zeros(3), yaw=0.0)

    def links_up(self, uavs: Sequence[int]) -> np.ndarray:
        self.asked.append(list(uavs))
        return self.links[np.ix_(uavs, uavs)].copy()


@dataclass
class Member:
    uav: int
    agent: Agent


class Hold:
    """Guidance that keeps the target estimates it was given."""

    def __init__(self) -> None:
        self.targets: list[TargetEstimate | None] = []

    def command(self, own, target, teammates, t):
        self.targets.append(target)
        return VelocitySetpoint(v_W=np.zeros(3), yaw=0.0)


class Fixed:
    """Estimator that always gives one estimate at y = ``y``."""

    def __init__(self, y: float) -> None:
        self.y = y

    def step(self, t, detections):
        return TargetEstimate(t=t, p_W=np.array([0.0, self.y]), v_W=np.zeros(2), P=np.eye(4))


def _shared(t: float) -> list[TargetEstimate]:
    return [TargetEstimate(t=t, p_W=np.array([0.0, 20.0]), v_W=np.zeros(2), P=np.eye(4))]


def test_independent_members_use_no_shared_estimate_and_track_fusion_members_fuse_them():
    ctx = Ctx(t=1.0, tick=240, links=np.ones((2, 2), bool))
    alone = Member(0, Agent("a", Fixed(0.0), Hold()))
    fusing = Member(1, Agent("b", Fixed(0.0), Hold(), fusion=TrackFusion(TrackFusionConfig())))
    out_alone = IndependentTeam([0]).step([alone], ctx)[0](ctx.own_state(0), [], _shared(1.0))
    out_fused = TrackFusionTeam([1]).step([fusing], ctx)[1](ctx.own_state(1), [], _shared(1.0))
    assert out_alone.estimate.p_W[1] == 0.0
    assert out_fused.estimate.p_W[1] == pytest.approx(10.0) and out_fused.local_estimate.p_W[1] == 0.0
    assert ctx.asked == []  # no team-level work, no links drawn


def test_what_each_protocol_shares_is_declared():
    assert TrackFusionTeam([0]).shares_estimates and not IndependentTeam([0]).shares_estimates
    assert MeasurementSharingTeam([0]).takes_detections and not TrackFusionTeam([0]).takes_detections
    assert not SetFusionTeam({}, set()).point_estimates and IndependentTeam([0]).point_estimates


def test_the_hcmci_protocol_is_the_hcmci_team_step_over_the_links_of_the_context():
    sensors = [(30.0, -20.0, 40.0), (-25.0, 15.0, 40.0), (10.0, 35.0, 50.0)]
    rngs = [np.random.default_rng(10 + j) for j in range(3)]
    scans = [[[_radar((1.0 * k, 0.5 * k, 0.0), p, 0.5 * k, rng)] for k in range(8)]
             for p, rng in zip(sensors, rngs, strict=True)]
    links = pair_adjacency(3, [(0, 1), (1, 2)])
    cfg = HcmciConfig(rounds=2, gain="safe")
    members = [Member(j, Agent(f"u{j}", SingleTargetTracker(CFG), Hold())) for j in range(3)]
    reference = [copy.deepcopy(m.agent.estimator) for m in members]
    team, ref_team = HcmciConsensusTeam([0, 1, 2], cfg), HcmciTeam(cfg)
    assert all(is_information_tracker(m.agent.estimator) for m in members)
    for k in range(8):
        t = 0.5 * k
        for m, s in zip(members, scans, strict=True):
            m.agent.receive(s[k])
        ctx = Ctx(t=t, tick=120 * k, links=links)
        decide = team.step(members, ctx)
        expected, step = ref_team.step(t, reference, [s[k] for s in scans], links)
        assert ctx.asked == [[0, 1, 2]]
        for m, e in zip(members, expected, strict=True):
            out = decide[m.uav](ctx.own_state(m.uav), [], _shared(t))  # shared estimates are not used
            assert (out.estimate is None) == (e is None) and out.used_detections == 1
            if e is not None:
                assert np.array_equal(out.estimate.p_W, e.p_W) and np.array_equal(out.estimate.P, e.P)
    assert team.steps == 8
    assert set(team.active_links) == {0, 2} and team.active_links[-1] == 2  # the path's two links once all track
    tracked = [k for k in range(8) if team.active_links[k]]
    assert team.linked_steps == {0: len(tracked), 1: len(tracked), 2: len(tracked)}
    assert team.summary()["team_steps"] == 8


def test_an_hcmci_team_with_no_member_due_does_nothing():
    team = HcmciConsensusTeam([0, 1], HcmciConfig())
    ctx = Ctx(t=0.0, tick=0, links=np.zeros((2, 2), bool))
    assert team.step([], ctx) == {} and ctx.asked == [] and team.steps == 0


def test_a_set_team_hands_each_observed_region_to_its_members_tracker_only():
    class Trk:
        def __init__(self) -> None:
            self.regions = []

        def observe(self, region):
            self.regions.append(region)

    a, b = Trk(), Trk()
    team = SetFusionTeam({0: a, 2: b}, fusing={0})
    team.on_scan(0, 1.0, 0.25, {"observed_region": "R0"})
    team.on_scan(1, 1.0, 0.25, {"observed_region": "R1"})  # not a member
    team.on_scan(2, 1.5, 0.0, {})  # no region
    assert team.members == (0, 2) and b.regions == []
    (r,) = a.regions
    assert (r.t_meas, r.t_arrival, r.region) == (1.0, 1.25, "R0")


def test_the_base_station_steps_once_after_the_members_with_those_due():
    calls = []

    class Base:
        def step(self, tick, t, due):
            calls.append((tick, t, list(due)))

    team = BaseStationTeam({1: object(), 3: object()})
    ctx = Ctx(t=2.0, tick=480, links=np.zeros((4, 4), bool))
    team.end_step([], ctx)
    team.base = Base()
    team.end_step([], ctx)
    team.end_step([Member(3, None)], ctx)
    assert calls == [(480, 2.0, [3])]
