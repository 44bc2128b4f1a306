"""The multi-target tracker: M-of-N confirmation follows the binomial law, crossing cars keep their tracks, the
target track is kept by identity among look-alike traffic, and the single-target estimator wrapper sees only the
target's detections."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import binom

from autonomy.estimation.tracker import TrackerConfig
from autonomy.estimation.tracking.gated import TargetGatedEstimator
from autonomy.estimation.tracking.identity import IdentityConfig, accumulate_readings, track_evidence
from autonomy.estimation.tracking.multi import MultiTargetTracker, MultiTrackerConfig
from autonomy.estimation.tracking.unseen import CAMERA_RESOLUTION_M, UNSEEN_DROP, UNSEEN_NODES
from autonomy.sensing.measurement import ClassMeasurement, Detection

SIGMA = 2.0  # m, position detections
BG = {"colour": np.array([0.9, 0.1])}  # the target's colour (1) is rare in the background
CONF = np.array([[0.9, 0.1], [0.1, 0.9]])


def _det(xy, t, colour=None, sensor="s") -> Detection:
    classes = () if colour is None else (ClassMeasurement(attribute="colour", observed=colour, confusion=CONF),)
    return Detection(z=np.asarray(xy, float), R=np.eye(2) * SIGMA**2, t_meas=t, t_arrival=t, sensor_id=sensor,
                     p_sensor_W=np.array([0.0, 0.0, 100.0]), kind="box", classes=classes)


def _tracker(m=3, n=5, associator="gnn", **identity) -> MultiTargetTracker:
    cfg = TrackerConfig(filter="ekf", model="cv", q=0.5, max_target_speed=30.0, lost_after_s=3.0)
    ident = IdentityConfig(target_classes={"colour": 1}, background=BG,
                           **({"background_density": 1e-5} | identity))
    return MultiTargetTracker(cfg, MultiTrackerConfig(associator=associator, confirm_m=m, confirm_n=n), ident)


@pytest.mark.parametrize("m,n,pd", [(3, 5, 0.6), (4, 6, 0.7)])
def test_m_of_n_confirmation_follows_the_binomial_law(m, n, pd):
    """A tentative track starts with 2 hits in 2 scans; it is confirmed iff at least m−2 of the next n−2 scans
    detect it: P = P(Binom(n−2, pd) >= m−2). Scans are made visible by one far false alarm each."""
    rng = np.random.default_rng(11)
    runs, confirmed = 400, 0
    for _ in range(runs):
        tr = _tracker(m, n)
        car = np.array([0.0, 0.0])
        for k in range(40):
            t = 0.5 * k
            scan = [_det(rng.uniform(5e4, 9e4, 2) * rng.choice([-1, 1], 2), t)]
            if k < 2 or rng.uniform() < pd:
                scan.append(_det(car + rng.normal(0, SIGMA, 2), t))
            tr.step(t, scan)
            first = [x for x in tr.tracks if np.linalg.norm(x.filter.x[[0, 2]]) < 50]
            if tr.confirmations or (k >= 2 and not first):
                break
        confirmed += tr.confirmations > 0
    p = binom.sf(m - 3, n - 2, pd)
    lo, hi = binom.ppf(0.0005, runs, p), binom.ppf(0.9995, runs, p)
    assert lo <= confirmed <= hi, (confirmed, runs * p)


def test_two_crossing_cars_keep_their_tracks_under_gnn():
    """Two cars on straight lines crossing at 30° (the linear-Gaussian case): each ends on the track it started
    with, on (almost) every seed."""
    swaps, seeds = 0, 40
    for seed in range(seeds):
        rng = np.random.default_rng(seed)
        tr = _tracker()
        v1 = 10.0 * np.array([1.0, 0.0])
        v2 = 10.0 * np.array([np.cos(np.radians(30)), np.sin(np.radians(30))])
        p1, p2 = np.array([-100.0, 0.0]), -10.0 * v2
        ids_at_start = None
        for k in range(41):
            t = 0.5 * k
            a, b = p1 + v1 * t, p2 + v2 * t
            tr.step(t, [_det(a + rng.normal(0, SIGMA, 2), t), _det(b + rng.normal(0, SIGMA, 2), t)])
            if k == 8:
                ids_at_start = _nearest_ids(tr, a, b)
        assert ids_at_start is not None and None not in ids_at_start
        swaps += _nearest_ids(tr, a, b) != ids_at_start
    assert swaps <= 2, swaps


def _nearest_ids(tr, a, b):
    out = []
    for car in (a, b):
        best = min(tr.tracks, key=lambda x: np.linalg.norm(x.filter.x[[0, 2]] - car), default=None)
        out.append(None if best is None or np.linalg.norm(best.filter.x[[0, 2]] - car) > 15 else best.track_id)
    return out


@pytest.mark.parametrize("associator", ["gnn", "jpda"])
def test_target_is_found_among_traffic_by_colour_and_held(associator):
    """Five cars in a row 60 m apart, one of the target's colour; no cue. The colour readings make its track the
    target's within a few scans, and it stays so. Without a cue, "the target is a car not yet tracked" keeps the
    weight of a track without readings, so the red track's probability tends to (1/π(red)) / (1/π(red) + 1) = 10/11
    (the four others' readings rule them out)."""
    rng = np.random.default_rng(3)
    tr = _tracker(associator=associator)
    cars = np.array([[60.0 * k, 0.0] for k in range(5)])
    colours = [0, 0, 1, 0, 0]
    on_target = []
    for k in range(40):
        t = 0.5 * k
        pos = cars + np.array([8.0 * t, 0.0])
        scan = [_det(p + rng.normal(0, SIGMA, 2), t, colour=int(rng.uniform() < CONF[c, 1]))
                for p, c in zip(pos, colours, strict=True)]
        est = tr.step(t, scan)
        if k >= 12:
            on_target.append(est is not None and np.linalg.norm(est.p_W - pos[2]) < 10)
    assert np.mean(on_target) == 1.0
    assert tr.identity.probability(tr.target_track_id) == pytest.approx(10 / 11, abs=0.02)


def test_cue_designates_the_target_without_class_readings():
    rng = np.random.default_rng(4)
    tr = _tracker()
    cars = np.array([[0.0, 0.0], [200.0, 0.0], [400.0, 0.0]])
    tr.cue(0.0, cars[1] + rng.normal(0, 20, 2), sigma_m=20.0)
    for k in range(20):
        t = 0.5 * k
        pos = cars + np.array([0.0, 5.0 * t])
        est = tr.step(t, [_det(p + rng.normal(0, SIGMA, 2), t) for p in pos])
    assert np.linalg.norm(est.p_W - pos[1]) < 10
    # before any track, the estimate is the cue (guidance flies there)
    fresh = _tracker()
    fresh.cue(0.0, np.array([5.0, 6.0]), sigma_m=20.0)
    est0 = fresh.step(0.0, [])
    np.testing.assert_allclose(est0.p_W, [5.0, 6.0])


def test_gated_estimator_sees_only_the_target_tracks_detections():
    class Recorder:
        def __init__(self):
            self.seen = []

        def step(self, t, detections):
            self.seen.extend(detections)
            return None

    rng = np.random.default_rng(5)
    inner = Recorder()
    est = TargetGatedEstimator(inner, _tracker())
    cars = np.array([[0.0, 0.0], [300.0, 0.0]])
    est.cue(0.0, cars[0], sigma_m=10.0)
    for k in range(20):
        t = 0.5 * k
        est.step(t, [_det(p + rng.normal(0, SIGMA, 2), t) for p in cars])
    assert inner.seen, "the target's detections reach the wrapped estimator"
    assert all(np.linalg.norm(d.z - cars[0]) < 20 for d in inner.seen)
    assert est.target_track_id is not None and est.track_reports()


def _precise(xy, t, sigma=0.3) -> Detection:
    return Detection(z=np.asarray(xy, float), R=np.eye(2) * sigma**2, t_meas=t, t_arrival=t, sensor_id="s",
                     p_sensor_W=np.array([0.0, 0.0, 100.0]), kind="box")


def test_cars_stopped_side_by_side_keep_two_tracks():
    """Two cars stopped 3 m apart (inside the 4 m merge distance), each detected on every scan: two cars, not one
    car's duplicate tracks, since every scan updates both with different detections."""
    rng = np.random.default_rng(3)
    tr = _tracker()
    cars = [np.array([0.0, 0.0]), np.array([3.0, 0.0])]
    for k in range(40):
        t = 0.5 * k
        tr.step(t, [_precise(c + rng.normal(0, 0.3, 2), t) for c in cars])
    live = [x for x in tr.tracks if x.confirmed]
    assert tr.merges == 0 and len(live) == 2
    ends = sorted(float(x.filter.x[0]) for x in live)
    assert abs(ends[0] - 0.0) < 0.5 and abs(ends[1] - 3.0) < 0.5


def test_two_tracks_on_one_car_are_merged():
    """A duplicate of a car's track (same estimate, same updating scans) is merged into the older one."""
    import copy

    rng = np.random.default_rng(4)
    tr = _tracker()
    car = np.array([10.0, -5.0])
    for k in range(10):
        tr.step(0.5 * k, [_precise(car + rng.normal(0, 0.3, 2), 0.5 * k)])
    (orig,) = [x for x in tr.tracks if x.confirmed]
    dup = copy.deepcopy(orig)
    dup.track_id = 99
    tr.tracks.append(dup)
    tr.identity.confirmed(99, orig.filter.t, orig.filter.x[[0, 2]], np.eye(2), 0.0)
    tr.step(5.0, [_precise(car + rng.normal(0, 0.3, 2), 5.0)])
    assert tr.merges == 1 and [x.track_id for x in tr.tracks if x.confirmed] == [orig.track_id]


def test_track_reports_are_made_once_per_step_and_follow_every_change():
    """Reports read twice after a step are the same objects; a step, a filter moved in time from outside, or a
    cue makes them anew, equal to reports computed from the tracks directly."""
    tr = _tracker()
    for k in range(4):
        t = 0.5 * k
        tr.step(t, [_det([10.0 * t, 0.0], t), _det([0.0, 200.0 + 5.0 * t], t)])
    first, again = tr.track_reports(), tr.track_reports()
    assert len(first) == 2 and first is not again and all(a is b for a, b in zip(first, again, strict=True))
    tr.step(2.0, [_det([20.0, 0.0], 2.0)])
    after = tr.track_reports()
    assert all(a is not b for a, b in zip(first, after, strict=True))
    assert [r.estimate.t for r in after] == [x.filter.t for x in tr.tracks]
    moved = tr.tracks[1]
    moved.filter.predict(moved.filter.t + 1.0)  # from outside the tracker: its time changes, so do its reports
    fresh = tr.track_reports()
    assert fresh[1].estimate.t == moved.filter.t
    np.testing.assert_array_equal(fresh[1].estimate.p_W, moved.filter.x[[0, 2]])
    tr.cue(2.0, np.array([20.0, 0.0]), 5.0)
    cued = tr.track_reports()
    assert all(a is not b for a, b in zip(fresh, cued, strict=True))



def _stop_and_go(cfg: TrackerConfig) -> tuple[np.ndarray, np.ndarray, set, list]:
    """Two cars 40 m apart on one road at 8 m/s, position detections of σ 6 m at 2 Hz; the cued one stands from 20
    to 40 s and drives off. Times, target errors, target track ids and (time, stop-mode probability) from 5 s on."""
    rng = np.random.default_rng(8)
    sigma = 6.0
    ident = IdentityConfig(target_classes={"colour": 1}, background=BG, background_density=1e-5)
    tr = MultiTargetTracker(cfg, MultiTrackerConfig(associator="gnn"), ident)
    tr.cue(0.0, np.array([0.0, 0.0]), sigma_m=10.0)
    x, times, errors, ids, mu_stop = 0.0, [], [], set(), []
    for k in range(120):
        t = 0.5 * k
        x += (0.0 if 20.0 <= t < 40.0 else 8.0) * 0.5
        cars = [np.array([x, 0.0]), np.array([40.0 + 8.0 * t, 0.0])]
        scan = [Detection(z=c + rng.normal(0, sigma, 2), R=np.eye(2) * sigma**2, t_meas=t, t_arrival=t, sensor_id="s",
                          p_sensor_W=np.array([0.0, 0.0, 100.0]), kind="box") for c in cars]
        est = tr.step(t, scan)
        if k >= 10:
            times.append(t)
            errors.append(np.linalg.norm(est.p_W - cars[0]))
            ids.add(tr.target_track_id)
            track = next(tk for tk in tr.tracks if tk.track_id == tr.target_track_id)
            mu_stop.append(getattr(track.filter, "mu", [1.0, 0.0])[1])
    return np.array(times), np.array(errors), ids, np.array(mu_stop)


def test_a_car_that_stops_and_drives_off_keeps_its_track_under_the_move_stop_imm():
    """The per-track move–stop IMM holds the car through the stop (its stop mode takes over: measured 0.79 against
    0.07 while it drives) with less error than the Singer EKF alone on the same detections (measured 1.6 against
    4.5 m), and the same track follows it when it drives again."""
    singer = {"model": "singer", "singer_alpha": 0.6, "singer_sigma_a": 2.0, "max_target_speed": 30.0,
              "lost_after_s": 3.0}
    t, err, ids, mu = _stop_and_go(TrackerConfig(filter="imm", imm_modes="move_stop", **singer))
    _, err_ekf, ids_ekf, _ = _stop_and_go(TrackerConfig(filter="ekf", **singer))
    assert len(ids) == 1 == len(ids_ekf)
    standing, driving = (t >= 25.0) & (t < 40.0), (t >= 50.0) | (t < 20.0)
    assert mu[standing].mean() > 0.6 and mu[driving].mean() < 0.2
    assert err[standing].mean() < 0.8 * err_ekf[standing].mean()
    assert err.max() < 15.0


# -- the cameras' negative information ------------------------------------------------------------------------------
class _Cover:
    """A frame's coverage whose view is the points with ``x >= x_min`` (a stand-in for a camera's)."""

    def __init__(self, t: float, x_min: float = -np.inf, sensor: str = "cam") -> None:
        self.t_meas = self.t_arrival = t
        self.sensor_id, self.x_min = sensor, x_min

    def visible(self, p_W):
        return np.asarray(p_W)[:, 0] >= self.x_min


def _tracker_seen(pd: float) -> MultiTargetTracker:
    cfg = TrackerConfig(filter="ekf", model="cv", q=0.5, max_target_speed=30.0, lost_after_s=30.0)
    ident = IdentityConfig(target_classes={"colour": 1}, background=BG, background_density=1e-5)
    return MultiTargetTracker(cfg, MultiTrackerConfig(confirm_m=2, confirm_n=2, camera_detection_probability=pd),
                              ident)


def _one_track(tr: MultiTargetTracker) -> None:
    for k in range(4):  # a standing car, seen by a position sensor: one confirmed track
        tr.step(0.5 * k, [_det((100.0, 0.0), 0.5 * k)])
    assert len(tr.tracks) == 1 and tr.tracks[0].confirmed


def test_a_track_the_camera_keeps_seeing_nothing_at_is_dropped_on_the_law():
    """Frames that have the whole track in view and show nothing: its score falls by log(1 − p_D) per frame and it
    is dropped at the first frame that takes it below log(UNSEEN_DROP): p_D = 0.9, 0.1² < 0.02, the second frame;
    p_D = 0.6, 0.4⁵ < 0.02 < 0.4⁴, the fifth. Its target probability joins "in no track", and the target is
    searched for from its last estimate."""
    for pd, frames in ((0.9, 2), (0.6, 5)):
        tr = _tracker_seen(pd)
        _one_track(tr)
        tr.cue(1.5, np.array([100.0, 0.0]), 5.0)
        track = tr.tracks[0]
        for k in range(frames):
            assert tr.tracks, (pd, k)
            t = 2.0 + 0.5 * k
            tr.observe_coverage([_Cover(t)])
            est = tr.step(t, [])
            assert track.unseen == pytest.approx((k + 1) * math.log1p(-pd))
        assert not tr.tracks and tr.dropped_unseen == 1
        assert frames * math.log1p(-pd) < math.log(UNSEEN_DROP) <= (frames - 1) * math.log1p(-pd)
        assert tr.target_track_id is None
        np.testing.assert_allclose(est.p_W, [100.0, 0.0], atol=1.0)  # the search starts where the track was


def test_the_visible_share_is_the_gauss_hermite_average_of_the_view():
    """A view of the half-plane x >= mean x + 1σ: the share is the Gauss–Hermite weight of the nodes there."""
    tr = _tracker_seen(0.9)
    _one_track(tr)
    track = tr.tracks[0]
    sigma_x = math.sqrt(track.filter.P[0, 0])
    nodes, weights = np.polynomial.hermite_e.hermegauss(UNSEEN_NODES)
    share = float(weights[nodes >= 1.0 + 1e-9].sum() / weights.sum())
    tr.observe_coverage([_Cover(2.0, x_min=float(track.filter.x[0]) + sigma_x)])
    tr.step(2.0, [])
    assert track.unseen == pytest.approx(math.log1p(-0.9 * share), rel=1e-9)


def test_a_camera_detection_restores_the_track_and_frames_out_of_view_say_nothing():
    tr = _tracker_seen(0.9)
    _one_track(tr)
    track = tr.tracks[0]
    for k in range(10):  # every other frame sees the car: never two misses in a row
        t = 2.0 + 0.5 * k
        tr.observe_coverage([_Cover(t)])
        tr.step(t, [_det((100.0, 0.0), t, sensor="cam")] if k % 2 else [])
        assert tr.tracks == [track]
        assert track.unseen == (0.0 if k % 2 else pytest.approx(math.log(0.1)))
    for k in range(10):  # frames that look elsewhere
        t = 7.0 + 0.5 * k
        tr.observe_coverage([_Cover(t, x_min=1000.0)])
        tr.step(t, [])
    assert tr.tracks == [track] and track.unseen == 0.0 and tr.dropped_unseen == 0


def test_without_a_camera_detection_probability_coverage_is_ignored():
    tr = _tracker_seen(0.0)
    _one_track(tr)
    for k in range(10):
        t = 2.0 + 0.5 * k
        tr.observe_coverage([_Cover(t)])
        tr.step(t, [])
    assert len(tr.tracks) == 1 and tr.tracks[0].unseen == 0.0


@pytest.mark.parametrize("pd", [-0.1, 1.0])
def test_a_camera_detection_probability_outside_0_1_is_refused(pd):
    with pytest.raises(ValueError, match=r"camera_detection_probability must be in \[0, 1\)"):
        MultiTrackerConfig(camera_detection_probability=pd)


def test_the_agent_hands_arrived_coverage_to_an_estimator_that_observes_it():
    """Coverage reaches the estimator at the first step at or after its arrival, through a gated user estimator
    too; an estimator without ``observe_coverage`` never sees it."""
    from autonomy.agent import Agent

    class Plain:
        def step(self, t, detections):
            return None

    tracker = _tracker_seen(0.9)
    for est in (tracker, TargetGatedEstimator(Plain(), tracker), Plain()):
        agent = Agent("uav1", est, guidance=None)
        early, late = _Cover(1.0), _Cover(2.0)
        late.t_arrival = 2.5
        agent.receive_coverage(early)
        agent.receive_coverage(late)
        agent.take_ready(2.0)
        if est is not tracker and not isinstance(est, TargetGatedEstimator):
            continue
        assert list(tracker._coverage) == [(1.0, "cam")]
        agent.take_ready(2.5)
        assert list(tracker._coverage) == [(1.0, "cam"), (2.0, "cam")]
        tracker._coverage.clear()
    assert not tracker._coverage  # the plain estimator's agent kept its coverage to itself


def test_two_tracks_within_the_camera_s_resolution_are_not_judged_by_a_miss():
    """Two cars 6 m apart (one blob to a camera that far): a frame that updates one of them, or neither, lowers
    neither's score; 30 m apart, the missed one loses log(1 − p_D)."""
    for gap, judged in ((6.0, False), (30.0, True)):
        tr = _tracker_seen(0.9)
        for k in range(4):
            tr.step(0.5 * k, [_det((100.0, 0.0), 0.5 * k), _det((100.0, gap), 0.5 * k)])
        assert len(tr.tracks) == 2 and all(x.confirmed for x in tr.tracks)
        tr.observe_coverage([_Cover(2.0)])
        tr.step(2.0, [_det((100.0, 0.0), 2.0, sensor="cam")])
        far = max(tr.tracks, key=lambda x: x.filter.x[2])
        assert far.unseen == (pytest.approx(math.log(0.1)) if judged else 0.0)
        assert gap < CAMERA_RESOLUTION_M or judged


def _sequential_reads(tracker: MultiTargetTracker, pairs) -> None:
    """A scan's class readings one by one: each detection's readings into its track's per-class log-likelihoods,
    the track's evidence, and the belief's read of it (the arithmetic of reading them one track at a time)."""
    ident = tracker.identity.config
    for track, det in pairs:
        if not det.classes:
            continue
        for c in det.classes:
            step = np.log(np.maximum(c.likelihood(), 1e-300))
            track.class_loglik[c.attribute] = accumulate_readings(track.class_loglik.get(c.attribute), step,
                                                                  ident.background.get(c.attribute),
                                                                  ident.swap_probability)
        track.evidence = track_evidence(track.class_loglik, ident)
        if track.confirmed:
            tracker.identity.read(track.track_id, track.evidence, where=lambda track=track: tracker._where(track))


def test_a_scan_s_class_readings_read_together_equal_them_read_one_by_one(monkeypatch):
    """A GNN scan's class readings are read for all its tracks at once: every track gets the bits that reading them
    one by one gives (per-class log-likelihoods, evidence) and the identity belief the same weights, with readings
    discounted (swap probability > 0), two attributes of 2 and 3 classes, some detections reading one attribute only,
    and tracks with and without earlier readings."""
    conf3 = np.array([[0.7, 0.2, 0.1], [0.15, 0.7, 0.15], [0.1, 0.2, 0.7]])

    def run(sequential: bool) -> MultiTargetTracker:
        if sequential:
            monkeypatch.setattr(MultiTargetTracker, "_read_taken", _sequential_reads)
        else:
            monkeypatch.undo()
        cfg = TrackerConfig(filter="ekf", model="cv", q=0.5, max_target_speed=30.0, lost_after_s=3.0)
        ident = IdentityConfig(target_classes={"colour": 1, "length": 2}, background=BG, swap_probability=0.05,
                               background_density=1e-5)
        tr = MultiTargetTracker(cfg, MultiTrackerConfig(confirm_m=2, confirm_n=3), ident)
        rng = np.random.default_rng(4)
        cars = rng.uniform(-400, 400, (40, 2))
        for k in range(12):
            t = 0.5 * k
            scan = []
            for xy in cars + np.array([8.0, 0.0]) * t:
                classes = []
                if rng.uniform() < 0.8:
                    classes.append(ClassMeasurement(attribute="colour", observed=int(rng.integers(2)), confusion=CONF))
                if k >= 3 and rng.uniform() < 0.6:
                    classes.append(ClassMeasurement(attribute="length", observed=int(rng.integers(3)),
                                                    confusion=conf3))
                scan.append(Detection(z=xy + rng.normal(0, SIGMA, 2), R=np.eye(2) * SIGMA**2, t_meas=t, t_arrival=t,
                                      sensor_id="s", p_sensor_W=np.array([0.0, 0.0, 100.0]), kind="box",
                                      classes=tuple(classes)))
            tr.step(t, scan)
        return tr

    together, alone = run(False), run(True)
    assert len(together.tracks) == len(alone.tracks) >= 30 and together.identity.held >= 30
    assert sum(len(tr.class_loglik) == 2 for tr in together.tracks) >= 20
    for a, b in zip(together.tracks, alone.tracks, strict=True):
        assert a.track_id == b.track_id and a.evidence == b.evidence
        assert a.class_loglik.keys() == b.class_loglik.keys()
        for name in a.class_loglik:
            assert np.array_equal(a.class_loglik[name], b.class_loglik[name])
    assert together.identity.weights == alone.identity.weights
    assert together.identity.w_none == alone.identity.w_none
