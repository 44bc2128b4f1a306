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

Solver choice. The cost is a sum of squares; its Gauss–Newton Hessian σ J_Rᵀ J_R (+ 1e-6 I) is positive
semi-definite by construction. With CasADi's exact Hessian the SQP had to regularise an indefinite matrix and needed
18–50 iterations from a cold start. Measured on the benchmark problem (2 UAVs, N = 20, warm-started from the shifted
plan, closed loop around a moving target, 2-core shared machine):

- ``sqpmethod`` + ``qrqp`` (default, "sqp"): median 3 iterations, ≈ 1.8 ms p50 / 2.5 ms p95 CPU with the Gauss–Newton
  Hessian, ≈ 2.1 / 3.4 ms with the constraint-curvature Hessian below (at 830b029, with inert building rows);
- IPOPT warm-started (``print_level 0``, ``sb yes``, same Hessian): ≈ 15 iterations, ≈ 6–13 ms p50 — the barrier
  method restarts from an interior point every call and cannot exploit the active-set warm start;
- one real-time iteration ("rti"): ≈ 0.4–0.7 ms and as accurate as "sqp" around a free orbit, but in the town
  scenario with building keep-outs it diverged (mean standoff error of hundreds of metres): not robust enough as
  the default.

Why the Gauss–Newton SQP stalled in ``road_standoff`` (physics, radar estimates of a stop-and-go car; seed 2, 40 s:
41 of 156 warm solves capped at 30 iterations, 31 retried by IPOPT, none with a building constrained — at 60–70 m every
building of that town is flown over): the UAVs there sit on their speed bounds for the whole horizon chasing a
20–30° phase error, so the dynamics' multipliers (costates) are large and the residuals are far from zero. The
Gauss–Newton model then misses the curvature λᵀ∇²f_d of the heading dynamics; the QP steps zig-zag the heading rate
along the horizon, the line search fails ("3F" in CasADi's log) and the iterates cycle with a constraint violation
of ≈ 0.1–10 that the iteration cap never clears; IPOPT with the exact Hessian converged on the same problems in
≈ 12–18 iterations. The QP solver is not the cause (qpOASES and DAQP stalled on the same problems). Hence
the constraint-curvature Hessian: the Gauss–Newton cost Hessian plus the exact curvature Σ λ_j ∇²g_j of the
dynamics and constraints, made positive definite by CasADi's block-wise eigenvalue clipping (the Hessian's strongly
connected components are per-stage blocks of at most 5 × 5). Near a solution with negative curvature the clipped
model converges only linearly, so its cap is 15 iterations and a capped iterate that satisfies all constraints
within 1e-3 is used (counted in ``stats.inexact``): the next call continues from it. Alone (seeds 2 / 3, thread CPU
time of the solver calls) it cut the IPOPT retries 31 / 22 → 5 / 3 and the NMPC time per 40 s run 2.95 / 2.67 s →
1.66 / 1.55 s, but made the benchmark problem slower (CPU p50 / p95 1.8 / 2.5 → 2.1 / 3.4 ms). The cost is not the
clipping (≈ 0.1 ms per solve) but evaluating the exact Hessian: ≈ 15 000 virtual-machine instructions against
≈ 1 600 for Gauss–Newton (0.33 vs 0.03 ms per solve), plus a denser QP. "regularize" (one Gershgorin shift of the
whole matrix) is cheaper per iteration but so conservative that every solve hits the cap; "eigen-reflect" needs
more iterations than "eigen-clip".

