"""The information planner as one UAV's guidance law.

Every UAV runs the same deterministic :class:`~autonomy.guidance.infoplan.planner.TeamInfoPlanner` on the states its
teammates share (ids 0 … N−1), so all UAVs arrive at the same team plan without a central planner (with a lossy or
delayed state exchange they may differ; the shared plans then keep them close). The UAV flies the first heading rate
of its own row as a :class:`~interfaces.setpoints.UnicycleSetpoint` and shares its planned path.

A teammate's state may be older than the planning time ``t`` (over a radio, the last state that got through; a
teammate that plans later in the same tick has not sent this step's state yet). It is brought to ``t`` along the
teammate's shared plan (:meth:`TeammateState.predict_xy`): the plan is a chain of the planner's constant-rate arcs, so
the course at the end of each arc follows from the arc's chord, ``χ_{k+1} = 2 θ_k − χ_k`` (a circular arc turns by
twice the angle between its chord and its start tangent). Beyond the plan, or without one, the teammate flies straight
at its last velocity.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from autonomy.guidance.base import Guidance
from autonomy.guidance.infoplan.config import InfoPlannerConfig
from autonomy.guidance.infoplan.planner import TeamInfoPlanner, TeamPlan
from autonomy.sensing.measurement import wrap_angle
from interfaces.setpoints import UnicycleSetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState

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
        states = {m.id: self._teammate_now(m, t) for m in teammates if m.id != self.uav_id}
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

    def _teammate_now(self, mate: TeammateState, t: float) -> tuple[np.ndarray, float]:
        """Horizontal position (m) and course (rad) of ``mate`` at ``t`` (s) (module docstring)."""
        course = float(np.arctan2(mate.v_W[1], mate.v_W[0])) if np.hypot(*mate.v_W[:2]) >= self.min_speed \
            else mate.yaw
        age = t - mate.t
        if age <= 1e-9:
            return mate.p_W[:2], course
        p = mate.predict_xy(np.array([t]))[0]
        if mate.plan_p_W is None:
            return p, course
        pts = np.vstack([mate.p_W[:2], mate.plan_p_W[:, :2]])
        s = min(age / mate.plan_dt, len(pts) - 1.0)  # arcs flown, the last one perhaps in part
        for k in range(int(np.ceil(s - 1e-9))):
            chord = pts[k + 1] - pts[k]
            turn = 2.0 * wrap_angle(float(np.arctan2(chord[1], chord[0])) - course)  # over the whole arc k
            course += min(1.0, s - k) * turn  # the heading rate is constant along an arc
        return p, float(wrap_angle(course))

    def plan_step_s(self) -> float:
        """Time between the points of :meth:`planned_path` (s): the planner's step."""
        return float(self.config.dt)

    def planned_path(self) -> np.ndarray | None:
        """(T_p, 2) own planned positions at the planner's steps after the last command (m)."""
        if self.last_plan is None:
            return None
        return self.last_plan.p_W[self._row].copy()
