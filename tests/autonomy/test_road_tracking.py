"""Road-constrained tracker on simulated traffic: error cut on a curved road, junction branches, leaving the map.

Truth: a kinematic car on a road's lane at a stop-and-go speed schedule (|acceleration| <= 1 m/s²), from the ``Road``
API. Sensors: paper 002's two GMTI radars (σr, σφ) = (20 m, 7°) and (30 m, 5°) measuring (slant range, azimuth) at
2 Hz from 100 m altitude, orbiting the car at 500 m standoff and 180° apart.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.estimation.measurements import Measurement
from autonomy.estimation.road.constraint import RoadConstraintParams
from autonomy.estimation.road.config import RoadFilterConfig
from autonomy.estimation.road.network_filter import RoadNetworkFilter
from autonomy.estimation.road.tracker import RoadConstrainedTracker, RoadTrackerConfig
from autonomy.estimation.tracker import SingleTargetTracker
from simulator.reproduce.road_replay import SCAN_DT, STOP_AND_GO, drive, sine_network, synthetic_scans
from worlds.roads.network import RoadNetwork
from worlds.roads.road import Road

DT = SCAN_DT  # s, radar period


def radar_scans(ts: np.ndarray, ps: np.ndarray, rng: np.random.Generator) -> dict[float, list[Measurement]]:
    """Both radars' measurements at each time (one tracker fed by both)."""
    per_radar = synthetic_scans(ts, ps, rng)
    return {float(t): [m for scans in per_radar for m in scans[float(t)]] for t in ts}


def run(tracker, ts, ps, scans) -> tuple[np.ndarray, list]:
    """Position errors (m, NaN without a track) and the tracker after each step (road id, on road)."""
    err, log = np.full(len(ts), np.nan), []
    for k, t in enumerate(ts):
        est = tracker.step(float(t), scans[float(t)])
        if est is not None:
            err[k] = np.linalg.norm(est.p_W - ps[k])
        log.append((getattr(tracker, "road_id", None), getattr(tracker, "on_road", False)))
    return err, log


def cross_network() -> RoadNetwork:
    """A curved approach road into a four-way junction J with straight branches north, east and south."""
    return RoadNetwork.from_spec({
        "nodes": {"A": [0, 0], "J": [500, 0], "N": [500, 500], "E": [1000, 0], "S": [500, -500]},
        "streets": [{"id": "main", "nodes": ["A", "J"], "via": [[250, 40]]}, {"id": "north", "nodes": ["J", "N"]},
                    {"id": "east", "nodes": ["J", "E"]}, {"id": "south", "nodes": ["J", "S"]}]})


@pytest.fixture(scope="module")
def curved_road_runs() -> dict[str, list[float]]:
    """RMSE (m) over t >= 10 s of each estimator in 6 Monte Carlo runs on the curved road."""
    net = sine_network()
    ts, ps, _ = drive([net.roads["s.f"]], 150.0, STOP_AND_GO)
    out: dict[str, list[float]] = {"ekf": [], "maekf": [], "ecukf": []}
    for seed in range(6):
        scans = radar_scans(ts, ps, np.random.default_rng(seed))
        trackers = {"ekf": SingleTargetTracker(RoadTrackerConfig().tracker),
                    "maekf": RoadConstrainedTracker(RoadTrackerConfig(), net),
                    "ecukf": RoadConstrainedTracker(RoadTrackerConfig(road=RoadFilterConfig(variant="ecukf")), net)}
        for name, tr in trackers.items():
            err, log = run(tr, ts, ps, scans)
            assert not np.isnan(err[ts >= 10.0]).any()
            out[name].append(float(np.sqrt(np.mean(err[ts >= 10.0] ** 2))))
            if name != "ekf":
                assert all(on and rid == "s.f" for rid, on in log[ts.searchsorted(10.0):])
    return out


@pytest.mark.parametrize("variant", ["maekf", "ecukf"])
def test_road_constraint_cuts_position_rmse_by_30_percent(curved_road_runs, variant):
    """Measured (6 runs): EKF 16.3 m; MAEKF 9.9 m (-40 %); ECUKF 9.6 m (-41 %)."""
    ekf = np.array(curved_road_runs["ekf"])
    con = np.array(curved_road_runs[variant])
    assert np.sqrt(np.mean(con**2)) <= 0.7 * np.sqrt(np.mean(ekf**2))
    assert np.all(con < ekf)  # in every run, not only on average


