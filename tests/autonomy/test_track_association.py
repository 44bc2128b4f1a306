"""Team fusion among traffic: teammates' tracks are associated with one's own before fusing, and the team's target
is chosen with the teammates' class evidence."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.fusion.convex import state_vector_fusion
from autonomy.fusion.track_association import TeamTrackFusion, associate_tracks
from interfaces.state import TargetEstimate, TrackPicture, TrackReport

CHI2_2_999 = -2.0 * math.log(1e-3)  # χ²₂ quantile at 0.999


def _est(x, y, var=25.0, t=10.0) -> TargetEstimate:
    P = np.diag([var, var, 4.0, 4.0])
    return TargetEstimate(t=t, p_W=np.array([x, y]), v_W=np.zeros(2), P=P)


def _rep(k, x, y, p=0.0, evidence=0.0, var=25.0) -> TrackReport:
    return TrackReport(track_id=k, estimate=_est(x, y, var), target_probability=p, evidence=evidence)


def test_association_pairs_the_same_cars_and_leaves_far_ones_alone():
    own = [_est(0, 0), _est(100, 0), _est(300, 0)]
    other = [_est(103, 4), _est(-2, 1), _est(900, 0)]
    pairs = associate_tracks(own, other, CHI2_2_999)
    assert sorted(pairs) == [(0, 1), (1, 0)]
    # the gate: a difference d with P_a + P_b = 50 I is associated iff |d|²/50 <= χ²
    edge = math.sqrt(CHI2_2_999 * 50.0)
    assert associate_tracks([_est(0, 0)], [_est(edge * 0.99, 0)], CHI2_2_999) == [(0, 0)]
    assert associate_tracks([_est(0, 0)], [_est(edge * 1.01, 0)], CHI2_2_999) == []


def test_only_associated_tracks_fuse_into_the_target():
    fusion = TeamTrackFusion("convex", max_age_s=2.0, q=0.0)
    own = [_rep(1, 0, 0, p=0.9), _rep(2, 200, 0, p=0.05)]
    mate = TrackPicture(t=10.0, tracks=(_rep(5, 204, 0, p=0.0), _rep(6, 3, 2, p=0.8)), target_track_id=6)
    out = fusion.fuse(10.0, own[0].estimate, own, 1, [mate])
    assert out.own_track_id == 1 and out.fused_with == 1
    f = state_vector_fusion(np.r_[0.0, 0, 0, 0], own[0].estimate.P, np.r_[3.0, 2, 0, 0], mate.tracks[1].estimate.P)
    np.testing.assert_allclose(out.estimate.p_W, f.x[:2])


def test_the_team_target_is_the_linear_pool_of_the_members_beliefs():
    """Own belief: track 1 at 0.45, track 2 at 0.35; a teammate holds the car of track 2 at 0.95 and nothing on
    track 1's car: pooled (0.45 + 0) / 2 and (0.35 + 0.95) / 2 = 0.65, so track 2 is the team's target."""
    fusion = TeamTrackFusion("covariance_intersection", max_age_s=2.0, q=0.0)
    own = [_rep(1, 0, 0, p=0.45), _rep(2, 200, 0, p=0.35)]
    mate = TrackPicture(t=10.0, tracks=(_rep(9, 201, 1, p=0.95),), target_track_id=9)
    out = fusion.fuse(10.0, own[0].estimate, own, 1, [mate])
    assert out.own_track_id == 2
    assert out.probability == pytest.approx((0.35 + 0.95) / 2)
    assert fusion.disagreements == 1
    # a car only the teammate holds (its belief 0.8) takes one's own "in none of my tracks" (0.9) shared out as the
    # teammate does: (0.8 + 0.9 · 0.8) / 2 = 0.76, against "in no track" (0.9 · 0.2 + 0.2) / 2 = 0.19
    lone = TrackPicture(t=10.0, tracks=(_rep(4, 900, 0, p=0.8),), target_track_id=4)
    out = fusion.fuse(10.0, own[0].estimate, [_rep(1, 0, 0, p=0.1)], 1, [lone])
    assert out.own_track_id is None and out.probability == pytest.approx((0.8 + 0.9 * 0.8) / 2)
    np.testing.assert_allclose(out.estimate.p_W, [900, 0])


def test_stale_pictures_are_ignored_and_no_candidate_keeps_the_local_estimate():
    fusion = TeamTrackFusion("convex", max_age_s=2.0, q=0.0)
    own = [_rep(1, 0, 0, p=0.3)]
    old = TrackPicture(t=5.0, tracks=(_rep(3, 1, 1, p=0.9, evidence=5.0),), target_track_id=3)
    local = _est(50, 50)
    out = fusion.fuse(10.0, local, own, None, [old])
    assert out.estimate is local and out.fused_with == 0


def test_a_switch_margin_keeps_the_team_target_through_near_ties():
    """Own tracks 1 and 2 with a teammate's on each car: the team's probabilities (p_own + p_mate) / 2 swap their
    order by 0.02 from step to step. With no margin the choice follows every swap; with 0.1 it keeps track 2 until
    track 1 beats it by more than 0.1; a kept track that is gone is replaced by the most probable."""
    def pictures(p1, p2, m1, m2):
        own = [_rep(1, 0, 0, p=p1), _rep(2, 200, 0, p=p2)]
        return own, [TrackPicture(t=10.0, tracks=(_rep(7, 1, 0, p=m1), _rep(8, 201, 0, p=m2)), target_track_id=8)]

    steps = [(0.45, 0.47, 0.45, 0.47), (0.48, 0.46, 0.48, 0.46), (0.45, 0.47, 0.45, 0.47), (0.55, 0.40, 0.55, 0.40),
             (0.62, 0.30, 0.62, 0.30)]
    plain, sticky = (TeamTrackFusion("convex", max_age_s=2.0, q=0.0, switch_margin=m) for m in (0.0, 0.1))
    chosen = {id(f): [] for f in (plain, sticky)}
    for probs in steps:
        own, mates = pictures(*probs)
        for f in (plain, sticky):
            chosen[id(f)].append(f.fuse(10.0, own[0].estimate, own, None, mates).own_track_id)
    assert chosen[id(plain)] == [2, 1, 2, 1, 1]
    assert chosen[id(sticky)] == [2, 2, 2, 1, 1]  # 0.55 - 0.40 = 0.15 > 0.1 at the fourth step
    # the kept track gone: the most probable one
    own = [_rep(3, 400, 0, p=0.2), _rep(4, 600, 0, p=0.5)]
    assert sticky.fuse(10.0, own[0].estimate, own, None, []).own_track_id == 4
    # then 4 kept within the margin of 3, and given up beyond it
    assert sticky.fuse(10.0, own[0].estimate, [_rep(3, 400, 0, p=0.52), _rep(4, 600, 0, p=0.45)], None,
                       []).own_track_id == 4
    assert sticky.fuse(10.0, own[0].estimate, [_rep(3, 400, 0, p=0.58), _rep(4, 600, 0, p=0.40)], None,
                       []).own_track_id == 3
    with pytest.raises(ValueError, match="switch_margin"):
        TeamTrackFusion("convex", max_age_s=2.0, q=0.0, switch_margin=1.0)


class _Tracks:
    """A multi-target estimator that holds two tracks and believes track 1 is the target; it keeps the team's
    choice it is given (``team_target``), as the built-in tracker does."""

    def __init__(self) -> None:
        self.team_target = None

    def step(self, t, detections):
        return self.track_reports()[0].estimate

    def track_reports(self):
        return [_rep(1, 0, 0, p=0.45), _rep(2, 200, 0, p=0.35)]

    @property
    def target_track_id(self):
        return 1


def test_an_agent_among_traffic_hands_the_teams_target_to_its_tracker():
    """The teammate is sure of track 2's car: the pooled belief takes track 2, and the agent tells its tracker, which
    follows it from its next step on (its camera then looks at the car the team follows)."""
    from autonomy.agent import Agent
    from autonomy.fusion.track_fusion import TrackFusion, TrackFusionConfig
    from interfaces.setpoints import VelocitySetpoint
    from interfaces.state import OwnState

    class Hover:
        def command(self, own, target, teammates, t):
            return VelocitySetpoint(v_W=np.zeros(3), yaw=0.0)

    est = _Tracks()
    agent = Agent("a", est, Hover(), fusion=TrackFusion(TrackFusionConfig(method="covariance_intersection", q=0.0)))
    own = OwnState(t=10.0, p_W=np.zeros(3), v_W=np.zeros(3), yaw=0.0)
    mate = TrackPicture(t=10.0, tracks=(_rep(9, 201, 1, p=0.95),), target_track_id=9)
    out = agent.step(10.0, own, [], [mate])
    assert est.team_target == 2 and out.estimate.p_W[0] > 100.0 and out.local_estimate.p_W[0] == 0.0
    lone = TrackPicture(t=10.0, tracks=(_rep(4, 900, 0, p=0.1),), target_track_id=4)
    agent.step(10.0, own, [], [lone])  # "in no track" is likelier for the team (0.54 against 0.225 and 0.06):
    assert est.team_target is None     # no team choice, the tracker's own belief stands
