"""The PettingZoo parallel environment on short episodes of the demo world: PettingZoo's own API test, every UAV an
agent, an agent leaving on its own collision while the others fly on, and the one-rate rule."""

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test

from simulator.envs import parallel_env


def test_passes_pettingzoos_parallel_api_test():
    env = parallel_env(world="demo", duration=2.0)
    parallel_api_test(env, num_cycles=30)
    env.close()


def test_every_uav_is_an_agent_with_the_gym_spaces():
    env = parallel_env(world="demo", duration=1.0)
    assert env.possible_agents == ["uav1", "uav2"]
    obs, infos = env.reset(seed=3)
    assert env.agents == ["uav1", "uav2"] and infos["uav2"] == {"t": 0.1, "seed": 3}
    for a in env.agents:
        assert env.observation_space(a).contains(obs[a])
        assert env.observation_space(a) is env.observation_space(a)
    np.testing.assert_allclose(obs["uav2"]["own"][:3], [360.0, 260.0, 60.0], atol=0.5)  # uav2 starts there
    env.close()


def test_a_colliding_agent_leaves_while_the_others_fly_on():
    env = parallel_env(world="demo", duration=3.0, action="velocity",
                       overrides=("uavs[1].initial.position=[360,260,3]",))
    env.reset(seed=1)
    down, level = np.array([0.0, 0.0, -5.0], np.float32), np.zeros(3, np.float32)
    for _ in range(20):
        obs, rewards, terms, truncs, infos = env.step({a: down if a == "uav2" else level for a in env.agents})
        if terms.get("uav2"):
            break
    assert terms == {"uav1": False, "uav2": True} and infos["uav2"]["collided"]
    assert rewards["uav2"] <= -100.0 < rewards["uav1"]
    assert env.agents == ["uav1"]
    obs, rewards, terms, truncs, infos = env.step({"uav1": level})
    assert list(obs) == ["uav1"]
    with pytest.raises(ValueError, match=r"actions for agents that are not live: \['uav2'\]"):
        env.step({"uav1": level, "uav2": level})
    env.close()


def test_refuses_uavs_at_different_autonomy_rates():
    with pytest.raises(ValueError, match=r"parallel_env needs every UAV's autonomy at one rate; world demo has "
                                         r"\[5.0, 10.0\] Hz"):
        parallel_env(world="demo", overrides=("uavs[1].autonomy.rate_hz=5",))
