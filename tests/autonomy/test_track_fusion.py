"""Track-to-track fusion of shared, aged estimates."""

import numpy as np
import pytest

from autonomy.fusion.track_fusion import TrackFusion, TrackFusionConfig, predict_estimate
from interfaces.state import TargetEstimate


def est(t, p, v, var_p, var_v):
    return TargetEstimate(t=t, p_W=np.array(p, float), v_W=np.array(v, float),
                          P=np.diag([var_p, var_p, var_v, var_v]))


def test_prediction_is_constant_velocity_with_white_acceleration_noise():
    e = est(1.0, [10, 20], [2, -1], 4.0, 1.0)
    out = predict_estimate(e, 3.0, q=0.5)
    assert np.allclose(out.p_W, [14, 18]) and out.t == 3.0
    dt = 2.0
    # per axis: F P Fᵀ + q [[dt³/3, dt²/2], [dt²/2, dt]]
    assert out.P[0, 0] == pytest.approx(4 + dt ** 2 * 1 + 0.5 * dt ** 3 / 3)
    assert out.P[0, 2] == pytest.approx(dt * 1 + 0.5 * dt ** 2 / 2)
    assert out.P[2, 2] == pytest.approx(1 + 0.5 * dt)


def test_convex_fusion_of_independent_estimates_is_the_information_weighted_mean():
    fusion = TrackFusion(TrackFusionConfig(method="convex", q=0.0))
    a = est(5.0, [0, 0], [1, 0], 1.0, 1.0)
    b = est(5.0, [3, 0], [1, 0], 2.0, 1.0)
    f = fusion.fuse(5.0, a, [b])
    assert f.p_W[0] == pytest.approx(3 * (1 / 2) / (1 + 1 / 2))  # (x_a/σa² + x_b/σb²)/(1/σa² + 1/σb²)
    assert f.P[0, 0] == pytest.approx(1 / (1 + 1 / 2))
    assert fusion.fusions == 1


def test_stale_or_missing_estimates():
    fusion = TrackFusion(TrackFusionConfig(max_age_s=1.0))
    own = est(10.0, [0, 0], [0, 0], 1.0, 1.0)
    stale = est(8.0, [5, 5], [0, 0], 1.0, 1.0)
    assert fusion.fuse(10.0, own, [stale]).p_W.tolist() == [0, 0]
    fresh = est(9.5, [5, 5], [0, 0], 1.0, 1.0)
    only = fusion.fuse(10.0, None, [fresh])  # no own track yet: the teammate's, aged to now
    assert only.t == 10.0 and only.P[0, 0] > 1.0
    assert fusion.fuse(10.0, None, []) is None


def test_covariance_intersection_never_claims_more_than_the_best_input():
    fusion = TrackFusion(TrackFusionConfig(method="covariance_intersection", q=0.0))
    a = est(0.0, [0, 0], [0, 0], 1.0, 1.0)
    f = fusion.fuse(0.0, a, [a])  # the same track twice (fully correlated): CI must not halve the covariance
    assert np.trace(f.P) == pytest.approx(np.trace(a.P), rel=1e-6)


def test_config_validation():
    with pytest.raises(ValueError, match="max_age_s"):
        TrackFusionConfig(max_age_s=0)


def test_predicting_many_estimates_at_once_gives_each_ones_numbers_bit_for_bit():
    from autonomy.fusion.track_fusion import predict_estimate, predict_estimates
    from interfaces.state import TargetEstimate

    rng = np.random.default_rng(5)
    ests = []
    for k in range(40):
        a = rng.normal(size=(4, 4))
        P = a @ a.T + np.eye(4)
        t = float(rng.uniform(0, 10)) if k % 2 else float(rng.choice([9.5, 10.0, 11.25]))  # some share a time
        ests.append(TargetEstimate(t=t, p_W=rng.normal(size=2) * 100, v_W=rng.normal(size=2) * 10,
                                   P=P if k % 7 else None))
    ests.append(TargetEstimate(t=12.5, p_W=np.zeros(2), v_W=np.ones(2), P=np.eye(4)))  # dt = 0: itself
    batch = predict_estimates(ests, 12.5, 0.7)
    for e, b in zip(ests, batch, strict=True):
        one = predict_estimate(e, 12.5, 0.7)
        assert b.t == one.t and np.array_equal(b.p_W, one.p_W) and np.array_equal(b.v_W, one.v_W)
        assert (b.P is None and one.P is None) or np.array_equal(b.P, one.P)
    assert batch[-1] is ests[-1]


def test_predicted_estimates_give_each_ones_numbers_and_arrays_without_making_every_estimate():
    from autonomy.fusion.track_fusion import PredictedEstimates, predict_estimate
    from interfaces.state import TargetEstimate

    rng = np.random.default_rng(6)
    ests = []
    for _ in range(12):
        a = rng.normal(size=(4, 4))
        ests.append(TargetEstimate(t=float(rng.uniform(0, 10)), p_W=rng.normal(size=2) * 100,
                                   v_W=rng.normal(size=2) * 10, P=a @ a.T + np.eye(4)))
    a = rng.normal(size=(6, 6))
    ests.append(TargetEstimate(t=3.0, p_W=np.ones(3), v_W=np.ones(3), P=a @ a.T + np.eye(6)))  # 3-D: one at a time
    ests.append(TargetEstimate(t=12.5, p_W=np.zeros(2), v_W=np.ones(2), P=np.eye(4)))  # already at t
    pred = PredictedEstimates(ests, 12.5, 0.7)
    assert len(pred._made) == 2  # only the two predicted one at a time are made up front
    ones = [predict_estimate(e, 12.5, 0.7) for e in ests]
    assert np.array_equal(pred.xy, np.array([o.p_W[:2] for o in ones]))
    assert np.array_equal(pred.P_xy, np.array([o.P[:2, :2] for o in ones]))
    for k in (4, -1, 0):
        b, one = pred[k], ones[k]
        assert b.t == one.t and np.array_equal(b.p_W, one.p_W) and np.array_equal(b.P, one.P)
    assert pred[-1] is ests[-1] and pred[4] is pred[4]
    with pytest.raises(IndexError):
        pred[len(ests)]
    with pytest.raises(ValueError, match="no covariance"):
        _ = PredictedEstimates([TargetEstimate(t=0.0, p_W=np.zeros(2), v_W=np.zeros(2))], 1.0, 0.7).P_xy
