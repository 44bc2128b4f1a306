"""The environments' parts that need no physics: observation and action encoding, the default reward, the loss of a
track, the configuration's checks and the collision log."""

import math

import numpy as np
import pytest

from interfaces.setpoints import UnicycleSetpoint, VelocitySetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState
from simulator.envs.config import EnvConfig, RewardConfig
from simulator.envs.episode import HeldSetpoint, Knowledge
from simulator.envs.event_log import EventLog
from simulator.envs.reward import RewardInputs, TrackHold, estimate_error, standoff_reward
from simulator.envs.spaces import ActionCodec, ObservationCodec
from vehicles.quadrotor.airframes import load_airframe

OWN = OwnState(t=2.0, p_W=np.array([1.0, 2.0, 60.0]), v_W=np.array([3.0, 4.0, 0.5]), yaw=math.pi / 2)


def knowledge(target=None, teammates=()):
    return Knowledge(t=2.0, own=OWN, target=target, teammates=tuple(teammates))


def test_observation_holds_own_state_estimate_covariance_and_teammates_by_world_index():
    P = np.arange(36, dtype=float).reshape(6, 6)  # 3-D estimate: (x, y, z, vx, vy, vz)
    est = TargetEstimate(t=1.5, p_W=np.array([10.0, 20.0, 0.0]), v_W=np.array([1.0, -1.0, 0.0]), P=P)
    mate = TeammateState(id=2, t=1.9, p_W=np.array([5.0, 6.0, 70.0]), v_W=np.array([0.1, 0.2, 0.3]))
    codec = ObservationCodec(n_uavs=3, uav=1, image=None)
    obs = codec.encode(knowledge(est, [mate]))
    assert codec.space.contains(obs)
    np.testing.assert_allclose(obs["own"], [1, 2, 60, 3, 4, 0.5, 0, 1], atol=1e-7)
    np.testing.assert_allclose(obs["target"], [1, 0.5, 10, 20, 1, -1])
    idx = [0, 1, 3, 4]  # x, y, vx, vy of the 6-state covariance
    np.testing.assert_array_equal(obs["target_cov"], P[np.ix_(idx, idx)].astype(np.float32))
    # rows are the other UAVs in world order (0, 2): UAV 0 not heard yet, UAV 2 heard 0.1 s ago
    np.testing.assert_allclose(obs["teammates"][0], np.zeros(8))
    np.testing.assert_allclose(obs["teammates"][1], [1, 0.1, 5, 6, 70, 0.1, 0.2, 0.3], rtol=1e-6)


def test_observation_without_an_estimate_is_zero_and_a_lone_uav_has_no_teammates():
    codec = ObservationCodec(n_uavs=1, uav=0, image=(4, 6))
    assert sorted(codec.space.spaces) == ["image", "own", "target", "target_cov"]
    obs = codec.encode(knowledge(), image=np.full((4, 6, 3), 7, dtype=np.uint8))
    assert codec.space.contains(obs)
    assert not obs["target"].any() and not obs["target_cov"].any()
    with pytest.raises(ValueError, match="the observation space has an image: pass the camera image"):
        codec.encode(knowledge())


def test_unicycle_action_is_clipped_to_the_airframe_envelope():
    frame = load_airframe("survey_quad")
    codec = ActionCodec("unicycle", frame, (10.0, 150.0))
    np.testing.assert_allclose(codec.space.low, [0.0, -frame.max_heading_rate, 10.0], rtol=1e-6)
    np.testing.assert_allclose(codec.space.high, [frame.max_speed, frame.max_heading_rate, 150.0], rtol=1e-6)
    sp = codec.setpoint(np.array([1e3, -1e3, 5.0]))
    assert sp == UnicycleSetpoint(speed=float(codec.space.high[0]), heading_rate=float(codec.space.low[1]),
                                  altitude=10.0)
    np.testing.assert_allclose(codec.action(UnicycleSetpoint(speed=3.0, heading_rate=0.1, altitude=60.0)),
                               [3.0, 0.1, 60.0], rtol=1e-6)
    with pytest.raises(ValueError, match=r"action must be 3 finite numbers \(unicycle\)"):
        codec.setpoint(np.array([1.0, np.nan, 60.0]))
    with pytest.raises(ValueError, match="a unicycle action cannot hold a VelocitySetpoint"):
        codec.action(VelocitySetpoint(v_W=np.zeros(3)))


def test_velocity_action_flies_a_velocity_set_point():
    frame = load_airframe("survey_quad")
    codec = ActionCodec("velocity", frame, (10.0, 150.0))
    sp = codec.setpoint(np.array([1.0, -2.0, -1e3]))
    assert isinstance(sp, VelocitySetpoint) and sp.yaw is None
    np.testing.assert_allclose(sp.v_W, [1.0, -2.0, -frame.max_climb_rate], rtol=1e-6)


