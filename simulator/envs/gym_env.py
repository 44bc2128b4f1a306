"""``skytrack/Tracking-v0``: one learning UAV of a world in a Gymnasium environment.

>>> import gymnasium, simulator.envs
>>> env = gymnasium.make("skytrack/Tracking-v0", world="road_standoff", duration=30.0)   # doctest: +SKIP
>>> obs, info = env.reset(seed=3)                                                       # doctest: +SKIP

One ``step`` is one autonomy step of the learner (the world's ``autonomy.rate_hz``): its action, a set-point
(:mod:`simulator.envs.spaces`), is flown while the physics, the sensors and every other UAV's world-file autonomy run
underneath, until the learner's next autonomy step, whose knowledge is the next observation. ``reset(seed=s)`` starts
the run ``skytrack run <world> --seed s`` would (same seed, same streams); without a seed, a seed is drawn from the
environment's generator. ``terminated`` on a collision of the learner's UAV or a lost track, ``truncated`` at the
episode's duration.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np

from simulator.envs.config import EnvConfig, RewardConfig
from simulator.envs.core import TrackingCore
from simulator.envs.reward import Reward
from worlds.loader import LoadedWorld, load_world

__all__ = ["TrackingEnv"]

_SEED_BOUND = 2**31  # run seeds drawn by reset() without a seed lie in [0, _SEED_BOUND)


class TrackingEnv(gym.Env):
    """One learning UAV tracking the world's target.

    Parameters
    ----------
    world : str | Path | LoadedWorld
        A shipped world's name, a world file or a loaded world.
    render_mode : {"rgb_array"} | None
        ``rgb_array``: ``render()`` returns an (H, W, 3) frame from the off-screen renderer.
    reward : RewardConfig | callable | None
        The default reward's weights, or ``f(RewardInputs) -> float`` (:mod:`simulator.envs.reward`).
    **settings
        The other fields of :class:`~simulator.envs.config.EnvConfig`: ``uav``, ``duration``, ``overrides``,
        ``action``, ``image``, ``lost_radius_m``, ``lost_after_s``, ``render_size``, ``render_camera`` ...
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, world: Any = "road_standoff", render_mode: str | None = None,
                 reward: RewardConfig | Reward | None = None, **settings: Any) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}")
        if isinstance(reward, RewardConfig):
            settings["reward"] = reward
        config = EnvConfig(world=world, **settings)
        loaded = config.world if isinstance(config.world, LoadedWorld) else load_world(config.world, config.overrides)
        first = [u.id for u in loaded.world.uavs][:1]
        self.core = TrackingCore(replace(config, world=loaded),
                                 [config.uav] if config.uav is not None else first,
                                 reward=None if isinstance(reward, RewardConfig) else reward)
        self.uav = learner = self.core.learners[0]
        self.uav_id = self.core.uav_ids[learner]
        self.render_mode = render_mode
        self.observation_space = self.core.observations[learner].space
        self.action_space = self.core.actions[learner].space
        self.metadata = {**self.metadata, "render_fps": float(self.core.loaded.world.uavs[learner].autonomy.rate_hz)}

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        run_seed = int(seed) if seed is not None else int(self.np_random.integers(_SEED_BOUND))
        obs = self.core.start(run_seed)[self.uav]
        ep = self.core.episode
        return obs, {"t": ep.t, "seed": run_seed, "uav": self.uav_id}

    def step(self, action: np.ndarray) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        res = self.core.step({self.uav: action})[self.uav]
        return self.core.observe(self.uav), res.reward, res.terminated, res.truncated, res.info

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode: pass render_mode='rgb_array' to make()")
            return None
        return self.core.render(self.uav)

    def setpoint_action(self, setpoint: Any) -> np.ndarray:
        """The action that flies ``setpoint`` (a set-point of the env's action kind): for scripted policies."""
        return self.core.actions[self.uav].action(setpoint)

    def close(self) -> None:
        self.core.close()
        super().close()
