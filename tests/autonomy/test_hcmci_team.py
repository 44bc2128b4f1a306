"""HCMCI team step (autonomy.fusion.hcmci_team) and the tracker's information step it runs on."""

import copy
import dataclasses

import numpy as np
import pytest

from autonomy.estimation.linalg import tria
from autonomy.estimation.scif import SqrtInformation
from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig, TrackInformation
from autonomy.fusion.consensus import hcmci, ring_adjacency
from autonomy.fusion.hcmci_team import HcmciConfig, HcmciTeam, consensus_adjacency, fuse_team, pair_adjacency
from autonomy.sensing.measurement import Detection

N_STATE = 6


def _random_info(rng: np.random.Generator, width: int, scale: float) -> SqrtInformation:
    S = tria(rng.normal(size=(N_STATE, width)) * scale)
    return SqrtInformation(S, rng.normal(size=N_STATE) * scale)


def _infos(seed: int, n: int, t: float = 1.0) -> list[TrackInformation]:
    rng = np.random.default_rng(seed)
    return [TrackInformation(t=t, prior=_random_info(rng, N_STATE, 1.0), contribution=_random_info(rng, 3, 0.5))
            for _ in range(n)]


def _Y(info: SqrtInformation) -> np.ndarray:
    return info.S @ info.S.T


def test_team_step_is_hcmci_on_the_nodes_with_a_track():
    infos: list = _infos(1, 5)
    infos[3] = None  # no track: takes no part
    links = ring_adjacency([0, 2, 1, 3, 4])
    cfg = HcmciConfig(rounds=3, gain="safe")
    out = fuse_team(infos, links, cfg)
    nodes = [0, 1, 2, 4]
    sub = consensus_adjacency(links, [x is not None for x in infos])[np.ix_(nodes, nodes)]
    ref = hcmci([infos[j].prior for j in nodes], [infos[j].contribution for j in nodes], sub, 3, "safe")
    assert out.posteriors[3] is None
    for j, r in zip(nodes, ref, strict=True):
        assert np.allclose(_Y(out.posteriors[j]), _Y(r), rtol=1e-12, atol=1e-12)
        assert np.allclose(out.posteriors[j].h, r.h, rtol=1e-12, atol=1e-12)
    assert out.active_links == 3  # the ring 0-2-1-3-4-0 without node 3's two links


def test_with_every_link_up_and_many_rounds_the_nodes_agree_on_the_centralised_sum():
    n = 4
    infos = _infos(2, n)
    full = ~np.eye(n, dtype=bool)
    out = fuse_team(infos, full, HcmciConfig(rounds=60, gain=float(n)))
    Y_central = np.mean([_Y(x.prior) for x in infos], axis=0) + sum(_Y(x.contribution) for x in infos)
    h_central = np.mean([x.prior.h for x in infos], axis=0) + sum(x.contribution.h for x in infos)
    for post in out.posteriors:
        assert np.allclose(_Y(post), Y_central, rtol=1e-9, atol=1e-9)
        assert np.allclose(post.h, h_central, rtol=1e-9, atol=1e-9)
    x = [np.linalg.solve(_Y(p), p.h) for p in out.posteriors]  # consensus error -> 0
    assert max(np.linalg.norm(xi - np.mean(x, axis=0)) for xi in x) < 1e-9


def test_a_cut_off_node_keeps_its_own_prior_plus_its_own_contribution():
    infos = _infos(3, 4)
    links = pair_adjacency(4, [(1, 2), (2, 3), (3, 1)])  # node 0 has no link
    out = fuse_team(infos, links, HcmciConfig(rounds=3))
    own = infos[0]
    assert np.allclose(_Y(out.posteriors[0]), _Y(own.prior) + _Y(own.contribution), rtol=1e-12, atol=1e-12)
    assert np.allclose(out.posteriors[0].h, own.prior.h + own.contribution.h, rtol=1e-12, atol=1e-12)


def test_adjacency_excludes_trackless_nodes_and_self_links():
    links = np.ones((4, 4), dtype=bool)
    A = consensus_adjacency(links, [True, False, True, True])
    assert not A[1].any() and not A[:, 1].any()
    assert not A.diagonal().any()
    assert A[0, 2] and A[2, 3] and A[0, 3]
    with pytest.raises(ValueError, match="symmetric"):
        consensus_adjacency(np.triu(links), [True] * 4)
    with pytest.raises(ValueError, match="different nodes"):
        pair_adjacency(3, [(1, 1)])


def test_priors_at_different_times_are_refused():
    infos = _infos(4, 2)
    infos[1] = TrackInformation(t=2.0, prior=infos[1].prior, contribution=None)
    with pytest.raises(ValueError, match="one time"):
        fuse_team(infos, ~np.eye(2, dtype=bool), HcmciConfig())