def test_held_setpoint_keeps_the_knowledge_and_returns_the_learners_set_point():
    sp = UnicycleSetpoint(speed=2.0, heading_rate=0.0, altitude=50.0)
    law = HeldSetpoint(sp)
    mate = TeammateState(id=0, t=1.0, p_W=np.zeros(3), v_W=np.zeros(3))
    assert law.command(OWN, None, [mate], 2.0) is sp
    assert law.knowledge == Knowledge(t=2.0, own=OWN, target=None, teammates=(mate,))


def inputs(uav_xy, est_xy=None, collided=False, lost=False):
    est = None if est_xy is None else TargetEstimate(t=0.0, p_W=np.array(est_xy), v_W=np.zeros(2))
    return RewardInputs(t=1.0, uav_p_W=np.array([*uav_xy, 60.0]), target_p_W=np.zeros(3), estimate=est,
                        collided=collided, lost=lost, standoff_m=100.0)


def test_default_reward_closed_form():
    cfg = RewardConfig(w_standoff=2.0, w_error=3.0, error_scale_m=50.0, collision_penalty=100.0, lost_penalty=40.0)
    assert standoff_reward(cfg, inputs((100.0, 0.0), (0.0, 0.0))) == 0.0  # on the circle, estimate exact
    # 20 m inside the circle (0.2 of R), 10 m estimate error (0.2 of the scale)
    assert standoff_reward(cfg, inputs((80.0, 0.0), (6.0, 8.0))) == pytest.approx(-2.0 * 0.2 - 3.0 * 0.2)
    # each term saturates at its weight; no estimate costs the whole w_error
    assert standoff_reward(cfg, inputs((1000.0, 0.0))) == pytest.approx(-5.0)
    assert standoff_reward(cfg, inputs((100.0, 0.0), (0.0, 0.0), collided=True, lost=True)) == -140.0
    assert estimate_error(None, np.zeros(3)) == math.inf


def test_track_is_lost_after_lost_after_s_off_the_target():
    hold = TrackHold(radius_m=50.0, after_s=2.0)
    far = TargetEstimate(t=0.0, p_W=np.array([60.0, 0.0]), v_W=np.zeros(2))
    near = TargetEstimate(t=0.0, p_W=np.array([30.0, 40.0]), v_W=np.zeros(2))  # 50 m: held
    truth = np.zeros(3)
    assert not hold.update(1.9, None, truth)  # never acquired: counted from the start
    assert hold.update(2.0, None, truth)
    assert not hold.update(2.5, near, truth)
    assert not hold.update(4.4, far, truth)
    assert hold.update(4.5, far, truth)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"duration": 0.0}, "EnvConfig.duration must be > 0 s or None, got 0.0"),
    ({"action": "attitude"}, "EnvConfig.action must be one of ('unicycle', 'velocity'), got 'attitude'"),
    ({"altitude_range_m": (50.0, 20.0)}, "EnvConfig.altitude_range_m must be (low, high) with 0 < low < high m"),
    ({"image": (0, 8)}, "EnvConfig.image must be (height, width) in whole pixels >= 1, got (0, 8)"),
    ({"lost_after_s": -1.0}, "EnvConfig.lost_after_s must be > 0 s, got -1.0"),
    ({"render_camera": "orbit"}, "EnvConfig.render_camera must be 'chase' or 'topdown', got 'orbit'"),
], ids=["duration", "action", "altitude", "image", "lost_after", "camera"])
def test_env_config_names_the_bad_field(kwargs, message):
    with pytest.raises(ValueError) as err:
        EnvConfig(**kwargs)
    assert str(err.value).startswith(message)


def test_reward_config_names_the_bad_field():
    with pytest.raises(ValueError, match=r"RewardConfig.error_scale_m must be > 0 m, got 0.0"):
        RewardConfig(error_scale_m=0.0)
    with pytest.raises(ValueError, match=r"RewardConfig.w_error must be >= 0, got -1.0"):
        RewardConfig(w_error=-1.0)


def test_event_log_keeps_collisions_after_a_tick():
    log = EventLog()
    log.event("command_saturated", 3, 0.1, uav=0)
    log.event("collision", 48, 0.2, uav=1, uav_id="uav2", other="ground")
    assert log.event_counts == {"command_saturated": 1, "collision": 1}
    assert log.collided(1, after_tick=24) and not log.collided(1, after_tick=48) and not log.collided(0, 0)
