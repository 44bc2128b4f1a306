"""Base-station fusion without a prior, its information-form prediction, and the UAV side of the scheme
(:class:`InformationReporter`: a local EIF whose scan information is kept to send)."""

import numpy as np
import pytest

from autonomy.estimation.measurements import Measurement
from autonomy.estimation.models import ConstantVelocity, Singer
from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig
from autonomy.fusion.base_station import BaseStationFusion, InformationReporter, information_contribution
from autonomy.sensing.measurement import Detection


def _fix(xy, t, sigma, sensor):
    """A linear position measurement (kind box) of ``xy`` with standard deviation ``sigma`` per axis."""
    return Measurement(z=np.asarray(xy, float), R=np.eye(2) * sigma**2, t_meas=t, kind="box", sensor_id=sensor)


def test_a_base_without_prior_knows_nothing_until_two_scan_times_then_fits_the_line():
    model = ConstantVelocity(q=0.0)  # no process noise: the estimate is the weighted least-squares line
    base = BaseStationFusion(model)
    assert not base.valid and base.estimate(0.0) is None
    scans = {1.0: [((1.0, 2.0), 0.5, 0), ((1.4, 1.8), 1.0, 1)], 3.0: [((5.2, 0.9), 0.7, 0)]}
    x_any = np.zeros(4)  # linear measurements: the contribution does not depend on the linearisation point
    base.fuse([information_contribution(x_any, _fix(s[0], 1.0, s[1], s[2]), model.layout) for s in scans[1.0]])
    assert not base.valid  # position only: no velocity information yet
    base.fuse([information_contribution(x_any, _fix(s[0], 3.0, s[1], s[2]), model.layout) for s in scans[3.0]])
    assert base.valid and base.t == 3.0 and base.n_received == 3
    # closed form: unknowns (p(3), v) per axis, p(t_k) = p(3) − (3 − t_k) v, weights 1/σ²
    A, b, W = [], [], []
    for t, fixes in scans.items():
        for xy, sigma, _ in fixes:
            for axis in range(2):
                row = np.zeros(4)
                row[axis], row[2 + axis] = 1.0, -(3.0 - t)
                A.append(row)
                b.append(xy[axis])
                W.append(sigma**-2)
    A, b, W = np.array(A), np.array(b), np.diag(W)
    sol = np.linalg.solve(A.T @ W @ A, A.T @ W @ b)  # (x, y, vx, vy) at t = 3
    est = base.estimate(3.0)
    np.testing.assert_allclose(np.r_[est.p_W, est.v_W], sol, atol=1e-9)
    np.testing.assert_allclose(est.P, np.linalg.inv(A.T @ W @ A), atol=1e-9)
    later = base.estimate(5.0)  # predicted along the line, the filter untouched
    np.testing.assert_allclose(later.p_W, sol[:2] + 2.0 * sol[2:], atol=1e-9)
    assert base.t == 3.0 and later.t == 5.0


@pytest.mark.parametrize("dt", [0.5, 2.0])
def test_information_form_prediction_equals_the_covariance_form(dt):
    rng = np.random.default_rng(3)
    model = ConstantVelocity(q=0.3)
    L = rng.normal(size=(4, 4))
    P0 = L @ L.T + np.eye(4)
    x0 = rng.normal(size=4)
    base = BaseStationFusion(model, x0, P0)
    base.predict(dt)
    F, Q = model.matrices(dt)
    P = F @ P0 @ F.T + Q
    np.testing.assert_allclose(base.P, P, rtol=1e-10)
    np.testing.assert_allclose(base.x, F @ x0, rtol=1e-10, atol=1e-12)


def test_with_process_noise_no_prior_is_the_limit_of_a_vague_prior():
    # the information-form prediction of a singular Y (no prior, position information only) against the covariance
    # form of a KF whose prior is 10⁸ m² wide: the same estimate to within the prior's leftover information
    model = ConstantVelocity(q=0.3)
    rng = np.random.default_rng(11)
    base = BaseStationFusion(model)
    vague = BaseStationFusion(model, np.zeros(4), np.eye(4) * 1e8)
    for t in (1.0, 2.5, 3.0, 4.5):
        fixes = [_fix(rng.normal(size=2) * 3 + t, t, 1.0 + j, j) for j in range(2)]
        for b in (base, vague):
            b.fuse([information_contribution(np.zeros(4), m, model.layout) for m in fixes])
    np.testing.assert_allclose(base.x, vague.x, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(base.P, vague.P, rtol=1e-5, atol=1e-6)


def test_a_base_without_prior_needs_a_linear_model_and_both_or_neither_prior_term():
    with pytest.raises(ValueError, match="linear motion model"):
        BaseStationFusion(_NonLinear())
    with pytest.raises(ValueError, match="both x0 and P0"):
        BaseStationFusion(ConstantVelocity(q=1.0), x0=np.zeros(4))


class _NonLinear(Singer):
    is_linear = False

    def __init__(self) -> None:
        super().__init__(alpha=0.5, sigma_a=1.0, dim=2)


# --- the UAV's side -----------------------------------------------------------------------------------------------

def _radar(p_target, p_sensor, t, rng, sigma=(0.4, 0.05)):
    d = np.asarray(p_target, float) - np.asarray(p_sensor, float)
    z = np.array([np.linalg.norm(d), np.arctan2(d[1], d[0])]) + rng.normal(size=2) * np.asarray(sigma)
    return Detection(z=z, R=np.diag(np.square(sigma)), t_meas=t, t_arrival=t, sensor_id="radar",
                     p_sensor_W=np.asarray(p_sensor, float), kind="radar")


CFG = TrackerConfig(filter="scif", model="cv", q=0.01)


def test_the_reporter_tracks_exactly_like_the_tracker_and_keeps_each_scans_information():
    rng = np.random.default_rng(7)
    plain, reporter = SingleTargetTracker(CFG), InformationReporter(SingleTargetTracker(CFG))
    sent = 0
    for k in range(12):
        t = float(k)
        scan = [_radar((2.0 * t, -0.7 * t, 0.0), (60.0 - 5 * t, -40.0, 10.0), t, rng)]
        prior = None if reporter.tracker.filter is None else reporter.tracker.filter.information_state.Y.copy()
        ref, est = plain.step(t, scan), reporter.step(t, scan)
        assert (ref is None) == (est is None)
        if ref is None:
            assert reporter.contribution is None  # no track yet: nothing to send
            continue
        np.testing.assert_allclose(est.p_W, ref.p_W, atol=1e-9)
        np.testing.assert_allclose(est.P, ref.P, atol=1e-9)
        c = reporter.contribution
        if prior is None:  # the scan that confirmed the track initiated it: no contribution against a prior
            assert c is None
            continue
        sent += 1
        assert c.t_meas == t
        # the contribution is what the local update added to the prior predicted to t (the position block of a
        # range-azimuth scan: rank 2, no velocity information)
        assert np.linalg.matrix_rank(c.info_matrix, tol=1e-9 * np.abs(c.info_matrix).max()) == 2
        model = reporter.tracker.model
        F, Q = model.matrices(1.0)
        prior_t = np.linalg.inv(F @ np.linalg.inv(prior) @ F.T + Q)
        np.testing.assert_allclose(reporter.tracker.filter.information_state.Y, prior_t + c.info_matrix,
                                   rtol=1e-7, atol=1e-9)
    assert sent >= 9


def test_the_reporter_needs_the_information_filter():
    with pytest.raises(TypeError, match="scif"):
        InformationReporter(SingleTargetTracker(TrackerConfig(filter="ekf")))