def test_priors_of_different_state_sizes_are_refused():
    infos = _infos(4, 2)
    rng = np.random.default_rng(7)
    S4 = tria(rng.normal(size=(4, 4)))  # a 4-state (cv) prior beside 6-state (singer) ones
    infos[1] = TrackInformation(t=infos[1].t, prior=SqrtInformation(S4, rng.normal(size=4)), contribution=None)
    with pytest.raises(ValueError, match="state size"):
        fuse_team(infos, ~np.eye(2, dtype=bool), HcmciConfig())


@pytest.mark.parametrize("kwargs, match", [({"rounds": 0}, "rounds"), ({"rounds": 2.5}, "rounds"),
                                           ({"gain": "big"}, "gain"), ({"gain": -1.0}, "gain")])
def test_bad_settings_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        HcmciConfig(**kwargs)


# --- trackers in a team ---------------------------------------------------------------------------------------------

def _radar(p_target, p_sensor, t, rng, sigma=(1.0, 0.05, 0.05)):
    d = np.asarray(p_target, float) - np.asarray(p_sensor, float)
    z = np.array([np.linalg.norm(d), np.arctan2(d[1], d[0]), np.arctan2(d[2], np.hypot(d[0], d[1]))])
    z = z + rng.normal(size=3) * np.asarray(sigma)
    return Detection(z=z, R=np.diag(np.square(sigma)), t_meas=t, t_arrival=t, sensor_id="radar",
                     p_sensor_W=np.asarray(p_sensor, float), kind="radar")


def _scans(seed: int, n_scans: int, sensor=(30.0, -20.0, 40.0)):
    rng = np.random.default_rng(seed)
    return [[_radar((2.0 * 0.5 * k, 0.5 * k, 0.0), sensor, 0.5 * k, rng)] for k in range(n_scans)]


CFG = TrackerConfig(filter="scif", model="singer", singer_alpha=0.6, singer_sigma_a=0.67)


def test_a_lone_team_member_tracks_exactly_like_a_tracker_on_its_own():
    alone, member = SingleTargetTracker(CFG), SingleTargetTracker(CFG)
    team = HcmciTeam(HcmciConfig(rounds=3))
    for k, scan in enumerate(_scans(5, 12)):
        t = 0.5 * k
        ref = alone.step(t, scan)
        (est,), fused = team.step(t, [member], [scan], np.zeros((1, 1), dtype=bool))
        assert (ref is None) == (est is None)
        if ref is not None:
            assert np.allclose(est.p_W, ref.p_W, atol=1e-9) and np.allclose(est.P, ref.P, atol=1e-9)
    assert member.updates == alone.updates and team.steps == 12


def test_team_members_take_the_hcmci_posteriors_of_their_priors_and_contributions():
    sensors = [(30.0, -20.0, 40.0), (-25.0, 15.0, 40.0), (10.0, 35.0, 50.0)]
    scans = [_scans(10 + j, 10, sensor=p) for j, p in enumerate(sensors)]
    trackers = [SingleTargetTracker(CFG) for _ in sensors]
    links = pair_adjacency(3, [(0, 1), (1, 2)])  # a path: node 1 hears both, nodes 0 and 2 only node 1
    cfg = HcmciConfig(rounds=2, gain="safe")
    team = HcmciTeam(cfg)
    fused_steps = 0
    for k in range(10):
        t = 0.5 * k
        dets = [s[k] for s in scans]
        infos = [copy.deepcopy(trk).step_information(t, d) for trk, d in zip(trackers, dets, strict=True)]
        estimates, step = team.step(t, trackers, dets, links)
        if all(x is None for x in infos):
            assert all(e is None for e in estimates)
            continue
        assert all(x is not None for x in infos)  # the three confirm their tracks at the same scan
        ref = hcmci([x.prior for x in infos], [x.contribution for x in infos], links, cfg.rounds, cfg.gain)
        for trk, r, est in zip(trackers, ref, estimates, strict=True):
            post = trk.filter.information_state
            assert trk.filter.t == pytest.approx(t) and est.t == pytest.approx(t)
            assert np.allclose(_Y(post), _Y(r), rtol=1e-10, atol=1e-10)
            assert np.allclose(post.h, r.h, rtol=1e-10, atol=1e-10)
            xy = np.linalg.solve(_Y(r), r.h)[[trk.layout.index("x"), trk.layout.index("y")]]
            assert np.allclose(est.p_W, xy, atol=1e-8)
        assert step.active_links == 2
        fused_steps += all(x.contribution is not None for x in infos)
    assert fused_steps >= 7 and team.steps == 10


