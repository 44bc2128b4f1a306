"""The tracker's parts, each alone, against closed-form answers: the χ² gate, the nearest-neighbour associator, the
deleters, the fix-confirming initiator and the position fixes; and the composed tracker's list of tracks."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from autonomy.estimation.ekf import EKF
from autonomy.estimation.models import ConstantVelocity
from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig
from autonomy.estimation.tracking.associator import NearestNeighbourAssociator
from autonomy.estimation.tracking.deleter import MissedScansDeleter, UpdateTimeDeleter
from autonomy.estimation.tracking.fixes import PositionFixer, triangulate
from autonomy.estimation.tracking.gate import ChiSquareGate, PredictedNis
from autonomy.estimation.tracking.initiator import FixConfirmingInitiator
from autonomy.estimation.tracking.track import Track
from autonomy.sensing.measurement import Detection

CV = ConstantVelocity(q=0.5)  # layout (x, vx, y, vy)


def box(xy, t=0.0, R=None, sensor="box") -> Detection:
    R = np.eye(2) if R is None else np.asarray(R, float)
    return Detection(z=np.asarray(xy, float), R=R, t_meas=t, t_arrival=t, sensor_id=sensor,
                     p_sensor_W=np.array([0.0, 0.0, 100.0]), kind="box")


def bearing(az, p_xy, t=0.0, sigma=0.01, sensor="cam") -> Detection:
    return Detection(z=np.array([az]), R=np.array([[sigma**2]]), t_meas=t, t_arrival=t, sensor_id=sensor,
                     p_sensor_W=np.array([*p_xy, 50.0]), kind="bearing")


def track_at(p_xy, P_pos, v=(0.0, 0.0), t=0.0) -> Track:
    x = np.array([p_xy[0], v[0], p_xy[1], v[1]], float)
    P = np.zeros((4, 4))
    P[np.ix_([0, 2], [0, 2])] = P_pos
    P[1, 1] = P[3, 3] = 4.0
    return Track(EKF(CV, x, P, t), t)


# --- gate ---------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("p", [0.9, 0.99, 0.999])
def test_gate_thresholds_are_the_chi_square_quantiles(p):
    gate = ChiSquareGate(p)
    assert gate.threshold(2) == pytest.approx(-2.0 * np.log(1.0 - p), rel=1e-12)  # χ²₂ is exponential
    assert gate.threshold(1) == pytest.approx(stats.norm.ppf(0.5 + p / 2) ** 2, rel=1e-10)
    assert gate.threshold(3) == pytest.approx(stats.chi2.ppf(p, 3), rel=1e-10)


def test_gate_accepts_exactly_the_points_inside_the_chi_square_ellipse():
    """A box detection 1 s after the track: S = H (F P Fᵀ + Q) Hᵀ + R per axis, closed form for the CV model."""
    gate, nis = ChiSquareGate(0.99), PredictedNis(CV, target_height=0.0)
    P_pos = np.array([[30.0, 12.0], [12.0, 10.0]])
    tr = track_at((100.0, -50.0), P_pos, v=(5.0, 2.0))
    R = np.diag([4.0, 1.0])
    dt = 1.0
    # predicted position covariance: P_pos + dt² P_vel + q dt³/3 (no position-velocity cross terms in the prior)
    S = P_pos + dt**2 * 4.0 * np.eye(2) + CV.q * dt**3 / 3.0 * np.eye(2) + R
    centre = np.array([105.0, -48.0])
    gamma = -2.0 * np.log(1.0 - 0.99)
    L = np.linalg.cholesky(S)
    for theta in np.linspace(0.0, 2 * np.pi, 24, endpoint=False):
        u = np.array([np.cos(theta), np.sin(theta)])
        for s, inside in ((0.995, True), (1.005, False)):
            z = centre + s * np.sqrt(gamma) * (L @ u)
            d = box(z, t=dt, R=R)
            value = nis(tr.filter, d)
            assert value == pytest.approx(s**2 * gamma, rel=1e-9)
            assert gate.accepts(value, 2) is inside
    assert tr.filter.t == 0.0  # the distance predicts a copy, never the track


def test_gate_rejects_a_bad_probability():
    with pytest.raises(ValueError, match="probability"):
        ChiSquareGate(1.0)


# --- associator ---------------------------------------------------------------------------------------------------

def test_associator_takes_the_nearest_in_mahalanobis_not_euclidean_distance():
    tr = track_at((0.0, 0.0), np.diag([100.0, 1.0]))
    along, across = box([8.0, 0.0], R=np.eye(2) * 1e-6), box([0.0, 3.0], R=np.eye(2) * 1e-6)
    assoc = NearestNeighbourAssociator(ChiSquareGate(0.999), PredictedNis(CV, 0.0))
    (a,) = assoc.associate([tr], [across, along])
    assert a.detections == (along,) and a.gated_out == 0  # NIS 0.64 against 9, though 8 m > 3 m


def test_associator_takes_one_detection_per_sensor_and_counts_the_sensors_that_had_none():
    tr = track_at((0.0, 0.0), np.eye(2) * 4.0)
    near_a, far_a = box([1.0, 0.0], sensor="a"), box([3.0, 0.0], sensor="a")
    near_b = box([0.0, -1.0], sensor="b")
    out_c1, out_c2 = box([500.0, 0.0], sensor="c"), box([0.0, 400.0], sensor="c")
    assoc = NearestNeighbourAssociator(ChiSquareGate(0.999), PredictedNis(CV, 0.0))
    (a,) = assoc.associate([tr], [far_a, near_b, out_c1, near_a, out_c2])
    assert a.detections == (near_a, near_b) and a.gated_out == 2


def test_associator_answers_every_track():
    left, right = track_at((-50.0, 0.0), np.eye(2)), track_at((50.0, 0.0), np.eye(2))
    dl, dr = box([-49.0, 0.5]), box([51.0, -0.5])
    assoc = NearestNeighbourAssociator(ChiSquareGate(0.999), PredictedNis(CV, 0.0))
    a, b = assoc.associate([left, right], [dr, dl])
    assert (a.track, a.detections, b.track, b.detections) == (left, (dl,), right, (dr,))


# --- deleters -----------------------------------------------------------------------------------------------------

def test_update_time_deleter_drops_a_track_after_exactly_the_coasting_time():
    tr = track_at((0.0, 0.0), np.eye(2), t=2.0)
    d = UpdateTimeDeleter(10.0)
    assert not d.deletes(tr, 12.0) and d.deletes(tr, 12.0 + 1e-9)
    with pytest.raises(ValueError, match="lost_after_s"):
        UpdateTimeDeleter(0.0)


def test_missed_scans_deleter_counts_scans():
    tr = track_at((0.0, 0.0), np.eye(2))
    d = MissedScansDeleter(3)
    tr.missed = 2
    assert not d.deletes(tr, 0.0)
    tr.missed = 3
    assert d.deletes(tr, 0.0)
    with pytest.raises(ValueError, match="max_missed_scans"):
        MissedScansDeleter(0)


def test_tracker_drops_its_track_after_lost_after_s_of_coasting():
    trk = SingleTargetTracker(TrackerConfig(lost_after_s=4.0))
    trk.step(0.0, [box([0.0, 0.0], 0.0)])
    assert trk.step(0.5, [box([5.0, 0.0], 0.5)]) is not None and len(trk.tracks) == 1
    assert trk.step(4.5, []) is not None  # 4 s after the last update: still coasting
    assert trk.step(4.5 + 1e-6, []) is None and trk.tracks == []


# --- position fixes and the initiator -----------------------------------------------------------------------------

def test_crossing_bearings_fix_their_intersection():
    dets = [bearing(np.pi / 4, (0.0, 0.0), sensor="a"), bearing(3 * np.pi / 4, (100.0, 0.0), sensor="b")]
    meas, xy, P = triangulate(dets, np.deg2rad(10.0))
    np.testing.assert_allclose(xy, [50.0, 50.0], atol=1e-9)
    # perpendicular lines at range r = 50√2: each bearing's σ·r across its own line
    np.testing.assert_allclose(np.linalg.eigvalsh(P), [(0.01 * 50 * np.sqrt(2)) ** 2] * 2, rtol=1e-9)
    assert meas.parts == tuple(dets)
    assert triangulate([dets[0], bearing(np.pi / 4 + 0.1, (100.0, 0.0))], np.deg2rad(10.0)) is None  # shallow
    assert triangulate([bearing(-3 * np.pi / 4, (0.0, 0.0)), dets[1]], np.deg2rad(10.0)) is None  # behind
    fixer = PositionFixer(0.0, None)
    assert fixer.fixes(dets) == [] and not fixer.fixes_position(dets)  # without stacking bearings never fix
    assert PositionFixer(0.0, np.deg2rad(10.0)).fixes_position(dets)


def _initiator(**kw) -> tuple[FixConfirmingInitiator, list]:
    made = []

    def filters(x0, P0, t0):
        made.append((x0, P0, t0))
        return EKF(CV, x0, P0, t0)

    args = {"max_target_speed": 20.0, "tentative_window_s": 3.0, "confirm_fixes": 2, "max_target_accel": 4.0,
            "initial_speed_sigma": None, **kw}
    return FixConfirmingInitiator(fixer=PositionFixer(0.0, None), filters=filters, layout=CV.layout, **args), made


def test_two_fixes_within_the_speed_bound_confirm_a_track_at_the_newer_fix_with_the_pair_velocity():
    init, made = _initiator()
    sigma, dt = 2.0, 0.5
    R = np.eye(2) * sigma**2
    assert init.initiate([box([0.0, 0.0], 0.0, R)]) == []
    (tr,) = init.initiate([box([6.0, 8.0], dt, R)])
    x0, P0, t0 = made[0]
    assert t0 == dt and tr.last_update_t == dt and tr.missed == 0
    np.testing.assert_allclose(x0, [6.0, 12.0, 8.0, 16.0])
    np.testing.assert_allclose(np.diag(P0), [sigma**2 + 1e-6, 2 * sigma**2 / dt**2 + 1e-6] * 2)


@pytest.mark.parametrize(("excess", "confirms"), [(-0.01, True), (0.01, False)])
def test_the_confirming_gate_is_max_speed_times_dt_plus_three_sigma(excess, confirms):
    init, _ = _initiator()
    sigma, dt = 2.0, 0.5
    R = np.eye(2) * sigma**2
    reach = 20.0 * dt + 3.0 * np.sqrt(2.0) * sigma  # 3σ of the difference of two fixes
    init.initiate([box([0.0, 0.0], 0.0, R)])
    assert bool(init.initiate([box([reach + excess, 0.0], dt, R)])) is confirms


def test_a_tentative_fix_expires_after_the_window_and_reset_forgets_it():
    init, _ = _initiator(tentative_window_s=3.0)
    init.initiate([box([0.0, 0.0], 0.0)])
    assert init.initiate([box([1.0, 0.0], 3.5)]) == []  # partner too late; this fix is now tentative
    init.reset()
    assert init.initiate([box([2.0, 0.0], 4.0)]) == []
    assert len(init.initiate([box([3.0, 0.0], 4.5)])) == 1


def test_three_fix_confirmation_needs_the_pair_prediction():
    init, _ = _initiator(confirm_fixes=3)
    assert init.initiate([box([0.0, 0.0], 0.0)]) == []
    assert init.initiate([box([5.0, 0.0], 0.5)]) == []  # a pair, not yet a track
    assert len(init.initiate([box([10.0, 0.0], 1.0)])) == 1  # where the pair predicts


def test_speed_prior_is_fused_with_the_pair_velocity():
    init, made = _initiator(initial_speed_sigma=5.0)
    init.initiate([box([0.0, 0.0], 0.0)])
    init.initiate([box([5.0, 0.0], 0.5)])
    pv = 2.0 / 0.25
    np.testing.assert_allclose(made[0][0][[1, 3]], [10.0 * 25.0 / (pv + 25.0), 0.0])


# --- the composed tracker -----------------------------------------------------------------------------------------

def test_the_tracker_holds_its_target_track_in_a_list_of_tracks():
    trk = SingleTargetTracker(TrackerConfig())
    assert trk.tracks == [] and trk.filter is None and trk.current_estimate() is None
    trk.step(0.0, [box([0.0, 0.0], 0.0)])
    est = trk.step(0.5, [box([5.0, 0.0], 0.5)])
    (tr,) = trk.tracks
    assert trk.filter is tr.filter and trk.last_update_t == tr.last_update_t == 0.5
    np.testing.assert_allclose(est.p_W, [5.0, 0.0])
    trk.step(1.0, [box([10.0, 0.0], 1.0, sensor="a"), box([10.5, 0.0], 1.0, sensor="b")])
    assert trk.updates == 2 and trk.used_by_sensor == {"a": 1, "b": 1} and trk.initiations == 1


def test_parts_are_injected():
    calls = []

    def filters(x0, P0, t0):
        calls.append(t0)
        return EKF(CV, x0, P0, t0)

    trk = SingleTargetTracker(TrackerConfig(), model=CV, filters=filters)
    trk.step(0.0, [box([0.0, 0.0], 0.0)])
    trk.step(0.5, [box([5.0, 0.0], 0.5)])
    assert calls == [0.5] and trk.filter.model is CV
