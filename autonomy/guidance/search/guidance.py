"""Set-membership search as a per-UAV guidance law (the :class:`~autonomy.guidance.base.Guidance` interface).

Each UAV runs its own :class:`~autonomy.guidance.search.planner.SearchPlanner` on its own sets (read from its
:class:`~autonomy.estimation.setmem.estimator.SetMembershipEstimator`). The sequential order of the paper is carried
by the shared plans: a teammate whose ``plan_p_W`` is stamped at the current time ``t`` has already decided in this
step, so its planned observations are subtracted from the predicted sets; the others are ignored (they decide
after this UAV). The agent passes only the line-of-sight neighbours as ``teammates``.

The decision ``u`` becomes a world-frame velocity set-point along the new heading ``psi + u`` at the search speed,
with altitude hold ``v_z = k_z (z_ref - z)``, and the yaw set-point ``psi + u`` (the footprint turns with the yaw).

The planner's safe-loiter constraint (:mod:`~autonomy.guidance.search.safety`) is evaluated from the UAV's measured
position and course; its by-construction clearance holds for the discrete model (straight chords of ``V T``, exact
turns), so a physical UAV keeps it only up to its tracking error, which ``SearchConfig.clearance_margin`` must cover.

A vehicle whose horizontal velocity follows its set-point as a first-order lag of time constant ``tau``
(``velocity_lag_s``) does not turn at once: held for one step from the velocity ``v0``, the set-point ``v_c`` moves it
by ``v_c T + (v0 - v_c) tau (1 - exp(-T / tau))``. With ``velocity_lag_s > 0`` the set-point is chosen so that this
displacement is the model's chord ``V T (cos(psi + u), sin(psi + u))``, and the UAV ends the step where the planner
put it (to the first order: its speed limit and tilt saturation are not modelled); ``velocity_lag_s = 0`` commands the
chord's velocity.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from autonomy.estimation.setmem.estimator import SetMembershipEstimator
from autonomy.guidance.base import Guidance
from autonomy.guidance.search.planner import PlannedPath, SearchDecision, SearchPlanner
from interfaces.setpoints import VelocitySetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState

__all__ = ["SetMembershipSearchGuidance", "teammate_path"]

_MIN_COURSE_SPEED = 0.5  # m/s below which the body yaw is used as the heading


def teammate_path(tm: TeammateState) -> PlannedPath | None:
    """The planned positions (m) and headings (rad, from successive points) a teammate shares, or ``None``."""
    if tm.plan_p_W is None:
        return None
    pts = np.vstack([tm.p_W[:2], tm.plan_p_W[:, :2]])
    d = np.diff(pts, axis=0)
    yaw = np.arctan2(d[:, 1], d[:, 0])
    return PlannedPath(p_xy=pts[1:], yaw=yaw)


class SetMembershipSearchGuidance(Guidance):
    """Search MPC of one UAV (module docstring).

    Parameters
    ----------
    planner : SearchPlanner
        The one-step MPC.
    estimator : SetMembershipEstimator
        This UAV's set-membership estimator (read only).
    velocity_lag_s : float
        Time constant ``tau`` (s, >= 0) of the vehicle's velocity response that the set-point compensates (module
        docstring); 0 for none.
    max_speed : float
        Largest horizontal set-point speed (m/s), > 0; the compensated set-point is scaled down to it.
    """

    def __init__(self, planner: SearchPlanner, estimator: SetMembershipEstimator, velocity_lag_s: float = 0.0,
                 max_speed: float = np.inf):
        super().__init__()
        if not (velocity_lag_s >= 0):
            raise ValueError(f"SetMembershipSearchGuidance.velocity_lag_s must be >= 0 s, got {velocity_lag_s}")
        if not (max_speed > 0):
            raise ValueError(f"SetMembershipSearchGuidance.max_speed must be > 0 m/s, got {max_speed}")
        self.planner = planner
        self.estimator = estimator
        self.velocity_lag_s = float(velocity_lag_s)
        self.max_speed = float(max_speed)
        self.last_decision: SearchDecision | None = None

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> VelocitySetpoint:
        """Velocity set-point for the next step; ``target`` is unused (the sets replace a point estimate)."""
        cfg = self.planner.config
        heading = own.course(_MIN_COURSE_SPEED)
        decided = []
        for tm in teammates:
            path = teammate_path(tm)
            if path is not None and abs(tm.t - t) <= 1e-9:
                decided.append(path)
        t0 = time.perf_counter()
        decision = self.planner.decide(own.p_W[:2], heading, self.estimator.estimate, decided)
        self.stats.solve_times_s.append(time.perf_counter() - t0)
        self.stats.iterations.append(len(decision.controls))
        self.stats.calls += 1
        self.stats.solves += 1
        self.stats.last_status = "grid"
        self.last_decision = decision
        psi = heading + decision.u
        v_xy = cfg.speed * np.array([np.cos(psi), np.sin(psi)])
        if self.velocity_lag_s > 0:
            k = self.velocity_lag_s * (1.0 - np.exp(-cfg.dt / self.velocity_lag_s))  # the step's lag, s
            v_xy = (v_xy * cfg.dt - np.asarray(own.v_W[:2], float) * k) / (cfg.dt - k)
            norm = float(np.hypot(*v_xy))
            if norm > self.max_speed:
                v_xy *= self.max_speed / norm
        vz = cfg.altitude_gain * (cfg.altitude - float(own.p_W[2]))
        return VelocitySetpoint(v_W=np.array([v_xy[0], v_xy[1], vz]), yaw=psi)

    def plan_step_s(self) -> float:
        """Time between the points of :meth:`planned_path` (s): the planner's step."""
        return float(self.planner.config.dt)

    def planned_path(self) -> np.ndarray | None:
        """(h, 2) positions (m) planned by the last command, shared with the teammates."""
        return None if self.last_decision is None else self.last_decision.path.p_xy.copy()
