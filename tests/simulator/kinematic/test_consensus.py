"""Paper 000's closed loop: the scripted target drive, and SCIF + HCMCI + fast MPC tracking it within the paper's
bounds."""

import numpy as np
import pytest

from simulator.kinematic.consensus import STOP_AND_GO, ConsensusLoopConfig, run_consensus_loop, target_drive


def test_target_drive_follows_its_script():
    dt = 0.5
    x = target_drive(400, dt)
    speed = np.hypot(x[:, 1], x[:, 4])
    assert speed[0] == 0.0 and x[0, 0] == 4500.0 and x[0, 3] == -8.0
    assert speed[int(10 / dt)] == pytest.approx(6.0, abs=1e-9)  # 0.6 m/s² for 10 s
    # after the first turn (15 s at π/30 rad/s) the heading has turned by 90°
    k = int((10 + 25 + 15) / dt)
    assert np.arctan2(x[k, 4], x[k, 1]) == pytest.approx(np.pi / 2, abs=1e-6)
    stop = int((10 + 25 + 15 + 20 + 8 + 6) / dt)  # mid-stop
    assert speed[stop] == pytest.approx(0.0, abs=1e-9)
    assert sum(s[0] for s in STOP_AND_GO) == pytest.approx(200.0)


def test_case_1_tracks_agrees_and_keeps_separation():
    r = run_consensus_loop(ConsensusLoopConfig(case=1, steps=80), np.random.default_rng(4))
    late = slice(20, None)
    assert np.all(r.error[late].mean(axis=0) < 10.0)
    assert r.consensus_error[late].mean() < 0.05
    assert r.separation.min() >= 10.0
    assert np.all(np.abs(r.inputs[..., 1]) <= 5.0 + 1e-9) and np.all(r.inputs[..., 0] >= -1e-9)


def test_case_2_cuts_the_scheduled_links():
    cfg = ConsensusLoopConfig(case=2)
    assert cfg.outage_links(149) == [] and cfg.outage_links(150) == [(0, 2)] and cfg.outage_links(320) == [(0, 3)]
    assert cfg.uav_weights(0) == (5, 180, 0.2, 0.2) and cfg.uav_weights(1) == (4, 180, 0.4, 0.5)
    assert ConsensusLoopConfig(case=1).outage_links(160) == []