Hence the default ``hessian="tiered"``: the Gauss–Newton SQP capped at 6 iterations (a capped iterate is not used),
then, if it did not converge, the constraint-curvature SQP warm-started from its iterate and multipliers (counted in
``stats.escalations``), then IPOPT (``stats.retries``). Keep-out slots exist only for buildings taller than the
planning altitude minus the vertical clearance (no inert rows in every QP when all buildings are flown over).
Measured (CPU, median of 3 runs each, same load window; the machine's load moves these by ≈ 20 %):

- benchmark problem p50 / p95: constraint-curvature at 830b029 2.08 / 3.22 ms, Gauss–Newton at 830b029 1.73 /
  2.49 ms, tiered 1.42 / 2.06 ms (quieter window: tiered 1.18 / 1.81–1.99, Gauss–Newton 1.27 / 1.95–2.14,
  constraint-curvature 1.47 / 2.10 ms, all without inert building rows); 9 of 480 solves escalated;
- road_standoff (40 s, seeds 2 / 3, both without inert building rows): constraint-curvature IPOPT retries 4 / 3,
  NMPC CPU 1.10 / 1.26 s, standoff error 17.9, 9.4 / 22.8, 18.1 m, phase error 31.9 / 29.7°; tiered 91 / 93 of 156
  warm solves escalated, retries 3 / 3, NMPC CPU 1.00 / 1.25 s, standoff error 17.8, 10.0 / 24.1, 18.3 m, phase
  error 34.2 / 29.9°; no failures, separation unchanged. The Gauss–Newton tier there mostly fails and costs ≈ as
  much as the clipping it saves.

qrqp stays the QP solver: on the benchmark (tiered) osqp took 1.9 / 3.4 ms, qpOASES (sparse) 14 / 23 ms and DAQP
55 / 109 ms.

Overheads removed afterwards (same benchmark, same iterates, one process, back to back): a 1.1 ms solve was
≈ 0.45 ms QPs, ≈ 0.15 ms function evaluations in CasADi's virtual machine (≈ 0.4 ms for the Jacobian alone before
compiling) and ≈ 0.17 ms converting the six numpy arguments to ``DM``. The fast solvers now load their functions
compiled to C (:func:`autonomy.guidance.codegen.compiled_nlpsol`, cached on disk; ``NmpcConfig.compiled``) and all
solvers are called through :class:`autonomy.guidance.codegen.BufferedCall` (no conversion): wall p50 / p95
1.18 / 2.02 and 1.15 / 1.79 ms uncompiled → 0.81 / 1.31 and 0.82 / 1.34 ms, plans identical to the last bit.

Fatrop (``solver="fatrop"``, :mod:`autonomy.guidance.nmpc_stage`): the same problem in stage-wise order, solved by
a structure-exploiting interior point with the exact Hessian (Riccati recursion over the stages, compiled functions),
started from the shifted plan; no tiers. An interior point does not profit from the warm start the way an active-set
SQP does (≈ 15 iterations p50 whatever ``mu_init``), so on an easy orbit it is slower: benchmark problem p50 / p95
1.6–2.0 / 2.6–2.8 ms against 0.64–0.71 / 1.05–1.14 ms tiered (same process, back to back). Where the Gauss–Newton tier
fails it wins: on 481 warm problems captured from ``road_standoff`` (seed 1) its cost matched the tiered plan's
(median relative difference −1e-8) with no failure. Paired 10-run ``road_standoff`` campaigns (physics car, the
same run seeds; ``skytrack campaign road_standoff --runs 10``, the tiered arm with
``--set uavs[i].autonomy.guidance.params={}``), tiered → Fatrop: solve p95 13.8 / 12.8 → 6.5 / 6.6 ms, IPOPT
retries per run 2.8 / 2.4 → 0.2 / 0.5, autonomy wall time per 120 s run 3.50 → 2.71 s (paired −0.78 ± 0.28 s,
95 % CI), real-time factor 8.92 → 10.23 (+1.31 ± 0.80); standoff error −1.3 ± 2.9 / −0.1 ± 1.3 m, phase error
+0.7 ± 4.1°, fused position error −0.23 ± 0.56 m: no change the ten runs resolve.
``road_standoff`` therefore plans with Fatrop; ``helsinki_chase`` (keep-outs, three UAVs, where the Gauss–Newton tier
mostly converges) stays tiered: autonomy time 2.75–3.69 s against 3.02–3.52 s per 60 s run over three seeds, a wash.
Starting Fatrop as the second tier from the capped Gauss–Newton iterate was slower than either (p50 ≈ 10 ms).

A local minimum seen in ``road_standoff`` (physics, stop-and-go car): when the car stops while a UAV flies against
the orbit direction, the warm-started SQP can keep a slow looping plan (speed floor, heading rate at ±ω_max) that is a
KKT point (accepted at 0 iterations) while a solve from the vector-field guess reaches a lower cost (seed 2, t = 105 s:
9691 against 8186). ``NmpcConfig.restart_probe`` re-solves from the vector-field guess whenever the plan rides the
speed floor on half the horizon and keeps the cheaper plan. Paired 10-run campaigns of ``road_standoff`` (same seeds,
whole-run mean phase error 23.45° without): probing with IPOPT −4.6 ± 3.5°, with the fast solver −4.0 ± 3.8° (RTF
7.1 → 4.3), with the fast solver and a 2 s pause after an unused probe −3.3 ± 3.8° (RTF −0.7 ± 0.6); standoff and
estimation errors unchanged. The benefit is at the edge of ten runs' resolution and costs time, so it is off by
default.

