"""The NMPC problem in stage-wise order, solved by Fatrop (a structure-exploiting interior-point OCP solver).

:func:`autonomy.guidance.nmpc_problem.build_problem` lays the decision vector out by kind,
``w = (vec(X), vec(U), S)``, with the initial state a parameter: what ``sqpmethod`` and IPOPT take. Fatrop factorises
the KKT system by a Riccati recursion over the stages, which needs the OCP form

    z_k = (x_k, s_k) (k = 0..N),  v_k = (u_k, σ_k) (k = 0..N−1),  ordered z_0, v_0, z_1, v_1, …, z_N;
    gap-closing rows  z_{k+1} − (f_d(x_k, u_k), σ_k) = 0  followed by the path rows of stage k, in stage order.

The slack s_k of the soft separation and keep-out rows at x_k becomes a sixth state, chosen one step ahead by
the control σ_{k−1}: a path row may depend on its own stage only, and the last stage has no control. The initial
state is fixed by the bounds of z_0 (x_0 as given, s_0 = 0); ``p`` keeps the by-kind layout (its initial-state
entries are unused). :class:`StageLayout` maps vectors between the two orders, so the guidance keeps its warm
starts, plans and multipliers in the by-kind layout, and :class:`FatropSolver` takes and returns that layout: to
:class:`autonomy.guidance.nmpc.NmpcStandoffGuidance` it is one more solver of the same problem.

Fatrop uses the exact Hessian of the Lagrangian (the constraint curvature the Gauss–Newton SQP misses, see
``docs/nmpc.md``), is started from the shifted plan and needs no escalation tiers. Its functions are
compiled like the SQP's (:func:`autonomy.guidance.codegen.compiled_nlpsol`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from autonomy.guidance.codegen import BufferedCall, compiled_nlpsol
from autonomy.guidance.nmpc_problem import NU, NX, NmpcProblem

__all__ = ["FatropSolver", "StageLayout"]

_NZ, _NV = NX + 1, NU + 1  # stage state (x, s) and stage control (u, σ)


@dataclass(frozen=True)
class StageLayout:
    """Index maps between the by-kind layout (``w = (vec(X), vec(U), S)``, ``g`` per step ``(dynamics, path)``) and
    the stage-wise one of the module docstring, for horizon ``n`` and ``n_path`` path rows per step."""

    n: int
    n_path: int

    @property
    def n_w(self) -> int:
        """Size of the stage-wise decision vector."""
        return self.n * (_NZ + _NV) + _NZ

    def z(self, k: int) -> int:
        """Offset of z_k in the stage-wise vector."""
        return k * (_NZ + _NV)

    def v(self, k: int) -> int:
        """Offset of v_k in the stage-wise vector."""
        return k * (_NZ + _NV) + _NZ

    def w_from_kind(self) -> np.ndarray:
        """For each stage-wise entry, its index in the by-kind vector; −1 for z_0 (the initial state and s_0)."""
        n = self.n
        idx = np.full(self.n_w, -1)
        for k in range(n):
            idx[self.v(k):self.v(k) + NU] = NX * n + NU * k + np.arange(NU)  # u_k
            idx[self.v(k) + NU] = (NX + NU) * n + k  # σ_k = s_{k+1}
            idx[self.z(k + 1):self.z(k + 1) + NX] = NX * k + np.arange(NX)  # x_{k+1}
            idx[self.z(k + 1) + NX] = (NX + NU) * n + k  # s_{k+1}
        return idx

    def kind_from_w(self) -> np.ndarray:
        """For each by-kind entry, its index in the stage-wise vector (the slack is read from the states)."""
        n = self.n
        idx = np.empty((NX + NU + 1) * n, dtype=int)
        for k in range(n):
            idx[NX * k:NX * (k + 1)] = self.z(k + 1) + np.arange(NX)
            idx[NX * n + NU * k:NX * n + NU * (k + 1)] = self.v(k) + np.arange(NU)
            idx[(NX + NU) * n + k] = self.z(k + 1) + NX
        return idx

    def g_from_kind(self) -> np.ndarray:
        """For each stage-wise row, its row in the by-kind ``g``; −1 for the slack rows s_{k+1} − σ_k = 0."""
        n, per = self.n, NX + self.n_path
        rows: list[int] = []
        for k in range(n + 1):
            if k < n:
                rows += list(per * k + np.arange(NX)) + [-1]
            if k > 0:
                rows += list(per * (k - 1) + NX + np.arange(self.n_path))
        return np.asarray(rows, dtype=int)


class FatropSolver:
    """Fatrop on the stage-wise form of ``problem``, called and answering in the by-kind layout like the SQP solvers
    (``solver(x0=, p=, lbx=, ubx=, lbg=, ubg=, lam_g0=, lam_x0=)`` → ``x, f, g, lam_g, lam_x``; ``stats()``).

    Parameters
    ----------
    name : str
        Solver name (and compiled library prefix).
    problem : NmpcProblem
        The by-kind problem; ``x0`` is read from ``p`` (its ``layout.x0``) at each call.
    n_path : int
        Path rows per step (teammate separation and keep-out slots).
    opts : dict
        Options of Fatrop itself (``tol``, ``max_iter``, ...).
    compiled : bool
        Compile the problem's functions (see :func:`autonomy.guidance.codegen.compiled_nlpsol`).
    """

    def __init__(self, name: str, problem: NmpcProblem, n_path: int, opts: dict, compiled: bool = True) -> None:
        n = int(problem.lbx.size // (NX + NU + 1))
        self.layout = lay = StageLayout(n, n_path)
        self._w_idx, self._kind_idx, self._g_idx = lay.w_from_kind(), lay.kind_from_w(), lay.g_from_kind()
        wk, P = problem.nlp["x"], problem.nlp["p"]
        W = ca.SX.sym("w", lay.n_w)
        # by-kind variables and the initial state as expressions of the stage-wise ones
        self._x0 = problem.layout.x0  # the initial state's entries of p
        f, g = ca.substitute([problem.nlp["f"], problem.nlp["g"]], [wk, P[self._x0]],
                             [W[self._kind_idx], W[lay.z(0):lay.z(0) + NX]])
        rows = [g[int(r)] if r >= 0 else None for r in self._g_idx]
        slack_rows = iter(W[lay.z(k + 1) + NX] - W[lay.v(k) + NU] for k in range(n))
        g_stage = ca.vertcat(*[r if r is not None else next(slack_rows) for r in rows])
        eq_kind = problem.ubg == 0.0
        self._equality = [bool(eq_kind[r]) if r >= 0 else True for r in self._g_idx]
        nlp = {"x": W, "p": P, "f": f, "g": g_stage}
        sopts = {"structure_detection": "auto", "equality": self._equality, "calc_lam_p": False, "print_time": False,
                 "fatrop": {"print_level": 0, **opts}}
        if compiled:
            fun, self.compiled = compiled_nlpsol(name, "fatrop", nlp, sopts)
        else:
            fun, self.compiled = ca.nlpsol(name, "fatrop", nlp, sopts), False
        self._call = BufferedCall(fun)
        self._lbg_idx = np.where(self._g_idx >= 0, self._g_idx, 0)
        self._sigma = np.array([lay.v(k) + NU for k in range(n)], dtype=int)  # σ_k in the stage-wise vector

    def _to_stage(self, v_kind: np.ndarray, z0: np.ndarray) -> np.ndarray:
        out = np.asarray(v_kind, dtype=float).reshape(-1)[np.maximum(self._w_idx, 0)]
        out[self.layout.z(0):self.layout.z(0) + _NZ] = z0
        return out

    def _rows(self, v_kind: np.ndarray) -> np.ndarray:
        """Constraint bounds in stage-wise order; the slack rows are equalities (0)."""
        out = np.asarray(v_kind, dtype=float).reshape(-1)[self._lbg_idx]
        out[self._g_idx < 0] = 0.0
        return out

    def __call__(self, *, x0: np.ndarray, p: np.ndarray, lbx: np.ndarray, ubx: np.ndarray, lbg: np.ndarray,
                 ubg: np.ndarray, lam_g0: np.ndarray | None = None,
                 lam_x0: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Solve from the by-kind guess ``x0``; the solution in the by-kind layout (``g`` and ``lam_g`` without the
        slack rows, ``lam_x`` of the slack from its bound on the state). Fatrop starts from the primal guess alone
        (it does not use multiplier guesses), so ``lam_g0`` / ``lam_x0`` are accepted, like the SQP's, and dropped."""
        p = np.asarray(p, dtype=float).reshape(-1)
        xi = np.concatenate([p[self._x0], [0.0]])
        lbx_s, ubx_s = self._to_stage(lbx, xi), self._to_stage(ubx, xi)
        # the slack's bound holds on the state s_{k+1} only: bounding σ_k = s_{k+1} too would make the two active
        # bounds linearly dependent with the gap row, and the barrier would split the multiplier between them
        lbx_s[self._sigma], ubx_s[self._sigma] = -np.inf, np.inf
        sol = self._call(x0=self._to_stage(x0, xi), p=p, lbx=lbx_s, ubx=ubx_s, lbg=self._rows(lbg),
                         ubg=self._rows(ubg))
        keep = self._g_idx >= 0
        g, lam_g = np.empty(int(keep.sum())), np.empty(int(keep.sum()))
        g[self._g_idx[keep]] = sol["g"][keep]
        lam_g[self._g_idx[keep]] = sol["lam_g"][keep]
        return {"x": sol["x"][self._kind_idx], "f": sol["f"], "g": g, "lam_g": lam_g,
                "lam_x": sol["lam_x"][self._kind_idx]}

    def stats(self) -> dict:
        """Statistics of the last call (CasADi's: ``success``, ``return_status``, ``iter_count``, ...)."""
        return self._call.stats()