def test_a_team_step_reads_the_fused_tracks_without_estimating_again(monkeypatch):
    trk = SingleTargetTracker(CFG)
    team = HcmciTeam(HcmciConfig())
    monkeypatch.setattr(trk, "estimate", lambda t: pytest.fail("estimate() repeats the loss check and prediction"))
    for k, scan in enumerate(_scans(9, 4)):
        (est,), _ = team.step(0.5 * k, [trk], [scan], np.zeros((1, 1), dtype=bool))
    assert est is not None and est.t == pytest.approx(1.5)


def test_priors_within_the_time_tolerance_count_as_one_time(monkeypatch):
    import autonomy.fusion.hcmci_team as hcmci_team

    monkeypatch.setattr(hcmci_team, "TIME_TOLERANCE", 0.1)  # the estimation layer's tolerance, not a literal
    infos = _infos(4, 2)
    infos[1] = TrackInformation(t=1.05, prior=infos[1].prior, contribution=None)
    assert all(p is not None for p in fuse_team(infos, ~np.eye(2, dtype=bool), HcmciConfig()).posteriors)


def test_information_step_defers_only_a_scan_taken_at_the_step_time():
    trk = SingleTargetTracker(CFG)
    scans = _scans(6, 5)
    for k in range(4):
        trk.step(0.5 * k, scans[k])
    at_step = trk.step_information(2.0, scans[4])
    assert at_step.contribution is not None and at_step.t == 2.0 and trk.filter.t == pytest.approx(2.0)
    trk2 = SingleTargetTracker(CFG)
    for k in range(4):
        trk2.step(0.5 * k, scans[k])
    late = trk2.step_information(2.1, scans[4])  # the scan is older than the step: applied locally
    assert late.contribution is None and trk2.filter.t == pytest.approx(2.1)
    assert trk2.updates == trk.updates


def test_information_step_sums_the_contributions_of_every_scan_taken_at_the_step_time():
    rng = np.random.default_rng(8)
    trk = SingleTargetTracker(CFG)
    for k, scan in enumerate(_scans(6, 4)):
        trk.step(0.5 * k, scan)
    ref = copy.deepcopy(trk)
    ref.filter.predict(2.0)
    truth = (2.0 * 2.0, 2.0, 0.0)
    scans = [_radar(truth, (30.0, -20.0, 40.0), 2.0, rng), _radar(truth, (-25.0, 10.0, 35.0), 2.0, rng)]
    scans[1] = dataclasses.replace(scans[1], sensor_id="radar2")  # a second sensor, same time
    own = [copy.deepcopy(ref).filter.information(d)[0] for d in scans]  # each against the prior at 2.0
    updates = trk.updates
    info = trk.step_information(2.0, scans)
    assert trk.updates == updates + 2 and trk.filter.t == pytest.approx(2.0)
    assert np.allclose(_Y(info.prior), _Y(ref.filter.information_state), rtol=1e-9, atol=1e-9)
    assert np.allclose(info.prior.h, ref.filter.information_state.h, rtol=1e-9, atol=1e-9)
    assert np.allclose(_Y(info.contribution), _Y(own[0]) + _Y(own[1]), rtol=1e-9, atol=1e-9)
    assert np.allclose(info.contribution.h, own[0].h + own[1].h, rtol=1e-9, atol=1e-9)


def test_information_step_needs_the_information_filter():
    with pytest.raises(TypeError, match="scif"):
        SingleTargetTracker(TrackerConfig(filter="ekf")).step_information(0.0, [])


def test_associated_links_drop_pairs_whose_priors_are_two_cars():
    """Nodes tracking many cars fuse only with nodes whose target track is the same car: the link between priors
    d apart with covariances P_i = P_j = σ² I stays iff |d|² / (2σ²) <= gate."""
    from autonomy.estimation.scif import SqrtInformation
    from autonomy.estimation.tracking.information import TrackInformation
    from autonomy.fusion.hcmci_team import associated_links

    def info(x, var):
        Y = np.eye(4) / var
        return TrackInformation(t=1.0, prior=SqrtInformation(np.linalg.cholesky(Y), Y @ np.asarray(x, float)),
                                contribution=None)

    gate = 18.47  # χ²_4 at 0.999
    near, far = np.sqrt(gate * 2 * 25.0) * 0.99, np.sqrt(gate * 2 * 25.0) * 1.01
    infos = [info([0, 0, 0, 0], 25.0), info([near, 0, 0, 0], 25.0), info([far, 0, 0, 0], 25.0), None]
    links = np.ones((4, 4), bool)
    np.fill_diagonal(links, False)
    A = associated_links(infos, links, gate)
    assert A[0, 1] and A[1, 0] and not A[0, 2] and not A[2, 0] and A[1, 2]  # 1–2 are 0.02·… apart: one car
    assert A[0, 3] and A[3, 2]  # a node without a track keeps its links (the consensus drops it anyway)
