"""``skytrack/Tracking-v0`` on short episodes of the demo world: Gymnasium's own checker, reproducible seeding, the
first observation being the run's own knowledge, the ends of an episode, rendering, and no PyBullet client left
behind."""

import warnings

import gymnasium
import numpy as np
import pybullet as p
import pytest
from gymnasium.utils.env_checker import check_env

import simulator.envs  # noqa: F401 - registers skytrack/Tracking-v0
from simulator.api import run
from simulator.envs.episode import HeldSetpoint

ADVISORY = ("A Box observation space minimum value is -infinity", "A Box observation space maximum value is infinity",
            "For Box action spaces, we recommend using a symmetric and normalized space")
"""check_env's advice on unbounded observations (positions in a world frame have no bound) and on physical actions
(the action is the set-point; RescaleAction maps [-1, 1] onto it): anything else it says fails the test."""


def make(**kw):
    kw.setdefault("world", "demo")
    kw.setdefault("duration", 2.0)
    return gymnasium.make("skytrack/Tracking-v0", **kw)


def connected_clients() -> int:
    return sum(p.isConnected(i) for i in range(64))


def rollout(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        obs, *_ = env.step(a)
        out.append(obs)
    return out


def test_passes_gymnasiums_env_checker():
    env = make(render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    other = [str(w.message) for w in caught if not any(a in str(w.message) for a in ADVISORY)]
    assert other == []
    env.close()


def test_a_fixed_seed_gives_identical_observations_twice_and_another_seed_differs():
    actions = [np.array([8.0, 0.2 * np.sin(k), 60.0 + k], dtype=np.float32) for k in range(12)]
    env = make()
    first = rollout(env, 7, actions)
    again = rollout(env, 7, actions)  # same environment, reset again
    env.close()
    fresh = make()
    other_env = rollout(fresh, 7, actions)  # a new environment
    other_seed = rollout(fresh, 8, actions)
    fresh.close()
    for a, b, c in zip(first, again, other_env, strict=True):
        for key in a:
            assert np.array_equal(a[key], b[key]) and np.array_equal(a[key], c[key]), key
    assert not np.array_equal(first[-1]["target"], other_seed[-1]["target"])


def test_first_observation_is_what_the_uavs_autonomy_knew_in_the_run_of_that_seed(tmp_path):
    env = make(uav="uav2")
    obs, info = env.reset(seed=4)
    env.close()
    assert info == {"t": 0.1, "seed": 4, "uav": "uav2"}
    rec = run("demo", duration=0.5, seed=4, out_dir=tmp_path, plots=False)
    truth = rec.stream("uav_truth", uav=1)
    k = int(np.flatnonzero(np.isclose(truth["t"], 0.1))[0])
    np.testing.assert_allclose(obs["own"][:6], [truth[c][k] for c in ("x", "y", "z", "vx", "vy", "vz")],
                               rtol=1e-6, atol=1e-5)
    fused = rec.stream("fused_estimates", uav=1)  # demo's UAVs fuse: guidance flies on the fused estimate
    j = int(np.flatnonzero(np.isclose(fused["t"], 0.1))[0])
    assert obs["target"][0] == 1.0
    np.testing.assert_allclose(obs["target"][2:6], [fused[c][j] for c in ("x", "y", "vx", "vy")], rtol=1e-6)


def test_the_chosen_uav_learns_and_the_others_fly_their_world_autonomy():
    env = make(uav="uav2", duration=1.0)
    env.reset(seed=1)
    agents = env.unwrapped.core.episode.assembly.agents
    assert [type(a.agent.guidance).__name__ for a in agents] == ["VectorFieldGuidance", "HeldSetpoint"]
    assert isinstance(agents[1].agent.guidance, HeldSetpoint)
    env.close()
    with pytest.raises(ValueError, match=r"no UAV 'uav9' in world demo: its UAVs are \['uav1', 'uav2'\]"):
        make(uav="uav9")


def test_the_action_is_flown_at_the_autonomy_rate_until_truncation():
    env = make(duration=3.0)
    env.reset(seed=1)
    steps, up = 0, np.array([0.0, 0.0, 110.0], dtype=np.float32)  # hover, climb to 110 m
    while True:
        obs, reward, terminated, truncated, info = env.step(up)
        steps += 1
        if terminated or truncated:
            break
    env.close()
    assert (steps, terminated, truncated, info["t"]) == (29, False, True, 3.0)  # 10 Hz, first observation at 0.1 s
    assert obs["own"][2] > 70.0  # climbed from 60 m
    assert np.hypot(*obs["own"][3:5]) < 0.5


def test_collision_terminates_with_the_penalty():
    env = make(duration=5.0, action="velocity", overrides=("uavs[0].initial.position=[-60,-60,4]",))
    env.reset(seed=1)
    for _ in range(45):
        obs, reward, terminated, truncated, info = env.step(np.array([0.0, 0.0, -5.0], dtype=np.float32))
        if terminated or truncated:
            break
    env.close()
    assert (terminated, truncated, info["collided"], info["lost"]) == (True, False, True, False)
    assert -102.0 <= reward <= -100.0


def test_lost_track_terminates():
    env = make(duration=5.0, lost_after_s=0.5, lost_radius_m=1e-3)
    env.reset(seed=1)
    hover = np.array([0.0, 0.0, 60.0], dtype=np.float32)
    results = [env.step(hover) for _ in range(4)]
    env.close()
    assert [r[2] for r in results] == [False, False, False, True]
    assert results[-1][4]["t"] == 0.5 and results[-1][4]["lost"]


def test_a_reward_callable_sees_truth_and_the_estimate():
    seen = []
    env = make(reward=lambda x: seen.append(x) or -x.t)
    env.reset(seed=1)
    _, reward, *_ , info = env.step(env.action_space.sample())
    env.close()
    assert reward == -0.2 and seen[0].t == 0.2 and seen[0].standoff_m == 100.0  # demo's uav1 standoff
    assert seen[0].estimate is not None
    assert info["estimate_error_m"] == pytest.approx(np.hypot(*(seen[0].estimate.p_W[:2] - seen[0].target_p_W[:2])))


def test_rgb_array_frames_and_the_onboard_image():
    env = make(render_mode="rgb_array", image=(24, 32), render_size=(60, 80))
    obs, _ = env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (60, 80, 3) and frame.dtype == np.uint8 and frame.std() > 1.0
    assert obs["image"].shape == (24, 32, 3) and obs["image"].std() > 1.0
    assert env.observation_space.contains(obs)
    env.close()


def test_resets_and_close_leave_no_pybullet_client():
    before = connected_clients()
    env = make(render_mode="rgb_array", image=(8, 8), duration=0.5)
    for seed in range(3):
        env.reset(seed=seed)
        env.step(env.action_space.sample())
        env.render()
        assert connected_clients() == before + 2  # the episode's physics and its renderer's stage
    env.close()
    env.close()
    assert connected_clients() == before


def test_road_standoff_default_learner_steps_at_two_hertz_beside_the_nmpc_uav():
    env = gymnasium.make("skytrack/Tracking-v0", world="road_standoff", duration=1.5)
    obs, info = env.reset(seed=2)
    assert (info["t"], info["uav"]) == (0.5, "uav1")  # the world's 2 Hz autonomy: first step at 0.5 s
    agents = env.unwrapped.core.episode.assembly.agents
    assert [type(a.agent.guidance).__name__ for a in agents] == ["HeldSetpoint", "NmpcStandoffGuidance"]
    ends = [env.step(np.array([12.0, 0.0, 60.0], np.float32))[2:4] for _ in range(2)]
    env.close()
    assert ends == [(False, False), (False, True)]
    with pytest.raises(ValueError, match=r"UAV uav1 searches with set fusion, whose guidance is the team's decision"):
        make(world="search_decoys").reset(seed=1)