The slack of the soft constraints is a decision variable scaled by ``slack_l1`` (cost units), so its bound
multiplier is O(1) and does not inflate the L1-merit penalty of the line search (CasADi sets it from the largest
multiplier); unused teammate / building slots contribute rows 1 + s ≥ 0 that can never bind, not duplicates of the
slack's bound. Warm starts shift the previous plan, extend its tail through the model under the last control (a
dynamically consistent guess) and shift its multipliers with it; after an IPOPT solve only the multipliers of active
constraints and bounds are kept. Gauss–Newton ignores the curvature of the dynamics; from a cold start far from the
orbit (e.g. a saturated turn) the SQP then cycles, so a cold start (no plan to shift: the first call and after a
vector-field fallback) is solved by IPOPT with the exact Hessian (≈ 10–30 ms, rare), whose plan then warm-starts the
fast solver. A warm solve that still fails is retried once by that IPOPT (``NmpcConfig.robust_retry``).

Failures (solver status not successful, exception, non-finite output, injected by :meth:`inject_failures`, or a
time-budget overrun when enforced) never raise: the command comes from the previous successful plan shifted by the
elapsed time if it is young enough, else from the Lyapunov vector field; both are counted in ``stats``.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from autonomy.guidance.base import Guidance, GuidanceStats
from autonomy.guidance.codegen import BufferedCall, compiled_nlpsol
from autonomy.guidance.keepout import nearby_keepouts
from autonomy.guidance.nmpc_config import NmpcConfig
from autonomy.guidance.nmpc_problem import NX as _NX
from autonomy.guidance.nmpc_problem import NU as _NU
from autonomy.guidance.nmpc_problem import NmpcProblem, build_problem
from autonomy.guidance.nmpc_stage import FatropSolver
from autonomy.guidance.setpoints import UnicycleSetpoint
from autonomy.guidance.types import OwnState, TargetEstimate, TeammateState
from autonomy.guidance.vector_field import VectorFieldGuidance
from worlds.geometry import Building

__all__ = ["NmpcStandoffGuidance", "NmpcStats"]

