"""Closed loop of guidance laws on kinematic unicycles around a target moving at constant velocity.

The harness of the guidance tests and benchmarks (no physics engine): each step every UAV receives its own state,
the exact target state and the teammates' states and plans shared at the start of the step (synchronous update), its
guidance law returns a :class:`~interfaces.setpoints.UnicycleSetpoint`, and the unicycle
(:mod:`autonomy.guidance.unicycle`) integrates it over one step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from autonomy.guidance.base import Guidance
from autonomy.guidance.unicycle import UnicycleParams, unicycle_step
from interfaces.setpoints import UnicycleSetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState

__all__ = ["LoopConfig", "LoopResult", "run_kinematic_loop"]


@dataclass(frozen=True, kw_only=True)
class LoopConfig:
    """Closed-loop run.

    Attributes
    ----------
    dt : float
        Guidance and integration step (s), > 0.
    steps : int
        Number of steps, >= 1.
    target_p0 : tuple[float, float]
        Target position at t = 0 (m).
    target_v : tuple[float, float]
        Constant target velocity (m/s).
    plant : UnicycleParams
        Lags of the simulated UAVs.
    """

    dt: float = 0.5
    steps: int = 200
    target_p0: tuple[float, float] = (0.0, 0.0)
    target_v: tuple[float, float] = (0.0, 0.0)
    plant: UnicycleParams = UnicycleParams()

    def __post_init__(self) -> None:
        if not (self.dt > 0):
            raise ValueError(f"LoopConfig.dt must be > 0 s, got {self.dt}")
        if int(self.steps) != self.steps or self.steps < 1:
            raise ValueError(f"LoopConfig.steps must be an integer >= 1, got {self.steps}")


@dataclass(frozen=True, kw_only=True)
class LoopResult:
    """Time series of a closed-loop run.

    Attributes
    ----------
    t : np.ndarray
        (S+1,) times (s).
    x : np.ndarray
        (S+1, N, 5) UAV states in the layout ``UNICYCLE`` (m, m, rad, m/s, rad/s).
    target_p : np.ndarray
        (S+1, 2) target positions (m).
    u : np.ndarray
        (S, N, 2) commanded (speed, heading rate) (m/s, rad/s).
    """

    t: np.ndarray
    x: np.ndarray
    target_p: np.ndarray
    u: np.ndarray

    @property
    def ranges(self) -> np.ndarray:
        """(S+1, N) horizontal distances UAV–target (m)."""
        return np.linalg.norm(self.x[:, :, :2] - self.target_p[:, None, :], axis=2)

    @property
    def phases(self) -> np.ndarray:
        """(S+1, N) phase angles atan2 of the UAV position relative to the target (rad)."""
        r = self.x[:, :, :2] - self.target_p[:, None, :]
        return np.arctan2(r[..., 1], r[..., 0])

    def min_separation(self) -> float:
        """Smallest horizontal distance between any two UAVs over the run (m); inf for one UAV."""
        n = self.x.shape[1]
        best = np.inf
        for i in range(n):
            for j in range(i + 1, n):
                best = min(best, float(np.min(np.linalg.norm(self.x[:, i, :2] - self.x[:, j, :2], axis=1))))
        return best


def run_kinematic_loop(laws: Sequence[Guidance], x0: np.ndarray, config: LoopConfig,
                       altitude: float = 60.0) -> LoopResult:
    """Fly ``laws[i]`` on unicycle i from ``x0`` (N, 5) for ``config.steps`` steps; see the module docstring."""
    x = np.array(x0, dtype=float).reshape(len(laws), 5)
    n = len(laws)
    p0, vt = np.asarray(config.target_p0, float), np.asarray(config.target_v, float)
    xs, us, ts, tps = [x.copy()], [], [0.0], [p0.copy()]
    plans: list[np.ndarray | None] = [None] * n
    for k in range(config.steps):
        t = k * config.dt
        target = TargetEstimate(t=t, p_W=p0 + vt * t, v_W=vt)
        own = [OwnState(t=t, p_W=np.array([xi[0], xi[1], altitude]),
                        v_W=np.array([xi[3] * np.cos(xi[2]), xi[3] * np.sin(xi[2]), 0.0]), yaw=xi[2]) for xi in x]
        shared = [TeammateState(id=i, t=t, p_W=own[i].p_W, v_W=own[i].v_W, yaw=float(x[i, 2]), plan_p_W=plans[i],
                                plan_dt=getattr(laws[i], "plan_dt", config.dt)) for i in range(n)]
        u = np.zeros((n, 2))
        for i, law in enumerate(laws):
            sp = law.command(own[i], target, [s for j, s in enumerate(shared) if j != i], t)
            if not isinstance(sp, UnicycleSetpoint):
                raise TypeError(f"the kinematic loop flies UnicycleSetpoint only, got {type(sp).__name__}")
            u[i] = (sp.speed, sp.heading_rate)
        plans = [law.planned_path() for law in laws]
        x = np.array([unicycle_step(x[i], u[i], config.dt, config.plant) for i in range(n)])
        xs.append(x.copy())
        us.append(u)
        ts.append((k + 1) * config.dt)
        tps.append(p0 + vt * (k + 1) * config.dt)
    return LoopResult(t=np.array(ts), x=np.array(xs), target_p=np.array(tps), u=np.array(us))
