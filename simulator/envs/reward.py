"""Rewards and the ends of an episode, judged on truth (which the observation never holds).

A reward is :func:`standoff_reward` with a :class:`~simulator.envs.config.RewardConfig`, or any callable
``f(RewardInputs) -> float``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from interfaces.state import TargetEstimate
from simulator.envs.config import RewardConfig

__all__ = ["Reward", "RewardInputs", "TrackHold", "estimate_error", "standoff_reward"]


@dataclass(frozen=True)
class RewardInputs:
    """What one learner step is judged on.

    Attributes
    ----------
    t : float
        Simulated time at the end of the step (s).
    uav_p_W : np.ndarray
        (3,) true UAV position (m).
    target_p_W : np.ndarray
        (3,) true target position (m).
    estimate : TargetEstimate | None
        The learner's target estimate at its last autonomy step.
    collided : bool
        The UAV began a contact during the step.
    lost : bool
        The track was lost during the step (:class:`TrackHold`).
    standoff_m : float
        The standoff radius of the episode (m).
    """

    t: float
    uav_p_W: np.ndarray
    target_p_W: np.ndarray
    estimate: TargetEstimate | None
    collided: bool
    lost: bool
    standoff_m: float


Reward = Callable[[RewardInputs], float]


def estimate_error(estimate: TargetEstimate | None, target_p_W: np.ndarray) -> float:
    """Horizontal distance from ``estimate`` to the true target (m); infinite without an estimate."""
    if estimate is None:
        return float("inf")
    return float(np.hypot(*(estimate.p_W[:2] - target_p_W[:2])))


def standoff_reward(config: RewardConfig, x: RewardInputs) -> float:
    """The default reward of :class:`~simulator.envs.config.RewardConfig` (its docstring has the formula)."""
    d = float(np.hypot(*(x.uav_p_W[:2] - x.target_p_W[:2])))
    standoff = min(abs(d - x.standoff_m) / x.standoff_m, 1.0)
    error = min(estimate_error(x.estimate, x.target_p_W) / config.error_scale_m, 1.0)
    r = -config.w_standoff * standoff - config.w_error * error
    r -= config.collision_penalty * float(x.collided) + config.lost_penalty * float(x.lost)
    return float(r)


class TrackHold:
    """Whether a UAV still holds its track: the track is lost once the estimate has stayed away from the true target
    (farther than ``radius_m`` horizontally, or absent) for ``after_s`` seconds without a break, counted from the
    start of the episode (so a track never acquired is lost too).

    Parameters
    ----------
    radius_m : float
        Horizontal distance within which the estimate is on the target (m).
    after_s : float
        Time off the target that loses the track (s).
    """

    def __init__(self, radius_m: float, after_s: float) -> None:
        self.radius_m, self.after_s = float(radius_m), float(after_s)
        self.last_held_t = 0.0

    def update(self, t: float, estimate: TargetEstimate | None, target_p_W: np.ndarray) -> bool:
        """Record the estimate at ``t`` (s); True when the track is lost."""
        if estimate_error(estimate, target_p_W) <= self.radius_m:
            self.last_held_t = t
        return t - self.last_held_t >= self.after_s
