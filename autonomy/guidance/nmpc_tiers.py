"""The NMPC's optimisers as tiers with one interface: a :class:`SolverTier` is one optimiser call with its rule for
accepting an iterate stopped by the iteration cap; a :class:`SolverChain` tries its tiers in order, each one
warm-started from the iterate and multipliers of the tier before it (an escalation).

:func:`build_solvers` makes the two chains of :class:`autonomy.guidance.nmpc.NmpcStandoffGuidance` from its
:class:`~autonomy.guidance.nmpc_config.NmpcConfig`:

- ``fast`` (warm starts): ``solver="sqp"`` / ``"rti"`` with ``hessian="tiered"`` is the Gauss–Newton SQP capped at
  ``gauss_newton_max_iter`` (a capped iterate is handed on, not used) then the constraint-curvature SQP (a capped
  iterate within ``ACCEPT_VIOLATION`` of feasibility is used); with another ``hessian`` the one SQP; ``"ipopt"``
  IPOPT with the Gauss–Newton Hessian; ``"fatrop"`` Fatrop on the stage-wise problem
  (:mod:`autonomy.guidance.nmpc_stage`). One real-time iteration (``"rti"``) always uses its capped iterate.
- ``cold`` (no plan to shift, and the robust retry of a failed warm solve): IPOPT with the exact Hessian; only the
  multipliers of its active constraints and bounds are kept for the next warm start.

Why these tiers, and what each costs, is measured in ``docs/nmpc.md``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Protocol

import casadi as ca
import numpy as np

from autonomy.guidance.base import GuidanceStats
from autonomy.guidance.codegen import BufferedCall, compiled_nlpsol
from autonomy.guidance.nmpc_config import NmpcConfig
from autonomy.guidance.nmpc_problem import NmpcProblem
from autonomy.guidance.nmpc_stage import FatropSolver

__all__ = ["ACCEPT_VIOLATION", "Attempt", "NmpcSolvers", "NmpcStats", "SolverChain", "SolverTier", "build_solvers"]

ACCEPT_VIOLATION = 1e-3  # largest constraint violation of an iterate accepted after the iteration cap (m, −)
# names CasADi expects of a hess_lag function (checked when the solver loads it from a compiled library)
_HESS_IO = (["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])
_CAPPED = "Maximum_Iterations_Exceeded"


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


class Optimiser(Protocol):
    """A solver called in the by-kind layout: ``solver(x0=, p=, lbx=, ubx=, lbg=, ubg=[, lam_g0=, lam_x0=])`` →
    ``x, f, g, lam_g, lam_x``, and ``stats()`` of the last call (:class:`BufferedCall`, :class:`FatropSolver`)."""

    def __call__(self, **args: Any) -> dict[str, np.ndarray]: ...

    def stats(self) -> dict: ...


@dataclass(frozen=True)
class Attempt:
    """One solve: success, wall time (s), the solver's status, the solution (``None`` after an exception) and the
    tier that produced it."""

    ok: bool
    wall_s: float
    status: str
    sol: dict[str, np.ndarray] | None
    tier: SolverTier | None = None


@dataclass(kw_only=True, eq=False)
class SolverTier:
    """One optimiser and its acceptance rule.

    Attributes
    ----------
    name : str
        What it is (``"gauss_newton"``, ``"constraint_curvature"``, ``"ipopt"``, ``"fatrop"``, ``"ipopt_exact"``).
    solver : Optimiser
        The optimiser.
    accept_capped : bool
        An iterate stopped by the iteration cap counts as a success when it satisfies all constraints within
        :data:`ACCEPT_VIOLATION` (counted in ``stats.inexact``).
    real_time : bool
        One real-time iteration: a capped iterate is always used (not counted as inexact).
    keep_active_multipliers : bool
        An interior point: of its multipliers only those of active constraints and bounds seed the next warm start.
    """

    name: str
    solver: Optimiser
    accept_capped: bool = False
    real_time: bool = False
    keep_active_multipliers: bool = False

    def attempt(self, args: dict, lbg: np.ndarray, ubg: np.ndarray, stats: GuidanceStats) -> Attempt:
        """One call with ``args``; its iteration count goes to ``stats.iterations``."""
        t0 = time.perf_counter()
        try:
            sol = self.solver(**args)
            st = self.solver.stats()
        except RuntimeError as exc:  # CasADi raises RuntimeError on evaluation errors
            return Attempt(False, time.perf_counter() - t0, f"exception: {exc}", None, self)
        wall = time.perf_counter() - t0
        status = str(st.get("return_status", ""))
        stats.iterations.append(int(st.get("iter_count", -1)))
        ok = bool(st.get("success", False))
        if not ok and self.accept_capped and status.strip() == _CAPPED:
            gv = np.asarray(sol["g"]).reshape(-1)
            viol = max(float(np.max(lbg - gv, initial=0.0)), float(np.max(gv - ubg, initial=0.0)))
            ok = self.real_time or viol <= ACCEPT_VIOLATION
            if ok and not self.real_time:
                stats.inexact += 1
        return Attempt(ok and bool(np.all(np.isfinite(np.asarray(sol["x"])))), wall, status, sol, self)


@dataclass(eq=False)
class SolverChain:
    """Tiers tried in order until one succeeds; each later tier starts from the iterate and multipliers of the tier
    before it when those are finite (counted in ``stats.escalations``)."""

    tiers: list[SolverTier] = field(default_factory=list)

    def solve(self, args: dict, lbg: np.ndarray, ubg: np.ndarray, stats: NmpcStats) -> Attempt:
        """Run the tiers on ``args``; the last attempt, with the wall time of all of them."""
        wall, att = 0.0, None
        for tier in self.tiers:
            if att is not None:
                if att.ok:
                    break
                stats.escalations += 1
                sol = att.sol
                if sol is not None and np.all(np.isfinite(np.asarray(sol["x"]))):
                    args = dict(args, x0=sol["x"], lam_g0=sol["lam_g"], lam_x0=sol["lam_x"])
            att = tier.attempt(args, lbg, ubg, stats)
            wall += att.wall_s
        return Attempt(att.ok, wall, att.status, att.sol, att.tier)


@dataclass(frozen=True, eq=False)
class NmpcSolvers:
    """The two chains and whether every solver that should be compiled is."""

    fast: SolverChain
    cold: SolverChain
    compiled: bool


def build_solvers(config: NmpcConfig, problem: NmpcProblem, n_path: int) -> NmpcSolvers:
    """The fast and cold chains of ``config`` on ``problem`` (``n_path`` path rows per step: teammate and keep-out
    slots); see the module docstring."""
    c, pb = config, problem
    nlp, wvar, P, lam_f, lam_g, H_gn = pb.nlp, pb.nlp["x"], pb.nlp["p"], pb.lam_f, pb.lam_g, pb.H_gn
    compiled = c.compiled

    def hess_fun(H: ca.SX) -> ca.Function:
        return ca.Function("nlp_hess_l", [wvar, P, lam_f, lam_g], [H], *_HESS_IO)

    def nlpsol(name: str, plugin: str, opts: dict) -> BufferedCall:
        nonlocal compiled
        if not c.compiled:
            return BufferedCall(ca.nlpsol(name, plugin, nlp, opts))
        solver, ok = compiled_nlpsol(name, plugin, nlp, opts)
        compiled = compiled and ok
        return BufferedCall(solver)

    if c.solver == "fatrop":  # exact Hessian, stage-wise (see nmpc_stage); no tiers
        fat = FatropSolver("nmpc_fatrop", pb, n_path, {"tol": c.fatrop_tol, "max_iter": c.fatrop_max_iter},
                           compiled=c.compiled)
        compiled = compiled and fat.compiled
        fast = SolverChain([SolverTier(name="fatrop", solver=fat, accept_capped=True)])
    elif c.solver == "ipopt":  # IPOPT takes the upper triangle
        opts = {"hess_lag": hess_fun(ca.triu(H_gn)), "print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
                "ipopt.max_iter": c.max_iter, "ipopt.warm_start_init_point": "yes", "ipopt.tol": 1e-6,
                "ipopt.acceptable_tol": 1e-4}
        fast = SolverChain([SolverTier(name="ipopt", solver=BufferedCall(ca.nlpsol("nmpc", "ipopt", nlp, opts)),
                                       accept_capped=True)])
    else:
        H_cc = pb.curvature_hessian()
        rti = c.solver == "rti"
        if c.hessian == "tiered":
            first = nlpsol("nmpc", "sqpmethod", _sqp_options(c, hess_fun(H_gn), "gauss_newton"))
            second = nlpsol("nmpc_curv", "sqpmethod", _sqp_options(c, hess_fun(H_cc), "constraint_curvature"))
            fast = SolverChain([SolverTier(name="gauss_newton", solver=first),
                                SolverTier(name="constraint_curvature", solver=second, accept_capped=True,
                                           real_time=rti)])
        else:
            H = H_gn if c.hessian == "gauss_newton" else H_cc
            only = nlpsol("nmpc", "sqpmethod", _sqp_options(c, hess_fun(H), c.hessian))
            fast = SolverChain([SolverTier(name=c.hessian, solver=only, accept_capped=True, real_time=rti)])
    cold_opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-6,
                 "ipopt.max_iter": c.cold_start_max_iter}
    cold = SolverChain([SolverTier(name="ipopt_exact", solver=BufferedCall(ca.nlpsol("nmpc_cold", "ipopt", nlp,
                                                                                     cold_opts)),
                                   keep_active_multipliers=True)])
    return NmpcSolvers(fast=fast, cold=cold, compiled=compiled)


def _sqp_options(c: NmpcConfig, hess: ca.Function, hessian: str) -> dict:
    """sqpmethod + qrqp options for the tier of Hessian ``hessian``."""
    if c.solver == "rti":
        max_iter = 1
    else:
        max_iter = c.gauss_newton_max_iter if c.hessian == "tiered" and hessian == "gauss_newton" else c.max_iter
    opts = {"qpsol": "qrqp", "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False,
                                               "error_on_fail": False},
            "print_header": False, "print_iteration": False, "print_status": False, "print_time": False,
            "hess_lag": hess, "max_iter": max_iter, "tol_pr": 1e-5, "tol_du": 1e-2, "error_on_fail": False}
    if hessian == "constraint_curvature":
        opts.update(convexify_strategy=c.convexify, convexify_margin=c.convexify_margin)
    return opts
