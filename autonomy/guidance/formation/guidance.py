"""FIM-optimal formation guidance: each agent computes the team's optimal geometry around the target estimate
(:mod:`.geometry`) and the Jacobi PD acceleration (:mod:`.jacobi`), and flies its own share as a velocity set-point.

The paper's agents are double integrators. A quadrotor's velocity controller is the plant here, so the acceleration
``a_i`` of the PD law is realised by commanding the velocity one guidance step ahead::

    v_i^cmd = v_i + a_i Δt,   |v_i^cmd| ≤ v_max

which for a velocity-tracking plant is the Euler step of p̈_i = a_i. Altitude is held by ``v_z = k_z (z_d − z)``.
The decision is the same in every agent (same inputs, deterministic), so the team needs no central planner.

``geometry="trail"`` replaces Algorithm 1 by a geometry that is not optimised, as a baseline: the agents fly a narrow
fan behind the target, bearings ``±trail_fan`` around the direction opposite to its velocity (agent i at the i-th of N
evenly spaced angles), at the desired ranges (the mean current range when ``ranges`` is None). Its nearly parallel
bearing lines are the poor geometry Algorithm 1 avoids; the PD law and limits are the same.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from autonomy.guidance.base import Guidance
from autonomy.guidance.formation.geometry import OptimalFormation, optimal_formation
from autonomy.guidance.formation.jacobi import JacobiGains, jacobi_pd_acceleration
from autonomy.metrics.fim import bearing_fim_from_directions, max_det_bearing_fim
from interfaces.setpoints import VelocitySetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState

__all__ = ["FormationConfig", "FormationStep", "FormationGuidance", "formation_step", "trail_formation"]


@dataclass(frozen=True, kw_only=True)
class FormationConfig:
    """Configuration of the FIM-optimal formation.

    Attributes
    ----------
    team_size : int
        Number of agents N, >= 2.
    sigma_bearing : float
        Bearing noise standard deviation σ (rad), > 0; scales det F only, not the optimal directions.
    ranges : tuple[float, ...] | None
        Desired range of each agent to the target (m), N values > 0; ``None`` keeps each agent's current range
        (the paper's Algorithm 1 input).
    gains : JacobiGains
        PD gains in Jacobi coordinates.
    dt : float
        Guidance step Δt (s), > 0, over which the acceleration is realised as a velocity change.
    max_speed : float
        Horizontal speed limit (m/s), > 0.
    backward_weight : float
        Penalty weight w_b on moves against the target's direction of travel (dimensionless), >= 0.
    n_rotations : int
        Coarse grid size of the free rotation search (refined 40-fold around the best), >= 4.
    altitude : float
        Altitude held (m).
    altitude_gain : float
        k_z of the altitude hold (1/s), >= 0.
    geometry : {"optimal", "trail"}
        Algorithm 1's det F-optimal geometry, or the trailing fan of the module docstring (a baseline).
    trail_fan : float
        Half-angle of the trailing fan (rad), in (0, π/2]; only with ``geometry="trail"``.
    """

    team_size: int = 3
    sigma_bearing: float = 0.01
    ranges: tuple[float, ...] | None = None
    gains: JacobiGains = field(default_factory=JacobiGains)
    dt: float = 0.1
    max_speed: float = 20.0
    backward_weight: float = 10.0
    n_rotations: int = 72
    altitude: float = 60.0
    altitude_gain: float = 1.0
    geometry: Literal["optimal", "trail"] = "optimal"
    trail_fan: float = float(np.deg2rad(15.0))

    def __post_init__(self) -> None:
        if self.geometry not in ("optimal", "trail"):
            raise ValueError(f"FormationConfig.geometry must be 'optimal' or 'trail', got {self.geometry!r}")
        if not (np.isfinite(self.trail_fan) and 0 < self.trail_fan <= np.pi / 2):
            raise ValueError(f"FormationConfig.trail_fan must be in (0, π/2] rad, got {self.trail_fan}")
        if int(self.team_size) != self.team_size or self.team_size < 2:
            raise ValueError(f"FormationConfig.team_size must be an integer >= 2, got {self.team_size}")
        if self.ranges is not None:
            r = tuple(float(x) for x in self.ranges)
            if len(r) != self.team_size or not all(np.isfinite(x) and x > 0 for x in r):
                raise ValueError(f"FormationConfig.ranges must be {self.team_size} values > 0 m, got {self.ranges}")
            object.__setattr__(self, "ranges", r)
        for name in ("sigma_bearing", "dt", "max_speed"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"FormationConfig.{name} must be > 0, got {v}")
        for name in ("backward_weight", "altitude_gain"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"FormationConfig.{name} must be >= 0, got {v}")
        if int(self.n_rotations) != self.n_rotations or self.n_rotations < 4:
            raise ValueError(f"FormationConfig.n_rotations must be an integer >= 4, got {self.n_rotations}")


@dataclass(frozen=True, kw_only=True)
class FormationStep:
    """One decision of the formation law for the whole team.

    Attributes
    ----------
    geometry : OptimalFormation
        Desired geometry around the target.
    a_W : np.ndarray
        (N, 2) PD accelerations (m/s²).
    v_cmd_W : np.ndarray
        (N, 2) commanded horizontal velocities (m/s).
    """

    geometry: OptimalFormation
    a_W: np.ndarray
    v_cmd_W: np.ndarray


def formation_step(p_W: np.ndarray, v_W: np.ndarray, target: TargetEstimate, config: FormationConfig,
                   a_target_W: np.ndarray | None = None) -> FormationStep:
    """Team decision from agent positions ``p_W`` and velocities ``v_W`` ((N, 2), m and m/s) at ``target.t``."""
    p = np.asarray(p_W, float)[:, :2]
    v = np.asarray(v_W, float)[:, :2]
    if p.shape != (config.team_size, 2) or v.shape != p.shape:
        raise ValueError(f"expected ({config.team_size}, 2) positions and velocities, got {p.shape} and {v.shape}")
    p_t, v_t = target.p_W[:2], target.v_W[:2]
    ranges = np.linalg.norm(p - p_t, axis=1) if config.ranges is None else np.asarray(config.ranges)
    if config.geometry == "trail":
        geo = trail_formation(p_t, v_t, ranges if config.ranges is not None else np.full(len(p), ranges.mean()),
                              config.trail_fan, config.sigma_bearing)
    else:
        geo = optimal_formation(p_t, v_t, p, np.maximum(ranges, 1e-6), config.sigma_bearing,
                                backward_weight=config.backward_weight, n_rotations=config.n_rotations)
    v_d = np.broadcast_to(v_t, p.shape)
    a = jacobi_pd_acceleration(p, v, geo.p_W, v_d, config.gains, a_target_W)
    v_cmd = v + a * config.dt
    speed = np.linalg.norm(v_cmd, axis=1, keepdims=True)
    v_cmd = np.where(speed > config.max_speed, v_cmd * (config.max_speed / np.maximum(speed, 1e-12)), v_cmd)
    return FormationStep(geometry=geo, a_W=a, v_cmd_W=v_cmd)


def trail_formation(p_t: np.ndarray, v_t: np.ndarray, ranges: np.ndarray, fan: float,
                    sigma_bearing: float) -> OptimalFormation:
    """The trailing fan of the module docstring around a target at ``p_t`` (m) moving with ``v_t`` (m/s): agent i at
    range ``ranges[i]`` (m), direction ``atan2(v_t) + π + linspace(−fan, fan, N)[i]`` (rad)."""
    r = np.asarray(ranges, dtype=float)
    theta = np.arctan2(v_t[1], v_t[0]) + np.pi + np.linspace(-fan, fan, r.size)
    p_d = p_t + r[:, None] * np.c_[np.cos(theta), np.sin(theta)]
    c2 = 1.0 / (sigma_bearing * np.maximum(r, 1e-6)) ** 2
    return OptimalFormation(theta=theta, p_W=p_d, ranges=r, det_fim=float(np.linalg.det(
        bearing_fim_from_directions(c2, theta))), det_bound=max_det_bearing_fim(c2), cost=0.0)


class FormationGuidance(Guidance):
    """Guidance of agent ``agent_id`` in a FIM-optimal formation (module docstring).

    Parameters
    ----------
    config : FormationConfig
        Team configuration (identical in every agent).
    agent_id : int
        This agent's team index, 0 <= agent_id < team_size; teammates are placed by their ``id``.
    """

    def __init__(self, config: FormationConfig, agent_id: int) -> None:
        super().__init__()
        if not 0 <= agent_id < config.team_size:
            raise ValueError(f"agent_id must be in [0, {config.team_size}), got {agent_id}")
        self.config = config
        self.agent_id = int(agent_id)
        self.last_step: FormationStep | None = None

    def plan_step_s(self) -> float:
        """The law's step (s); it shares no planned path."""
        return float(self.config.dt)

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> VelocitySetpoint:
        """Velocity set-point; with no target estimate, or teammates missing, hold position at the altitude."""
        self.stats.calls += 1
        cfg = self.config
        vz = cfg.altitude_gain * (cfg.altitude - float(own.p_W[2]))
        mates = {m.id: m for m in teammates if m.id != self.agent_id}
        if target is None or len(mates) != cfg.team_size - 1 or set(mates) | {self.agent_id} != set(
                range(cfg.team_size)):
            return VelocitySetpoint(v_W=np.array([0.0, 0.0, vz]))
        p = np.zeros((cfg.team_size, 2))
        v = np.zeros((cfg.team_size, 2))
        p[self.agent_id], v[self.agent_id] = own.p_W[:2], own.v_W[:2]
        tgt = TargetEstimate(t=t, p_W=target.predict_xy(t), v_W=target.v_W[:2])
        for i, m in mates.items():
            p[i] = m.predict_xy(np.array([t]))[0]
            v[i] = m.v_W[:2]
        self.last_step = formation_step(p, v, tgt, cfg)
        vx, vy = self.last_step.v_cmd_W[self.agent_id]
        return VelocitySetpoint(v_W=np.array([vx, vy, vz]))