# names CasADi expects of a hess_lag function (checked when the solver loads it from a compiled library)
_HESS_IO = (["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])
_ACCEPT_VIOLATION = 1e-3  # largest constraint violation of an iterate accepted after the iteration cap (m, −)


@dataclass(kw_only=True)
class NmpcStats(GuidanceStats):
    """:class:`GuidanceStats` plus the solver tiers of ``hessian="tiered"``.

    Attributes
    ----------
    escalations : int
        Warm solves the Gauss–Newton SQP did not finish (failed or capped), handed to the constraint-curvature SQP
        from its iterate. ``retries`` counts the IPOPT solves after the last SQP tier failed.
    restart_probes, restarts : int
        With ``NmpcConfig.restart_probe``: warm solutions that rode the speed floor and were re-solved from the
        vector-field guess, and how many of those re-solves had the lower cost and replaced the warm plan.
    """

    escalations: int = 0
    restart_probes: int = 0
    restarts: int = 0

    def summary(self) -> dict[str, float]:
        """:meth:`GuidanceStats.summary` plus ``escalations`` and, with ``restart_probe``, ``restart_probes`` /
        ``restarts`` (probes solved from the vector-field guess / probes whose plan replaced the warm one)."""
        return {**super().summary(), "escalations": self.escalations, "restart_probes": self.restart_probes,
                "restarts": self.restarts}


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
        self.compiled = config.compiled  # cleared when a solver could not be compiled
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
        c = self.config
        pb = build_problem(c, self._n_tm, self._n_bld, self._slack_scale)
        self._f_d, self._n_g, self._n_par = pb.f_d, pb.n_g, pb.n_par
        self._lbx, self._ubx, self._lbg, self._ubg = pb.lbx, pb.ubx, pb.lbg, pb.ubg
        nlp, wvar, P, lam_f, lam_g, H_gn = pb.nlp, pb.nlp["x"], pb.nlp["p"], pb.lam_f, pb.lam_g, pb.H_gn
        self._g_fun = BufferedCall(ca.Function("g", [wvar, P], [pb.nlp["g"]], ["x", "p"], ["g"]))
        self._f_fun = BufferedCall(ca.Function("f", [wvar, P], [pb.nlp["f"]], ["x", "p"], ["f"]))
        if c.solver == "fatrop":  # exact Hessian, stage-wise (see nmpc_stage); no tiers
            self._solver = self._fatrop(pb)
            self._curv_solver = None
        elif c.solver == "ipopt":  # IPOPT takes the upper triangle
            hess = ca.Function("nlp_hess_l", [wvar, P, lam_f, lam_g], [ca.triu(H_gn)], *_HESS_IO)
            self._solver = BufferedCall(ca.nlpsol("nmpc", *self._solver_spec(nlp, hess, "gauss_newton")))
            self._curv_solver = None
        else:
            H_cc = pb.curvature_hessian()
            first = "gauss_newton" if c.hessian == "tiered" else c.hessian
            H_first = H_gn if first == "gauss_newton" else H_cc
            hess = ca.Function("nlp_hess_l", [wvar, P, lam_f, lam_g], [H_first], *_HESS_IO)
            self._solver = self._nlpsol("nmpc", *self._solver_spec(nlp, hess, first))
            self._curv_solver = None  # second tier of "tiered": the constraint-curvature SQP
            if c.hessian == "tiered":
                hess_cc = ca.Function("nlp_hess_l", [wvar, P, lam_f, lam_g], [H_cc], *_HESS_IO)
                self._curv_solver = self._nlpsol("nmpc_curv", *self._solver_spec(nlp, hess_cc, "constraint_curvature"))
        cold_opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-6,
                     "ipopt.max_iter": c.cold_start_max_iter}
        self._cold_solver = BufferedCall(ca.nlpsol("nmpc_cold", "ipopt", nlp, cold_opts))

    def _fatrop(self, pb: NmpcProblem) -> FatropSolver:
        """Fatrop on the stage-wise form of ``pb`` (:mod:`autonomy.guidance.nmpc_stage`)."""
        c = self.config
        solver = FatropSolver("nmpc_fatrop", pb, self._n_tm + self._n_bld,
                              {"tol": c.fatrop_tol, "max_iter": c.fatrop_max_iter}, compiled=c.compiled)
        self.compiled = self.compiled and solver.compiled
        return solver

    def _nlpsol(self, name: str, plugin: str, nlp: dict, opts: dict) -> BufferedCall:
        """The fast solver ``name``: compiled (:mod:`autonomy.guidance.codegen`) when ``config.compiled``."""
        if not self.config.compiled:
            return BufferedCall(ca.nlpsol(name, plugin, nlp, opts))
        solver, ok = compiled_nlpsol(name, plugin, nlp, opts)
        self.compiled = self.compiled and ok
        return BufferedCall(solver)

    def _solver_spec(self, nlp: dict, hess: ca.Function, hessian: str) -> tuple:
        c = self.config
        if c.solver == "ipopt":
            opts = {"hess_lag": hess, "print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
                    "ipopt.max_iter": c.max_iter,
                    "ipopt.warm_start_init_point": "yes", "ipopt.tol": 1e-6, "ipopt.acceptable_tol": 1e-4}
            return "ipopt", nlp, opts
        opts = {"qpsol": "qrqp", "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False,
                                                   "error_on_fail": False},
                "print_header": False, "print_iteration": False, "print_status": False, "print_time": False,
                "hess_lag": hess, "max_iter": self._max_iter(hessian),
                "tol_pr": 1e-5, "tol_du": 1e-2, "error_on_fail": False}
        if hessian == "constraint_curvature":
            opts.update(convexify_strategy=c.convexify, convexify_margin=c.convexify_margin)
        return "sqpmethod", nlp, opts

    def _max_iter(self, hessian: str) -> int:
        c = self.config
        if c.solver == "rti":
            return 1
        return c.gauss_newton_max_iter if c.hessian == "tiered" and hessian == "gauss_newton" else c.max_iter

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
        parts = [x0, target.predict_xy(t), target.v_W[:2]]
        team = sorted(teammates, key=lambda tm: tm.id)[: self._n_tm]
        for tm in team:
            phi = c.direction * (tm.slot - self.slot) * c.separation
            parts.append([1.0, np.cos(phi), np.sin(phi)])
            parts.append(tm.predict_xy(tk).T.reshape(-1, order="F"))
        for _ in range(self._n_tm - len(team)):
            parts.append([0.0, 1.0, 0.0])
            parts.append(np.full(2 * n, 1e6))
        if self._n_bld > 0:
            reach = (c.nominal_speed + c.speed_deviation) * c.dt * n + c.separation_distance
            kos = nearby_keepouts(self.buildings, own.p_W, c.planning_altitude, reach, c.building_margin,
                                  c.building_vertical_clearance, self._n_bld)
            for e in kos:
                parts.append(np.concatenate([[1.0], e.params()]))
            for _ in range(self._n_bld - len(kos)):
                parts.append([0.0, 1e6, 1e6, 1.0, 0.0, 1.0, 1.0])
        return np.concatenate([np.asarray(p, dtype=float).reshape(-1) for p in parts])

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
        lam_x = np.concatenate([sh(lx[:_NX * n]), sh(lx[_NX * n:(_NX + _NU) * n]), sh(lx[(_NX + _NU) * n:])])
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
        gv = self._g_fun(x=w, p=par)["g"].reshape(n, -1)[:, _NX:]
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
        solver = self._cold_solver if self._w0 is None or robust else self._solver
        tiered = solver is self._solver and self._curv_solver is not None
        c0 = time.thread_time()
        ok, t_solve, status, sol = self._attempt(solver, args, accept_capped=solver is self._solver and not tiered)
        if not ok and tiered:  # second tier: the constraint-curvature SQP from the Gauss-Newton iterate
            self.stats.escalations += 1
            if sol is not None and np.all(np.isfinite(np.asarray(sol["x"]))):
                args = dict(args, x0=sol["x"], lam_g0=sol["lam_g"], lam_x0=sol["lam_x"])
            solver = self._curv_solver
            ok, t_curv, status, sol = self._attempt(solver, args, accept_capped=True)
            t_solve += t_curv
        self.stats.solve_cpu_times_s.append(time.thread_time() - c0)
        if not ok:
            return False, t_solve, status
        w = np.asarray(sol["x"]).reshape(-1)
        X = w[: _NX * n].reshape(n, _NX)
        U = w[_NX * n: _NX * n + _NU * n].reshape(n, _NU)
        self._plan_x = np.vstack([x0, X])
        self._plan_u = U
        self._w0 = w
        self._lam_g0 = np.asarray(sol["lam_g"]).reshape(-1)
        self._lam_x0 = np.asarray(sol["lam_x"]).reshape(-1)
        if solver is self._cold_solver:
            self._lam_g0, self._lam_x0 = self._active_multipliers(w, np.asarray(sol["g"]).reshape(-1), self._lam_g0,
                                                                  self._lam_x0)
        return True, t_solve, status

    def _attempt(self, solver: BufferedCall, args: dict, accept_capped: bool) -> tuple[bool, float, str, dict | None]:
        """One optimiser call: (success, wall time (s), status, solution or ``None`` after an exception). With
        ``accept_capped`` an iterate stopped by the iteration cap that satisfies all constraints within
        ``_ACCEPT_VIOLATION`` counts as a success (``stats.inexact``); RTI always ends there."""
        t0 = time.perf_counter()
        try:
            sol = solver(**args)
            st = solver.stats()
        except RuntimeError as exc:  # CasADi raises RuntimeError on evaluation errors
            return False, time.perf_counter() - t0, f"exception: {exc}", None
        t_solve = time.perf_counter() - t0
        status = str(st.get("return_status", ""))
        self.stats.iterations.append(int(st.get("iter_count", -1)))
        ok = bool(st.get("success", False))
        if not ok and accept_capped and status.strip() == "Maximum_Iterations_Exceeded":
            gv = np.asarray(sol["g"]).reshape(-1)
            viol = max(float(np.max(self._lbg - gv, initial=0.0)), float(np.max(gv - self._ubg, initial=0.0)))
            ok = self.config.solver == "rti" or viol <= _ACCEPT_VIOLATION
            if ok and self.config.solver != "rti":
                self.stats.inexact += 1
        return ok and bool(np.all(np.isfinite(np.asarray(sol["x"])))), t_solve, status, sol

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
