"""What the Gymnasium and PettingZoo environments share: the world, each learner's spaces, one episode at a time, and
the judging of each step (reward, collision, loss, end of time)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from interfaces.setpoints import UnicycleSetpoint
from simulator.envs.config import EnvConfig
from simulator.envs.episode import Episode
from simulator.envs.reward import Reward, RewardInputs, TrackHold, estimate_error, standoff_reward
from simulator.envs.spaces import ActionCodec, ObservationCodec
from simulator.envs.view import LiveView
from vehicles.quadrotor.airframes import load_airframe
from worlds.loader import LoadedWorld, load_world

__all__ = ["StepResult", "TrackingCore"]

_LOOK_AHEAD_M = 50.0  # without a target estimate the onboard camera looks this far ahead along the heading (m)


@dataclass(frozen=True)
class StepResult:
    """One learner's outcome of a step: the reward, whether its episode ended, and what is reported in ``info``."""

    reward: float
    terminated: bool
    truncated: bool
    info: dict[str, Any]


class TrackingCore:
    """One world and its learners, episode after episode.

    Parameters
    ----------
    config : EnvConfig
        The environment.
    learners : list of str | None
        The learning UAVs' ids; None = every UAV.
    reward : callable | None
        ``f(RewardInputs) -> float``; None = :func:`~simulator.envs.reward.standoff_reward` with ``config.reward``.
    """

    def __init__(self, config: EnvConfig, learners: list[str] | None = None, reward: Reward | None = None) -> None:
        self.config = config
        self.loaded = (config.world if isinstance(config.world, LoadedWorld)
                       else load_world(config.world, list(config.overrides)))
        world = self.loaded.world
        if not world.uavs:
            raise ValueError(f"world {world.name} has no UAV to learn with")
        self.uav_ids = [u.id for u in world.uavs]
        unknown = [u for u in learners or () if u not in self.uav_ids]
        if unknown:
            raise ValueError(f"no UAV {unknown[0]!r} in world {world.name}: its UAVs are {self.uav_ids}")
        self.learners = list(range(len(world.uavs))) if learners is None else [self.uav_ids.index(u) for u in learners]
        n = len(world.uavs)
        self.observations = {i: ObservationCodec(n, i, config.image) for i in self.learners}
        self.actions = {i: ActionCodec(config.action, load_airframe(world.uavs[i].airframe), config.altitude_range_m)
                        for i in self.learners}
        self.standoff_m = {i: config.reward.standoff_m or float(world.uavs[i].autonomy.guidance.standoff_m)
                           for i in self.learners}
        self.reward: Reward = reward or (lambda x: standoff_reward(config.reward, x))
        self.episode: Episode | None = None
        self.view: LiveView | None = None
        self.seed: int | None = None
        self._holds: dict[int, TrackHold] = {}

    # -- episodes ------------------------------------------------------------------------------------------------
    def start(self, seed: int) -> dict[int, dict[str, np.ndarray]]:
        """End the running episode and start one with run seed ``seed``; the learners' first observations."""
        self.close()
        self.seed = int(seed)
        self.episode = Episode(self.loaded, self.learners, self.seed, self.config.duration)
        self._holds = {i: TrackHold(self.config.lost_radius_m, self.config.lost_after_s) for i in self.learners}
        self.episode.advance()
        return {i: self.observe(i) for i in self.learners}

    def step(self, actions: dict[int, np.ndarray | None]) -> dict[int, StepResult]:
        """Give each learner in ``actions`` its set-point (None: keep the last one), run to the learners' next autonomy
        step and judge the learners in ``actions``."""
        ep = self._running()
        setpoints = {i: self.actions[i].setpoint(a) for i, a in actions.items() if a is not None}  # all checked first
        for i, sp in setpoints.items():
            ep.act(i, sp)
        before = ep.tick
        ep.advance()
        target = ep.target_truth()
        out = {}
        for i in actions:
            est = ep.knowledge(i).target
            collided = ep.log.collided(i, before)
            lost = self._holds[i].update(ep.t, est, target)
            x = RewardInputs(t=ep.t, uav_p_W=ep.uav_truth(i), target_p_W=target, estimate=est, collided=collided,
                             lost=lost, standoff_m=self.standoff_m[i])
            info = {"t": ep.t, "seed": self.seed, "collided": collided, "lost": lost,
                    # truth, for evaluating a policy: never part of its observation
                    "estimate_error_m": estimate_error(est, target),
                    "target_distance_m": float(np.hypot(*(x.uav_p_W[:2] - target[:2])))}
            out[i] = StepResult(reward=float(self.reward(x)), terminated=bool(collided or lost),
                                truncated=ep.finished and not (collided or lost), info=info)
        return out

    def stop(self, uav: int) -> None:
        """Hold UAV ``uav`` where it is (an agent whose episode ended while the others fly on)."""
        ep = self._running()
        z = float(ep.uav_truth(uav)[2])
        ep.act(uav, UnicycleSetpoint(speed=0.0, heading_rate=0.0, altitude=max(z, 1.0)))

    def _running(self) -> Episode:
        if self.episode is None:
            raise RuntimeError("no episode is running: call reset() first")
        return self.episode

    # -- observations and frames ---------------------------------------------------------------------------------
    def observe(self, uav: int) -> dict[str, np.ndarray]:
        """Learner ``uav``'s observation: its autonomy's knowledge at its last step (and the onboard image)."""
        ep = self._running()
        k = ep.knowledge(uav)
        image = None
        if self.config.image is not None:
            if k.target is not None:
                look = np.array([k.target.p_W[0], k.target.p_W[1], 0.0])
            else:
                look = k.own.p_W + _LOOK_AHEAD_M * np.array([np.cos(k.own.yaw), np.sin(k.own.yaw), 0.0])
                look[2] = 0.0
            image = self._view().frame("onboard", uav, look, self.config.image)
        return self.observations[uav].encode(k, image)

    def render(self, uav: int) -> np.ndarray:
        """A frame of the running episode (``config.render_camera``, ``config.render_size``) around UAV ``uav``."""
        ep = self._running()
        return self._view().frame(self.config.render_camera, uav, ep.target_truth(), self.config.render_size)

    def _view(self) -> LiveView:
        if self.view is None:
            self.view = LiveView(self._running(), self.loaded.world)
        return self.view

    def close(self) -> None:
        """End the running episode and free its PyBullet clients (idempotent)."""
        if self.view is not None:
            self.view.close()
            self.view = None
        if self.episode is not None:
            self.episode.close()
            self.episode = None