@pytest.mark.parametrize("branch", ["north.f", "east.f", "south.f"], ids=["left", "straight", "right"])
@pytest.mark.parametrize("variant", ["maekf", "ecukf"])
def test_junction_filter_follows_the_branch_taken(branch, variant):
    net = cross_network()
    roads = [net.roads["main.f"], net.roads[branch]]
    ts, ps, ids = drive(roads, 80.0, ((0.0, 12.0), (30.0, 5.0), (50.0, 11.0)))
    t_junction = ts[ids.index(branch)]
    window = 10.0  # s after the car passes the junction
    for seed in range(3):
        tr = RoadConstrainedTracker(RoadTrackerConfig(road=RoadFilterConfig(variant=variant)), net)
        err, log = run(tr, ts, ps, radar_scans(ts, ps, np.random.default_rng(seed)))
        settled = ts >= t_junction + window
        assert all(rid == branch for rid, _ in np.array(log, dtype=object)[settled])
        hyps = tr.hypotheses()
        assert hyps[0][0] == branch and hyps[0][1] > 0.99
        assert np.sqrt(np.nanmean(err[ts >= 10.0] ** 2)) < 20.0
        before = (ts > t_junction - 30.0) & (ts < t_junction - 5.0)  # within 5 s a branch may take over early
        assert all(rid == "main.f" for rid, _ in np.array(log, dtype=object)[before])


@pytest.mark.parametrize("street_dir", ["s.f", "s.r"])
def test_direction_on_a_two_way_street_is_resolved(street_dir):
    net = sine_network()
    ts, ps, _ = drive([net.roads[street_dir]], 60.0, ((0.0, 10.0),))
    tr = RoadConstrainedTracker(RoadTrackerConfig(), net)
    _, log = run(tr, ts, ps, radar_scans(ts, ps, np.random.default_rng(11)))
    assert all(rid == street_dir for rid, _ in log[ts.searchsorted(20.0):])


def off_map_truth(road: Road, s_exit: float = 300.0, depth: float = 200.0, v: float = 8.0, wait: float = 10.0):
    """Along ``road`` to ``s_exit``, then straight off it to the left for ``depth`` m, a wait, back, and on along it."""
    lat = road.lane_offset(0)
    base = road.point(s_exit, lat)
    n = np.array([-road.tangent(s_exit)[1], road.tangent(s_exit)[0]])
    step = v * DT
    ps = [road.point(s, lat) for s in np.arange(0.0, s_exit, step)]
    phase = ["road"] * len(ps)
    out = [base + d * n for d in np.arange(0.0, depth, step)]
    out += [out[-1]] * int(wait / DT) + [base + d * n for d in np.arange(depth, 0.0, -step)]
    ps += out
    phase += ["off"] * len(out)
    back = [road.point(s, lat) for s in np.arange(s_exit, s_exit + 500.0, step)]
    ps += back
    phase += ["road"] * len(back)
    return np.arange(len(ps)) * DT, np.array(ps), np.array(phase)


@pytest.mark.parametrize("variant", ["maekf", "ecukf"])
def test_leaving_the_map_falls_back_and_reattaches(variant):
    net = RoadNetwork.from_spec({"nodes": {"A": [0, 0], "B": [1500, 0]}, "streets": [{"id": "m", "nodes": ["A", "B"]}]})
    ts, ps, phase = off_map_truth(net.roads["m.f"])
    off = phase == "off"
    i_back = int(np.flatnonzero(off)[-1]) + 1  # first step back on the road
    for seed in range(3):
        scans = radar_scans(ts, ps, np.random.default_rng(seed))
        tr = RoadConstrainedTracker(RoadTrackerConfig(road=RoadFilterConfig(variant=variant)), net)
        err, log = run(tr, ts, ps, scans)
        err_base, _ = run(SingleTargetTracker(RoadTrackerConfig().tracker), ts, ps, scans)
        on_road = np.array([on for _, on in log])
        assert isinstance(tr.filter, RoadNetworkFilter)
        assert tr.filter.detachments >= 1 and tr.filter.attachments >= 2
        far = off & (np.abs(ps[:, 1]) > 120.0)  # the car more than 120 m from the road
        assert not on_road[far].any()
        # bounded: never worse than the off-road distance at which the gate fires plus the plain tracker's error
        assert np.nanmax(err[10:]) < 120.0
        assert np.sqrt(np.nanmean(err[off] ** 2)) < 2.0 * np.sqrt(np.nanmean(err_base[off] ** 2))
        # re-attached within 15 s of returning; on the right twin for good 15 s after returning (the car comes back
        # across the street, so only its motion along it tells the twins apart: measured 2–10.5 s in 6 seeds), and
        # constrained accuracy afterwards
        i_att = i_back + int(np.argmax(on_road[i_back:]))
        assert ts[i_att] - ts[i_back] < 15.0
        i_settled = i_back + int(15.0 / DT)
        assert all(rid == "m.f" for rid, on in log[i_settled:])
        tail = slice(i_settled, None)
        assert np.sqrt(np.nanmean(err[tail] ** 2)) < np.sqrt(np.nanmean(err_base[tail] ** 2))


def test_config_validation_names_the_field():
    with pytest.raises(ValueError, match="variant"):
        RoadFilterConfig(variant="kf")
    with pytest.raises(ValueError, match="prune_threshold"):
        RoadFilterConfig(prune_threshold=1.5)
    with pytest.raises(ValueError, match="attach_probability"):
        RoadFilterConfig(attach_probability=0.9999, off_road_probability=0.99)
    with pytest.raises(ValueError, match="sigma_normal_speed"):
        RoadConstraintParams(sigma_normal_speed=0.0)
    with pytest.raises(ValueError, match="velocity_update"):
        RoadConstraintParams(velocity_update="both")
    with pytest.raises(ValueError, match="tracker"):
        RoadTrackerConfig(tracker="ekf")


