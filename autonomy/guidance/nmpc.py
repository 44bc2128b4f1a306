"""Nonlinear MPC standoff tracking for a team of UAVs (Oh, Kim, Tsourdos 2015, section IV), built with CasADi.

Each UAV solves, every step, over N steps of length T with the lagged unicycle of :mod:`autonomy.guidance.unicycle`
(RK4-discretised, x_{k+1} = f_d(x_k, u_k)), the target predicted at constant velocity, p_t,k = p_t + v_t k T, and
r_k = p_k − p_t,k:

    min  Σ_{k=1}^{N-1} ½[q_r r̃_k² + q_d D_k] + ½[p_r r̃_N² + p_d D_N]
         + Σ_{k=0}^{N-1} ½[r_v ((u_v,k − v_0)/v_max)² + r_ω ((u_ω,k − d v_0/r_d)/ω_max)²] + Σ_k (w_1 s_k + w_2 s_k²)
    s.t. max(v_min, v_0 − v_max) ≤ u_v,k ≤ v_0 + v_max,  |u_ω,k| ≤ ω_max,  s_k ≥ 0,
         |p_k − q_j,k|² / d_sep² − 1 + s_k ≥ 0                  (each teammate j, k = 1..N)
         |diag(1/α_b, 1/β_b) R_bᵀ (p_k − c_b)|² − 1 + s_k ≥ 0      (each nearby building b, :mod:`keepout`)

with r̃ = (r_d² − |r|²)/r_d² (eq. 27). The phase term D_k generalises eq. 28 to N UAVs and any spacing:
"chord" D = mean_j |u − R(φ_ij) u_j|², u = r/|r| (unit vectors; φ_ij the desired phase of i minus that of j), which
for two UAVs at 180° equals 2 d̃ r_d²/(|r||r_j|) — the paper's d̃ normalised and not squared, so the cost is quadratic
rather than quartic in the phase error and holds the phase tightly; "paper" uses q_d d̃² as printed. The teammates'
positions q_j,k come from their shared plans (or constant-velocity extrapolation). Keep-out and separation are soft
with an exact L1 penalty, so the problem is always feasible; the slack is zero whenever the hard problem is feasible
and the penalty is large enough. The plan is 2-D at a fixed altitude clamped into the configured band.

Configuration: :class:`~autonomy.guidance.nmpc_config.NmpcConfig`. The problem is built symbolically in
:mod:`autonomy.guidance.nmpc_problem`; its parameter vector (initial state, target, teammate and keep-out slots) is
laid out once in :class:`~autonomy.guidance.nmpc_layout.ParameterLayout`, packed here and unpacked there.

Solving. The cost is a sum of squares, so its Gauss–Newton Hessian is positive semi-definite by construction. Warm
starts (the previous plan shifted by the elapsed steps, its tail rolled out through the model, its multipliers
shifted with it) go to the ``fast`` :class:`~autonomy.guidance.nmpc_tiers.SolverChain`: by default
(``hessian="tiered"``) CasADi's ``sqpmethod`` + ``qrqp`` with the Gauss–Newton Hessian under a small iteration cap,
then, from its iterate, the same SQP with the constraint curvature Σ λ_j ∇²g_j added and clipped positive definite
(``stats.escalations``); ``solver="fatrop"`` solves the stage-wise form with Fatrop instead
(:mod:`autonomy.guidance.nmpc_stage`). A cold start (no plan to shift) and a failed warm solve
(``NmpcConfig.robust_retry``, ``stats.retries``) go to the ``cold`` chain, IPOPT with the exact Hessian, whose plan
then warm-starts the fast solver. ``NmpcConfig.restart_probe`` re-solves from the vector-field guess when the plan
rides the speed floor and keeps the cheaper plan. The fast solvers' functions are compiled to C
(:mod:`autonomy.guidance.codegen`).

Failures (solver status not successful, exception, non-finite output, injected by :meth:`inject_failures`, or a
time-budget overrun when enforced) never raise: the command comes from the previous successful plan shifted by the
elapsed time if it is young enough, else from the Lyapunov vector field; both are counted in ``stats``.

Why each of these choices, with the measurements (iterations, solve times, campaigns of ``road_standoff`` and
``helsinki_chase``): ``docs/nmpc.md``.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import casadi as ca
import numpy as np

from autonomy.guidance.base import Guidance
from autonomy.guidance.codegen import BufferedCall
from autonomy.guidance.keepout import nearby_keepouts
from autonomy.guidance.nmpc_config import NmpcConfig
from autonomy.guidance.nmpc_layout import NU, NX
from autonomy.guidance.nmpc_problem import build_problem
from autonomy.guidance.nmpc_tiers import NmpcStats, SolverChain, build_solvers
from autonomy.guidance.vector_field import VectorFieldGuidance
from interfaces.setpoints import UnicycleSetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState
from worlds.geometry import Building

__all__ = ["NmpcStandoffGuidance", "NmpcStats"]


class NmpcStandoffGuidance(Guidance):
    """NMPC standoff tracking for the UAV in phase ``slot`` among ``config.team_size`` (see the module docstring).

    Parameters
    ----------
    config : NmpcConfig
        Configuration; the solver is built once here and reused.
    slot : int
        Phase slot of this UAV on the orbit (its team index).
    buildings : Sequence[Building]
        Static obstacles; the ``config.max_buildings`` nearest relevant ones are constrained at each solve (the
        solver has as many keep-out slots as there are buildings taller than ``planning_altitude −
        building_vertical_clearance``, at most ``max_buildings``).
    """

    def __init__(self, config: NmpcConfig, slot: int = 0, buildings: Sequence[Building] = ()) -> None:
        super().__init__()
        self.stats = NmpcStats()
        if int(slot) != slot or slot < 0:
            raise ValueError(f"slot must be a non-negative integer, got {slot}")
        self.config = config
        self.slot = int(slot)
        self.buildings = tuple(buildings)
        self.plan_dt = config.dt
        self._fallback = VectorFieldGuidance(config.fallback_config(), slot=self.slot)
        self._guess_law = VectorFieldGuidance(config.fallback_config(), slot=self.slot)  # cold-start guesses only
        self._n_tm = max(config.team_size - 1, 0)
        # keep-out slots only for buildings that can ever be constrained (the rest are flown over): no inert rows
        # in every QP when there are none (the benchmark, road_standoff)
        floor = config.planning_altitude - config.building_vertical_clearance
        self._n_bld = min(config.max_buildings, sum(1 for b in self.buildings if b.top_z >= floor))
        self._slack_scale = max(config.weights.slack_l1, 1.0)
        self._build()
        self._w0: np.ndarray | None = None
        self._lam_g0: np.ndarray | None = None
        self._lam_x0: np.ndarray | None = None
        self._plan_t: float | None = None
        self._plan_x: np.ndarray | None = None  # (N+1, 5) including the initial state
        self._plan_u: np.ndarray | None = None  # (N, 2)
        self._inject = 0
        self._last_t = 0.0
        self._next_probe_t = -np.inf  # earliest time of the next restart probe

    # ------------------------------------------------------------------ construction
    def _build(self) -> None:
        pb = build_problem(self.config, self._n_tm, self._n_bld, self._slack_scale)
        self.layout = pb.layout
        self._f_d, self._n_g, self._n_par = pb.f_d, pb.n_g, pb.n_par
        self._lbx, self._ubx, self._lbg, self._ubg = pb.lbx, pb.ubx, pb.lbg, pb.ubg
        wvar, P = pb.nlp["x"], pb.nlp["p"]
        self._g_fun = BufferedCall(ca.Function("g", [wvar, P], [pb.nlp["g"]], ["x", "p"], ["g"]))
        self._f_fun = BufferedCall(ca.Function("f", [wvar, P], [pb.nlp["f"]], ["x", "p"], ["f"]))
        solvers = build_solvers(self.config, pb, self._n_tm + self._n_bld)
        self.fast: SolverChain = solvers.fast  # warm starts (:mod:`autonomy.guidance.nmpc_tiers`)
        self.cold: SolverChain = solvers.cold  # cold starts and robust retries
        self.compiled = solvers.compiled  # False when a solver that should be compiled could not be

    # ------------------------------------------------------------------ public API
    def inject_failures(self, count: int = 1) -> None:
        """Make the next ``count`` solves fail (the solver is not called); for testing the fallback chain."""
        if count < 0:
            raise ValueError(f"count must be >= 0, got {count}")
        self._inject += int(count)

    def plan_step_s(self) -> float:
        """Time between the points of :meth:`planned_path` (s): the planner's step."""
        return float(self.config.dt)

    def planned_path(self) -> np.ndarray | None:
        """(N, 2) planned horizontal positions at t + k T, k = 1..N (m), t the time of the last command.

        After a shifted-plan fallback the last successful plan is shifted to that time and its tail extended at
        its final velocity; ``None`` when there is no plan (vector-field fallback or no solve yet).
        """
        if self._plan_x is None or self._plan_t is None:
            return None
        n = self.config.horizon
        shift = int(np.floor((self._last_t - self._plan_t) / self.config.dt + 1e-9))
        pts = self._plan_x[1 + shift:, :2]
        step = self._plan_x[-1, :2] - self._plan_x[-2, :2]
        tail = self._plan_x[-1, :2] + np.outer(np.arange(1, n - pts.shape[0] + 1), step)
        return np.vstack([pts, tail])[:n].copy()

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> UnicycleSetpoint:
        """Solve the NMPC at time ``t`` (s) and return the first speed / heading-rate command; falls back on failure."""
        c = self.config
        self.stats.calls += 1
        self._last_t = float(t)
        if target is None:  # nothing to track: loiter on the nominal orbit turn rate
            return UnicycleSetpoint(speed=c.speed_bounds[0] if c.min_speed == 0 else c.min_speed,
                                    heading_rate=c.direction * c.nominal_speed / c.standoff_radius,
                                    altitude=c.planning_altitude)
        x0 = self._initial_state(own, t)
        par = self._parameters(x0, own, target, teammates, t)
        ok, t_solve, status = False, 0.0, "injected failure"
        before = self._plan_state()
        if self._inject > 0:
            self._inject -= 1
        else:
            warm = self._w0 is not None
            ok, t_solve, status = self._solve(x0, par, t, target, teammates)
            if ok and warm and c.restart_probe and t >= self._next_probe_t and self._stalled():
                t_solve += self._probe_restart(x0, par, t, target, teammates)
            if not ok and c.robust_retry and self._w0 is not None and c.solver != "ipopt":
                self.stats.retries += 1
                ok, t_retry, status = self._solve(x0, par, t, target, teammates, robust=True)
                t_solve += t_retry
        self.stats.solves += 1
        self.stats.solve_times_s.append(t_solve)
        self.stats.last_status = status
        if t_solve > c.time_budget_s:
            self.stats.overruns += 1
            if c.enforce_time_budget and ok:  # too late to be used: the fallback works from the previous plan
                ok = False
                self._set_plan_state(before)
        if ok:
            self._plan_t = t
            u = self._plan_u[0]
            return UnicycleSetpoint(speed=float(max(u[0], 0.0)), heading_rate=float(u[1]), altitude=c.planning_altitude)
        self.stats.failures += 1
        return self._fall_back(own, target, teammates, t)

    # ------------------------------------------------------------------ internals
    def _initial_state(self, own: OwnState, t: float) -> np.ndarray:
        psi = own.course(min_speed=0.5)
        omega = 0.0
        if self._plan_x is not None and self._plan_t is not None:
            tk = self._plan_t + self.config.dt * np.arange(self._plan_x.shape[0])
            if t <= tk[-1]:
                omega = float(np.interp(t, tk, self._plan_x[:, 4]))
                # unwrap the course to the plan's branch so the warm start stays dynamically consistent
                psi_plan = float(np.interp(t, tk, self._plan_x[:, 2]))
                psi += 2 * np.pi * np.round((psi_plan - psi) / (2 * np.pi))
        return np.array([own.p_W[0], own.p_W[1], psi, own.speed, omega])

    def _parameters(self, x0: np.ndarray, own: OwnState, target: TargetEstimate, teammates: Sequence[TeammateState],
                    t: float) -> np.ndarray:
        c = self.config
        n = c.horizon
        tk = t + c.dt * np.arange(1, n + 1)
        mates = []
        for tm in sorted(teammates, key=lambda tm: tm.id)[: self._n_tm]:
            phi = c.direction * (tm.slot - self.slot) * c.separation
            mates.append((np.cos(phi), np.sin(phi), tm.predict_xy(tk)))
        kos = []
        if self._n_bld > 0:
            reach = (c.nominal_speed + c.speed_deviation) * c.dt * n + c.separation_distance
            kos = [e.params() for e in nearby_keepouts(self.buildings, own.p_W, c.planning_altitude, reach,
                                                       c.building_margin, c.building_vertical_clearance, self._n_bld)]
        return self.layout.pack(x0=x0, target_position=target.predict_xy(t), target_velocity=target.v_W[:2],
                                teammates=mates, keepouts=kos)

    def _initial_guess(self, x0: np.ndarray, t: float, target: TargetEstimate,
                       teammates: Sequence[TeammateState], fresh: bool = False) -> np.ndarray:
        c = self.config
        n = c.horizon
        shift = None if fresh else self._shift(t)
        if shift is not None:
            # the tail is extended by the model under the last control: a guess that satisfies the dynamics
            X, U = list(self._plan_x[1 + shift:]), np.vstack([self._plan_u[shift:], np.repeat(self._plan_u[-1:], shift,
                                                                                               axis=0)])
            for _ in range(shift):
                X.append(np.asarray(self._f_d(X[-1], U[-1])).reshape(-1))
            return np.concatenate([np.asarray(X).reshape(-1), U.reshape(-1), np.zeros(n)])
        # cold start: roll the vector-field law forward through the prediction model (a good, smooth guess)
        xs, us, x = [], [], np.array(x0, dtype=float)
        for k in range(n):
            tk = t + k * c.dt
            own = OwnState(t=tk, p_W=[x[0], x[1], c.planning_altitude],
                           v_W=[x[3] * np.cos(x[2]), x[3] * np.sin(x[2]), 0.0], yaw=float(x[2]))
            sp = self._guess_law.command(own, target, teammates, tk)
            lo, hi = c.speed_bounds
            u = np.array([np.clip(sp.speed, lo, hi), np.clip(sp.heading_rate, -c.max_heading_rate, c.max_heading_rate)])
            x = np.asarray(self._f_d(x, u)).reshape(-1)  # the solver's own discrete model: a consistent guess
            xs.append(x)
            us.append(u)
        return np.concatenate([np.array(xs).reshape(-1), np.array(us).reshape(-1), np.zeros(n)])

    def _shift(self, t: float) -> int | None:
        """Whole steps from the last plan to ``t`` when that plan can warm-start the solve at ``t``, else ``None``."""
        if self._w0 is None or self._plan_t is None:
            return None
        shift = int(round((t - self._plan_t) / self.config.dt))
        return shift if 0 <= shift < self.config.horizon else None

    def _shifted_multipliers(self, shift: int) -> tuple[np.ndarray, np.ndarray]:
        """The last solve's multipliers (lam_g, lam_x) moved ``shift`` steps earlier, the last step's repeated."""
        n = self.config.horizon

        def sh(a: np.ndarray) -> np.ndarray:
            a = a.reshape(n, -1)
            return np.vstack([a[shift:], np.repeat(a[-1:], shift, axis=0)]).reshape(-1)

        lx = self._lam_x0
        lam_x = np.concatenate([sh(lx[:NX * n]), sh(lx[NX * n:(NX + NU) * n]), sh(lx[(NX + NU) * n:])])
        return sh(self._lam_g0), lam_x

    def _active_multipliers(self, w: np.ndarray, gv: np.ndarray, lam_g: np.ndarray,
                            lam_x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Interior-point multipliers with those of inactive inequalities and bounds zeroed (all are nonzero in an
        interior point solution, and would seed the active-set QP with a huge active set)."""
        tol = 1e-6
        act_g = ~np.isfinite(self._ubg) & (gv - self._lbg > tol)
        lam_g = np.where(act_g, 0.0, lam_g)
        at_bound = (w - self._lbx <= tol) | (self._ubx - w <= tol)
        return lam_g, np.where(at_bound, lam_x, 0.0)

    def _feasible_slacks(self, w0: np.ndarray, par: np.ndarray) -> np.ndarray:
        """Slacks s_k = max(0, −min_j h_j,k) that make the soft constraints of the guess ``w0`` hold (N,)."""
        n = self.config.horizon
        w = np.array(w0, dtype=float)
        w[-n:] = 0.0
        gv = self._g_fun(x=w, p=par)["g"].reshape(n, -1)[:, NX:]
        if gv.shape[1] == 0:
            return np.zeros(n)
        return self._slack_scale * np.maximum(0.0, -gv.min(axis=1))

    def _solve(self, x0: np.ndarray, par: np.ndarray, t: float, target: TargetEstimate,
               teammates: Sequence[TeammateState], robust: bool = False,
               fresh: bool = False) -> tuple[bool, float, str]:
        """Run the solver warm-started from the shifted previous plan; store the plan on success. ``robust`` uses
        the exact-Hessian IPOPT of cold starts from the same guess; ``fresh`` starts the fast solver from the
        vector-field rollout instead of the previous plan (the restart probe)."""
        c = self.config
        n = c.horizon
        w0 = self._initial_guess(x0, t, target, teammates, fresh=fresh)
        w0[-n:] = self._feasible_slacks(w0, par)
        args = {"x0": w0, "p": par, "lbx": self._lbx, "ubx": self._ubx, "lbg": self._lbg, "ubg": self._ubg}
        shift = None if fresh else self._shift(t)
        if self._lam_g0 is not None and shift is not None and not robust:
            args["lam_g0"], args["lam_x0"] = self._shifted_multipliers(shift)
        # a cold start (no plan to shift) goes to the robust exact-Hessian IPOPT, warm starts to the fast solver
        chain = self.cold if self._w0 is None or robust else self.fast
        c0 = time.thread_time()
        att = chain.solve(args, self._lbg, self._ubg, self.stats)
        self.stats.solve_cpu_times_s.append(time.thread_time() - c0)
        if not att.ok:
            return False, att.wall_s, att.status
        sol = att.sol
        w = np.asarray(sol["x"]).reshape(-1)
        X = w[: NX * n].reshape(n, NX)
        U = w[NX * n: NX * n + NU * n].reshape(n, NU)
        self._plan_x = np.vstack([x0, X])
        self._plan_u = U
        self._w0 = w
        self._lam_g0 = np.asarray(sol["lam_g"]).reshape(-1)
        self._lam_x0 = np.asarray(sol["lam_x"]).reshape(-1)
        if att.tier.keep_active_multipliers:
            self._lam_g0, self._lam_x0 = self._active_multipliers(w, np.asarray(sol["g"]).reshape(-1), self._lam_g0,
                                                                  self._lam_x0)
        return True, att.wall_s, att.status

    def _stalled(self) -> bool:
        """The plan rides the speed floor on at least half of the horizon: the signature of the slow looping local
        minimum a warm start can stay in after the target stops while the UAV faces against the orbit."""
        lo = self.config.speed_bounds[0]
        return bool(np.mean(self._plan_u[:, 0] <= lo + 1e-3) >= 0.5)

    def _probe_restart(self, x0: np.ndarray, par: np.ndarray, t: float, target: TargetEstimate,
                       teammates: Sequence[TeammateState]) -> float:
        """Solve again from the vector-field guess (with the fast solver) and keep whichever plan costs less; the
        solve's wall time (s)."""
        self.stats.restart_probes += 1
        keep = self._plan_state()
        j_warm = self._cost(self._w0, par)
        ok, t_probe, _ = self._solve(x0, par, t, target, teammates, fresh=True)
        if ok and self._cost(self._w0, par) < j_warm - 1e-9 * abs(j_warm):
            self.stats.restarts += 1
        else:  # the warm plan stays; probe again only after the configured interval
            self._set_plan_state(keep)
            self._next_probe_t = t + self.config.restart_probe_interval_s
        return t_probe

    def _plan_state(self) -> tuple:
        """The plan and warm-start state a solve replaces (see :meth:`_set_plan_state`)."""
        return self._w0, self._lam_g0, self._lam_x0, self._plan_x, self._plan_u, self._plan_t

    def _set_plan_state(self, state: tuple) -> None:
        self._w0, self._lam_g0, self._lam_x0, self._plan_x, self._plan_u, self._plan_t = state

    def _cost(self, w: np.ndarray, par: np.ndarray) -> float:
        return float(self._f_fun(x=w, p=par)["f"][0])

    def _fall_back(self, own: OwnState, target: TargetEstimate, teammates: Sequence[TeammateState],
                   t: float) -> UnicycleSetpoint:
        """Previous plan shifted by the elapsed time if young enough, else the vector field."""
        c = self.config
        if self._plan_u is not None and self._plan_t is not None:
            shift = int(np.floor((t - self._plan_t) / c.dt + 1e-9))
            if 0 <= shift <= min(c.fallback_max_shift, c.horizon - 1):
                self.stats.fallbacks_shifted += 1
                u = self._plan_u[shift]
                return UnicycleSetpoint(speed=float(max(u[0], 0.0)), heading_rate=float(u[1]),
                                        altitude=c.planning_altitude)
        self.stats.fallbacks_vector_field += 1
        self._plan_x = self._plan_u = self._plan_t = None
        self._w0 = self._lam_g0 = self._lam_x0 = None
        return self._fallback.command(own, target, teammates, t)
