"""Every UAV of a world a learning agent, in a PettingZoo parallel environment.

>>> from simulator.envs import parallel_env
>>> env = parallel_env(world="road_standoff", duration=30.0)           # doctest: +SKIP
>>> obs, infos = env.reset(seed=3)                                       # doctest: +SKIP
>>> acts = {a: env.action_space(a).sample() for a in env.agents}        # doctest: +SKIP
>>> obs, rewards, terms, truncs, infos = env.step(acts)                  # doctest: +SKIP

Agents are the UAV ids. Observations, actions and rewards are those of the Gymnasium environment
(:mod:`simulator.envs.gym_env`), one per agent; a step is one autonomy step, so every UAV must run its autonomy at one
rate. An agent that collides or loses its track leaves ``agents`` and its UAV holds where it is (speed 0 at its
altitude) while the others fly on; all leave, truncated, at the episode's duration.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from simulator.envs.config import EnvConfig, RewardConfig
from simulator.envs.core import TrackingCore
from simulator.envs.reward import Reward

__all__ = ["TrackingParallelEnv", "parallel_env"]

_SEED_BOUND = 2**31


class TrackingParallelEnv(ParallelEnv):
    """Every UAV of the world learning (see the module docstring; parameters as
    :class:`~simulator.envs.gym_env.TrackingEnv`, less ``uav``)."""

    metadata = {"name": "skytrack_tracking_v0", "render_modes": ["rgb_array"], "render_fps": 4,
                "is_parallelizable": True}

    def __init__(self, world: Any = "road_standoff", render_mode: str | None = None,
                 reward: RewardConfig | Reward | None = None, **settings: Any) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}")
        if "uav" in settings:
            raise ValueError("parallel_env: every UAV is an agent, there is no 'uav' to choose")
        if isinstance(reward, RewardConfig):
            settings["reward"] = reward
        self.core = TrackingCore(EnvConfig(world=world, **settings),
                                 reward=None if isinstance(reward, RewardConfig) else reward)
        rates = {u.autonomy.rate_hz for u in self.core.loaded.world.uavs}
        if len(rates) != 1:
            raise ValueError(f"parallel_env needs every UAV's autonomy at one rate; world "
                             f"{self.core.loaded.world.name} has {sorted(rates)} Hz")
        self.render_mode = render_mode
        self.possible_agents = list(self.core.uav_ids)
        self.agents: list[str] = []
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self._obs_spaces = {a: self.core.observations[i].space for a, i in self._index.items()}
        self._act_spaces = {a: self.core.actions[i].space for a, i in self._index.items()}
        self.metadata = {**self.metadata, "render_fps": float(rates.pop())}
        self._rng = np.random.default_rng()

    def observation_space(self, agent: str) -> spaces.Space:
        return self._obs_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        return self._act_spaces[agent]

    def reset(self, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        run_seed = int(seed) if seed is not None else int(self._rng.integers(_SEED_BOUND))
        obs = self.core.start(run_seed)
        self.agents = list(self.possible_agents)
        t = self.core.episode.t
        return ({a: obs[self._index[a]] for a in self.agents},
                {a: {"t": t, "seed": run_seed} for a in self.agents})

    def step(self, actions: dict[str, np.ndarray]) -> tuple[dict[str, Any], dict[str, float], dict[str, bool],
                                                             dict[str, bool], dict[str, dict[str, Any]]]:
        unknown = set(actions) - set(self.agents)
        if unknown:
            raise ValueError(f"actions for agents that are not live: {sorted(unknown)} (live: {self.agents})")
        results = self.core.step({self._index[a]: actions.get(a) for a in self.agents})  # none given: keep the last
        live = list(self.agents)
        obs = {a: self.core.observe(self._index[a]) for a in live}
        rewards = {a: results[self._index[a]].reward for a in live}
        terms = {a: results[self._index[a]].terminated for a in live}
        truncs = {a: results[self._index[a]].truncated for a in live}
        infos = {a: results[self._index[a]].info for a in live}
        for a in live:
            if terms[a] and not truncs[a]:
                self.core.stop(self._index[a])
        self.agents = [a for a in self.agents if not (terms.get(a) or truncs.get(a))]
        return obs, rewards, terms, truncs, infos

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            return None
        return self.core.render(0)

    def state(self) -> np.ndarray:
        raise NotImplementedError("a global state is truth, which this environment keeps out of observations")

    def close(self) -> None:
        self.core.close()


def parallel_env(world: Any = "road_standoff", render_mode: str | None = None, **settings: Any) -> TrackingParallelEnv:
    """The PettingZoo parallel environment of ``world`` (every UAV an agent; :class:`TrackingParallelEnv`)."""
    return TrackingParallelEnv(world=world, render_mode=render_mode, **settings)