@pytest.mark.parametrize("variant", ["maekf", "ecukf"])
def test_a_branch_that_lost_weight_at_the_junction_takes_it_back(variant):
    """A car that waits at a junction stands on the line of another branch's child, which can gather nearly all the
    weight before the car moves on (seen in ``road_standoff``). The child of the branch taken must survive that and take
    the weight back once the car drives along its branch, without leaving the map."""
    net = cross_network()
    roads = [net.roads["main.f"], net.roads["east.f"]]
    ts, ps, ids = drive(roads, 80.0, ((0.0, 12.0), (30.0, 5.0), (50.0, 11.0)))
    k_j = ids.index("east.f")  # first scan with the car past the junction
    for seed in range(3):
        tr = RoadConstrainedTracker(RoadTrackerConfig(road=RoadFilterConfig(variant=variant)), net)
        scans = radar_scans(ts, ps, np.random.default_rng(seed))
        for t in ts[:k_j]:
            tr.step(float(t), scans[float(t)])
        f = tr.filter
        assert {h.key()[-1] for h in f.hypotheses} == {"north.f", "east.f", "south.f"}
        for h in f.hypotheses:  # as if the wait had favoured the left turn: east holds 3e-4 of the weight
            h.log_w = {"north.f": 0.0, "east.f": math.log(3e-4 / (1 - 3e-4)), "south.f": -50.0}[h.key()[-1]]
        log = [tr.step(float(t), scans[float(t)]) and tr.road_id for t in ts[k_j:]]
        settled = ts[k_j:] >= ts[k_j] + 8.0
        assert all(rid == "east.f" for rid, s in zip(log, settled, strict=True) if s)
        assert f.detachments == 0 and tr.filter is f


def stop_line_truth(net: RoadNetwork, branch: str, wait: float = 30.0) -> tuple[np.ndarray, np.ndarray, int]:
    """Along ``main.f`` at 10 m/s, braking at 1.5 m/s² to a stop 3 m before the junction, ``wait`` s there, then onto
    ``branch`` up to 8 m/s at 1.5 m/s²: times, positions and the index of the first step after the wait."""
    main = net.roads["main.f"]
    stop = main.length - 3.0
    path, s, v = [], 0.0, 10.0
    while s < stop - 0.05 and v > 0.05:
        path.append(("main.f", s))
        v = min(v, np.sqrt(2 * 1.5 * (stop - s)))
        s += v * DT
    path += [("main.f", stop)] * int(wait / DT)
    depart = len(path)
    s, v = -3.0, 0.0
    while s < 250.0:
        v = min(v + 1.5 * DT, 8.0)
        s += v * DT
        path.append((branch, s) if s > 0 else ("main.f", main.length + s))
    ps = np.array([net.roads[r].point(x, net.roads[r].lane_offset(0)) for r, x in path])
    return np.arange(len(ps)) * DT, ps, depart


@pytest.mark.parametrize("variant", ["maekf", "ecukf"])
def test_waiting_at_a_stop_line_does_not_make_a_branch_certain(variant):
    """While the car waits at the junction the branches cannot be told apart, so the weights must not drift to
    certainty; they did when the direction evidence Φ(v_t / σ) multiplied the weights at every scan (the same velocity
    evidence counted again and again): measured over these 12 runs, the largest child weight during the wait averaged
    1.000 (ECUKF; MAEKF 1.000) and the RMSE over the 20 s after departure 15.8 m (14.4 m); with the evidence carried
    once, 0.91 (0.95) and 12.1 m (11.6 m)."""
    net = cross_network()
    max_w, rmse_after = [], []
    for branch in ("north.f", "east.f", "south.f"):
        ts, ps, depart = stop_line_truth(net, branch)
        waiting = slice(depart - int(25.0 / DT), depart)  # from 5 s after the stop
        for seed in range(4):
            scans = radar_scans(ts, ps, np.random.default_rng(seed))
            tr = RoadConstrainedTracker(RoadTrackerConfig(road=RoadFilterConfig(variant=variant)), net)
            weights, ids, err = [], [], np.full(len(ts), np.nan)
            for k, t in enumerate(ts):
                est = tr.step(float(t), scans[float(t)])
                err[k] = np.linalg.norm(est.p_W[:2] - ps[k]) if est is not None else np.nan
                weights.append(max((w for _, w in tr.hypotheses()), default=0.0))
                ids.append(tr.road_id)
            max_w.append(max(weights[waiting]))
            rmse_after.append(float(np.sqrt(np.nanmean(err[depart:depart + int(20.0 / DT)] ** 2))))
            # on the branch taken for good within 15 s of departing (measured: at most 10 s)
            assert all(rid == branch for rid in ids[depart + int(15.0 / DT):])
    assert np.mean(max_w) < 0.98
    assert np.mean(rmse_after) < 13.5
