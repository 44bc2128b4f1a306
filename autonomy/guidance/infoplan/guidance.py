"""The information planner as one UAV's guidance law.

Every UAV runs the same deterministic :class:`~autonomy.guidance.infoplan.planner.TeamInfoPlanner` on the states its
teammates share (ids 0 … N−1), so all UAVs arrive at the same team plan without a central planner (with a lossy or
delayed state exchange they may differ; the shared plans then keep them close). The UAV flies the first heading rate
of its own row as a :class:`~autonomy.guidance.setpoints.UnicycleSetpoint` and shares its planned path.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from autonomy.guidance.base import Guidance
from autonomy.guidance.infoplan.config import InfoPlannerConfig
from autonomy.guidance.infoplan.planner import TeamInfoPlanner, TeamPlan
from autonomy.guidance.setpoints import UnicycleSetpoint
from autonomy.guidance.types import OwnState, TargetEstimate, TeammateState

__all__ = ["InfoPlannerGuidance"]


class InfoPlannerGuidance(Guidance):
    """Communication-aware information planning for UAV ``uav_id`` (module docstring).

    Parameters
    ----------
    config : InfoPlannerConfig
        Planner configuration, identical in every UAV.
    uav_id : int
        This UAV's team index; teammates are ordered by their ``id``.
    min_speed : float
        Speed (m/s) under which the yaw replaces the course as heading.
    """

    def __init__(self, config: InfoPlannerConfig, uav_id: int, min_speed: float = 1.0) -> None:
        super().__init__()
        if int(uav_id) != uav_id or uav_id < 0:
            raise ValueError(f"uav_id must be a non-negative integer, got {uav_id}")
        self.config = config
        self.uav_id = int(uav_id)
        self.min_speed = float(min_speed)
        self.plan_dt = config.dt
        self.planner = TeamInfoPlanner(config)
        self.last_plan: TeamPlan | None = None

    @staticmethod
    def _prior(target: TargetEstimate) -> np.ndarray | None:
        """Information (4 × 4, layout ``TARGET_CV``) of the estimate's horizontal position and velocity, if given."""
        if target.P is None:
            return None
        n = target.p_W.shape[0]
        idx = [0, 1, n, n + 1]
        return np.linalg.inv(target.P[np.ix_(idx, idx)])

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> UnicycleSetpoint:
        """Heading rate of the team plan's first step; straight flight at the altitude when there is no target."""
        self.stats.calls += 1
        cfg = self.config
        if target is None:
            self.last_plan = None
            return UnicycleSetpoint(speed=cfg.speed, heading_rate=0.0, altitude=cfg.altitude)
        states = {m.id: (m.p_W[:2], np.arctan2(m.v_W[1], m.v_W[0]) if np.hypot(*m.v_W[:2]) >= self.min_speed
                         else m.yaw) for m in teammates if m.id != self.uav_id}
        states[self.uav_id] = (own.p_W[:2], own.course(self.min_speed))
        ids = sorted(states)
        p = np.array([states[i][0] for i in ids])
        chi = np.array([states[i][1] for i in ids])
        self.stats.solves += 1
        t0, c0 = time.perf_counter(), time.thread_time()
        plan = self.planner.plan(p, chi, target.predict_xy(t), target.v_W[:2], self._prior(target))
        self.stats.solve_times_s.append(time.perf_counter() - t0)
        self.stats.solve_cpu_times_s.append(time.thread_time() - c0)
        self.stats.last_status = "ok"
        self.stats.iterations.append(plan.evaluations)
        self.last_plan = plan
        self._row = ids.index(self.uav_id)
        return UnicycleSetpoint(speed=cfg.speed, heading_rate=float(plan.heading_rates[self._row, 0]),
                                altitude=cfg.altitude)

    def planned_path(self) -> np.ndarray | None:
        """(T_p, 2) own planned positions at the planner's steps after the last command (m)."""
        if self.last_plan is None:
            return None
        return self.last_plan.p_W[self._row].copy()
