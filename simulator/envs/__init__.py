"""Gymnasium and PettingZoo environments of the shipped (and any) worlds: ``import simulator.envs`` registers
``skytrack/Tracking-v0`` (:mod:`simulator.envs.gym_env`); :func:`parallel_env` is the PettingZoo parallel
environment (:mod:`simulator.envs.parallel`)."""

from gymnasium.envs.registration import register, registry

from simulator.envs.config import EnvConfig, RewardConfig
from simulator.envs.gym_env import TrackingEnv
from simulator.envs.parallel import TrackingParallelEnv, parallel_env
from simulator.envs.reward import RewardInputs

__all__ = ["EnvConfig", "RewardConfig", "RewardInputs", "TrackingEnv", "TrackingParallelEnv", "parallel_env"]

if "skytrack/Tracking-v0" not in registry:  # a module imported twice (reloads, tests) must not register twice
    register(id="skytrack/Tracking-v0", entry_point="simulator.envs.gym_env:TrackingEnv")
