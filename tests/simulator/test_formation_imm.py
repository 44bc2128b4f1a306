"""Paper 003's world: three bearing-only quadrotors share their bearings, each runs the IMM on the team's stacked
bearings and flies the FIM-optimal formation around a car (physics runs of ``formation_imm``, case 1: a straight
road)."""

import numpy as np
import pytest

from autonomy.metrics.fim import bearing_fim, max_det_bearing_fim
from simulator.api import run

DURATION = 30.0
SETTLED = 15.0
"""s: the car pulls away from rest (≈ 7 s to 10 m/s), the tracks start from triangulated fixes with a velocity
prior, and the team turns into the optimal geometry; after this the estimates and the formation are steady."""
SIGMA = np.radians(5.73)  # the world's bearing noise (rad)
TRAIL = [f"uavs[{i}].autonomy.guidance.formation={{geometry: trail}}" for i in range(3)]


def _geometry(res):
    """Per recorded truth sample: times (K,), UAV positions (K, 3, 3), car (K, 2)."""
    ut, vt = res.stream("uav_truth"), res.stream("vehicle_truth")
    uavs = np.stack([np.c_[ut["x"], ut["y"], ut["z"]][ut["uav"] == k] for k in range(3)], axis=1)
    return ut["t"][ut["uav"] == 0], uavs, np.c_[vt["x"], vt["y"]]


def _log_det_gap(uavs, car):
    """(K,) ln of the det F bound for the UAVs' ranges minus ln det F of their geometry (0: optimal)."""
    gaps = []
    for p, c in zip(uavs[:, :, :2], car, strict=True):
        c2 = 1.0 / (SIGMA**2 * np.sum((p - c) ** 2, axis=1))
        gaps.append(np.log(max_det_bearing_fim(c2)) - np.log(np.linalg.det(bearing_fim(c, p, SIGMA))))
    return np.array(gaps)


@pytest.fixture(scope="module")
def case1(tmp_path_factory):
    return run("formation_imm", duration=DURATION, seed=1, out_dir=tmp_path_factory.mktemp("formation_imm"))


def test_every_uav_tracks_on_its_teammates_bearings(case1):
    assert case1.status == "completed", case1.error
    sh = case1.stream("measurement_sharing")
    scans = int(DURATION * 10)
    for k in range(3):
        last = {c: sh[c][sh["uav"] == k][-1] for c in ("received", "own_used", "mates_used")}
        assert last["received"] == 2 * scans  # both teammates' bearings, every scan (perfect radio)
        # every update stacks the two shared bearings with the own one (the 99.9 % gate may refuse a rare one; the
        # two first scans start the track)
        assert last["own_used"] >= scans - 5
        assert last["mates_used"] >= 2 * last["own_used"] - 5
        assert case1.metrics["uavs"][f"uav{k + 1}"]["collisions"] == 0


def test_the_estimate_beats_a_single_scan_of_the_team(case1):
    est = case1.stream("estimates")
    t_geo, uavs, car = _geometry(case1)
    for k in range(3):
        s = (est["uav"] == k) & est["valid"]
        t = est["t"][s]
        assert t[0] <= 0.3  # the track starts from the first two scans' triangulated fixes
        truth = case1.target_truth_at(t)
        err = np.hypot(est["x"][s] - truth[:, 0], est["y"][s] - truth[:, 1])[t >= SETTLED]
        # one scan of the three bearings fixes the car to √trace(F⁻¹) (the CRLB of that geometry, ≈ 16 m at the
        # 115–170 m ranges flown); the IMM at 10 Hz must do far better (measured: mean 3.6 m, 95th pct 6.0 m)
        late = t_geo >= SETTLED
        single = np.array([np.sqrt(np.trace(np.linalg.inv(bearing_fim(c, p[:, :2], SIGMA))))
                           for p, c in zip(uavs[late], car[late], strict=True)])
        assert err.mean() < 0.4 * single.mean()
        assert np.percentile(err, 95) < 0.8 * single.mean()


def test_the_team_holds_the_optimal_geometry_and_its_separation(case1):
    t, uavs, car = _geometry(case1)
    gap = _log_det_gap(uavs, car)[t >= SETTLED]
    # Algorithm 1 around the estimate, flown by quadrotors: within 0.05 of the bound on average (measured 0.013;
    # the trailing fan sits near 1.8) and never 0.2 away (measured 0.03)
    assert gap.mean() < 0.05 and gap.max() < 0.2
    dist = [np.linalg.norm(uavs[:, i] - uavs[:, j], axis=1).min() for i in range(3) for j in range(i + 1, 3)]
    assert min(dist) > 8.0  # 10 m between the altitudes; the horizontal geometry keeps them apart


@pytest.mark.slow
def test_the_trailing_fan_is_the_poorer_geometry(tmp_path):
    trail = run("formation_imm", duration=DURATION, seed=1, overrides=TRAIL, out_dir=tmp_path)
    assert trail.status == "completed", trail.error
    t, uavs, car = _geometry(trail)
    gap = _log_det_gap(uavs, car)[t >= SETTLED]
    assert gap.mean() > 1.0  # nearly parallel bearing lines (measured 1.8): far from the bound the optimum reaches


def test_over_a_radio_with_a_delay_of_one_agent_period_every_bearing_is_still_used(tmp_path):
    res = run("formation_imm", duration=6.0, seed=2, out_dir=tmp_path,
              overrides=["comms.model=rayleigh", "comms.latency_s=0.1"])
    assert res.status == "completed", res.error
    comms = res.metrics["comms"]
    assert comms["lost"] == 0 and comms["in_flight"] > 0  # ≈ 100 m apart: exp(−(d / 1 km)³) ≈ 1; the last in flight
    sh = res.stream("measurement_sharing")
    for k in range(3):
        i = np.flatnonzero(sh["uav"] == k)[-1]
        # each copy arrives with the next scan and updates the track at its own time, after the own bearing
        assert sh["received"][i] == 2 * (60 - 1)
        assert sh["mates_used"][i] >= 2 * sh["own_used"][i] - 5
