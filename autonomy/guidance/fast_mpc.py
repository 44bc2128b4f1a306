"""Linearised tracking MPC with inter-UAV separation, solved by a fixed-iteration interior point ("fast MPC",
Hu, Zhang, Tao, Wang 2018, section IV).

Model (Euler unicycle, step T): X = (x, y, θ), u = (v, ω), X⁺ = X + T (v cos θ, v sin θ, ω). Each step the model is
linearised about a reference (x^r_k, u^r_k): the previous inputs shifted by one step, rolled out through the nonlinear
model from the current state, so the reference is dynamically consistent and the first predicted step is exact
(the paper's R_es with shifted previous *states* is not, when the plant deviates). Then X_{k+1} = A_k X_k + B_k u_k
+ r_k with A_k = I + T [[0, 0, −v^r sin θ^r], [0, 0, v^r cos θ^r], 0], B_k = T [[cos θ^r, 0], [sin θ^r, 0], [0, 1]] and
r_k = f(x^r_k, u^r_k) − A_k x^r_k − B_k u^r_k. Cost (paper eq. 19, plus a heading regulariser ε θ² and the slack
penalty): Σ_{k=1}^M w_x (x_k − x^t_k)² + w_y (y_k − y^t_k)² + Σ_{k=0}^{M−1} w_v v_k² + w_o ω_k².
Decision vector z = [u_0, X_1, e_1, …, u_{M−1}, X_M, e_M] (e: separation slacks, penalised ρ₁ e + ρ₂ e²), stage by
stage so that the interior point's factorisations stay banded (see :mod:`autonomy.guidance.pdip`).

Separation ‖p_k − q_k‖ ≥ D against each same-altitude teammate's predicted (shared) position q_k, made linear:

- ``"buffered"`` (robust variant, default): the half-plane beyond the perpendicular bisector of the two reference
  positions, n_kᵀ (p_k − (p^r_k + q_k)/2) ≥ D'/2 − e_k with n_k the unit vector from q_k to p^r_k. When both UAVs plan
  on the same shared references their half-planes are disjoint and ≥ D' apart, so the constraint holds whatever the
  other UAV decides; the half-plane is outside the disc ‖p − q_k‖ < D'/2, hence conservative;
- ``"paper"``: the paper's eq. 29, σ((x_k + y_k) − (q_x + q_y)) ≥ √2 D' − e_k, σ the sign at the reference.

D' = D + ``separation_margin`` absorbs the linearisation error of later steps. The QP is solved by
:func:`autonomy.guidance.pdip.solve_qp_pdip` with a fixed iteration cap.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numba
import numpy as np

from autonomy.guidance.base import Guidance
from autonomy.guidance.pdip import PdipOptions, solve_qp_pdip
from interfaces.setpoints import UnicycleSetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState

__all__ = ["FastMpcConfig", "FastMpcQp", "FastMpcGuidance", "build_fast_mpc_qp", "euler_rollout"]

_NX, _NU = 3, 2
_NB = _NX + _NU + 1  # variables per stage: u_k, X_{k+1}, e_{k+1}


@dataclass(frozen=True, kw_only=True)
class FastMpcConfig:
    """Fast MPC (paper 000 numbers: T = 0.5 s, M = 10, D = 10 m, 0 ≤ v ≤ 40 m/s, |ω| ≤ 5 rad/s, weights
    (w_v, w_o, w_x, w_y) = (5, 180, 0.5, 0.5)).

    Attributes
    ----------
    dt : float
        Step T (s), > 0.
    horizon : int
        Steps M, >= 1.
    v_min, v_max : float
        Speed bounds (m/s), 0 <= v_min < v_max.
    omega_max : float
        Heading-rate bound |ω| (rad/s), > 0.
    w_x, w_y, w_v, w_o : float
        Cost weights (1/m², 1/m², s²/m², s²/rad²), >= 0, w_x + w_y > 0.
    theta_reg : float
        Heading regulariser ε (1/rad²), >= 0 (keeps H non-singular together with the solver's δ).
    separation_distance : float
        D (m), > 0.
    separation_margin : float
        Added to D in the planner (m), >= 0.
    separation_mode : {"buffered", "paper"}
        Linearisation of the separation constraint (module docstring).
    altitude_tolerance : float
        Teammates within this altitude difference are "same altitude" and constrained (m), >= 0.
    slack_l1, slack_l2 : float
        Slack penalty weights ρ₁ (1/m), ρ₂ (1/m²), >= 0.
    linearization_min_speed : float
        Floor of the reference speed the model is linearised about (m/s), >= 0: at v^r = 0 the heading has no
        effect on the linear model and a UAV at rest would never turn.
    altitude : float | None
        Commanded altitude (m); ``None`` holds the current one.
    pdip : PdipOptions
        Interior-point options (iteration cap).
    """

    dt: float = 0.5
    horizon: int = 10
    v_min: float = 0.0
    v_max: float = 18.0
    omega_max: float = 1.0
    w_x: float = 0.5
    w_y: float = 0.5
    w_v: float = 5.0
    w_o: float = 180.0
    theta_reg: float = 1e-4
    separation_distance: float = 10.0
    separation_margin: float = 4.0
    separation_mode: Literal["buffered", "paper"] = "buffered"
    altitude_tolerance: float = 5.0
    slack_l1: float = 1e4
    slack_l2: float = 1e2
    linearization_min_speed: float = 2.0
    altitude: float | None = None
    pdip: PdipOptions = field(default_factory=PdipOptions)

    def __post_init__(self) -> None:
        for name in ("dt", "omega_max", "separation_distance"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ValueError(f"FastMpcConfig.{name} must be > 0, got {getattr(self, name)}")
        for name in ("w_x", "w_y", "w_v", "w_o", "theta_reg", "separation_margin", "altitude_tolerance", "slack_l1",
                     "slack_l2", "linearization_min_speed"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) >= 0):
                raise ValueError(f"FastMpcConfig.{name} must be >= 0, got {getattr(self, name)}")
        if self.w_x + self.w_y <= 0:
            raise ValueError(f"FastMpcConfig.w_x + w_y must be > 0, got {self.w_x} + {self.w_y}")
        if int(self.horizon) != self.horizon or self.horizon < 1:
            raise ValueError(f"FastMpcConfig.horizon must be an integer >= 1, got {self.horizon}")
        if not (0 <= self.v_min < self.v_max):
            raise ValueError(f"FastMpcConfig.v_min/v_max must satisfy 0 <= v_min < v_max, "
                             f"got ({self.v_min}, {self.v_max})")
        if self.separation_mode not in ("buffered", "paper"):
            raise ValueError(f"FastMpcConfig.separation_mode must be 'buffered' or 'paper', "
                             f"got {self.separation_mode!r}")


@dataclass(frozen=True, kw_only=True)
class FastMpcQp:
    """The stacked QP ½zᵀHz + fᵀz, Cz = b, Pz ≤ m of one solve, with the reference it was linearised about
    (x_ref (M+1, 3), u_ref (M, 2)) and that reference as a point of z (slacks 0), the solver's warm start."""

    H: np.ndarray
    f: np.ndarray
    C: np.ndarray
    b: np.ndarray
    P: np.ndarray
    m: np.ndarray
    x_ref: np.ndarray
    u_ref: np.ndarray
    z_ref: np.ndarray


@numba.njit(cache=True)
def _rollout(x0: np.ndarray, u: np.ndarray, dt: float) -> np.ndarray:
    xs = np.empty((u.shape[0] + 1, _NX))
    xs[0, 0], xs[0, 1], xs[0, 2] = x0[0], x0[1], x0[2]
    for k in range(u.shape[0]):
        th = xs[k, 2]
        xs[k + 1, 0] = xs[k, 0] + dt * u[k, 0] * np.cos(th)
        xs[k + 1, 1] = xs[k, 1] + dt * u[k, 0] * np.sin(th)
        xs[k + 1, 2] = th + dt * u[k, 1]
    return xs


def euler_rollout(x0: np.ndarray, u: np.ndarray, dt: float) -> np.ndarray:
    """States (M+1, 3) of the Euler unicycle from ``x0`` (3,) under inputs ``u`` (M, 2)."""
    return _rollout(np.asarray(x0, dtype=np.float64), np.ascontiguousarray(u, dtype=np.float64), float(dt))


@numba.njit(cache=True)
def _assemble(x0: np.ndarray, u_ref: np.ndarray, target_xy: np.ndarray, q: np.ndarray, dt: float, h_diag: np.ndarray,
              slack_l1: float, v_min: float, v_max: float, omega_max: float, d_sep: float, buffered: bool):
    """(H, f, C, b, P, m, x_ref, z_ref) of :func:`build_fast_mpc_qp`; ``q`` (teammates, M, 2), ``h_diag`` the
    Hessian diagonal of one stage, ``d_sep`` = D'."""
    M, nq = u_ref.shape[0], q.shape[0]
    n, ns = _NB * M, 5 + nq
    xr = _rollout(x0, u_ref, dt)
    H, f = np.zeros((n, n)), np.zeros(n)
    C, b = np.zeros((_NX * M, n)), np.zeros(_NX * M)
    P, m = np.zeros((ns * M, n)), np.zeros(ns * M)
    z_ref = np.zeros(n)
    for k in range(M):
        iu, ix, ie, row = _NB * k, _NB * k + _NU, _NB * k + _NU + _NX, _NX * k
        z_ref[iu], z_ref[iu + 1] = u_ref[k, 0], u_ref[k, 1]
        z_ref[ix], z_ref[ix + 1], z_ref[ix + 2] = xr[k + 1, 0], xr[k + 1, 1], xr[k + 1, 2]
        # cost: diag(2w_v, 2w_o, 2w_x, 2w_y, 2ε, 2ρ₂), linear part −2 w (x^t, y^t) and ρ₁ e
        for i in range(_NB):
            H[iu + i, iu + i] = h_diag[i]
        f[ix], f[ix + 1], f[ie] = -h_diag[2] * target_xy[k, 0], -h_diag[3] * target_xy[k, 1], slack_l1
        # dynamics X_{k+1} − A_k X_k − B_k u_k = r_k (A_0 x_0 + r_0 for k = 0)
        th, v = xr[k, 2], u_ref[k, 0]
        a02, a12 = -dt * v * np.sin(th), dt * v * np.cos(th)  # A_k − I
        bx, by = dt * np.cos(th), dt * np.sin(th)  # B_k = [[bx, 0], [by, 0], [0, T]]
        r = (xr[k + 1, 0] - (xr[k, 0] + a02 * th) - bx * v, xr[k + 1, 1] - (xr[k, 1] + a12 * th) - by * v,
             xr[k + 1, 2] - th - dt * u_ref[k, 1])
        C[row, ix], C[row + 1, ix + 1], C[row + 2, ix + 2] = 1.0, 1.0, 1.0
        C[row, iu], C[row + 1, iu], C[row + 2, iu + 1] = -bx, -by, -dt
        if k == 0:
            b[0], b[1], b[2] = x0[0] + a02 * x0[2] + r[0], x0[1] + a12 * x0[2] + r[1], x0[2] + r[2]
        else:
            jx = ix - _NB
            C[row, jx], C[row + 1, jx + 1], C[row + 2, jx + 2] = -1.0, -1.0, -1.0
            C[row, jx + 2], C[row + 1, jx + 2] = -a02, -a12
            b[row], b[row + 1], b[row + 2] = r
        # v ≤ v_max, −v ≤ −v_min, ω ≤ ω_max, −ω ≤ ω_max, −e ≤ 0, then one separation row per teammate
        base = ns * k
        P[base, iu], P[base + 1, iu], P[base + 2, iu + 1], P[base + 3, iu + 1] = 1.0, -1.0, 1.0, -1.0
        m[base], m[base + 1], m[base + 2], m[base + 3] = v_max, -v_min, omega_max, omega_max
        P[base + 4, ie] = -1.0
        px, py = xr[k + 1, 0], xr[k + 1, 1]
        for j in range(nq):
            rr, qx, qy = base + 5 + j, q[j, k, 0], q[j, k, 1]
            P[rr, ie] = -1.0
            if buffered:
                dx, dy = px - qx, py - qy
                nrm = np.sqrt(dx * dx + dy * dy)
                if nrm > 1e-9:
                    nx, ny = dx / nrm, dy / nrm
                else:  # coincident references: push sideways
                    side = xr[k + 1, 2] + np.pi / 2
                    nx, ny = np.cos(side), np.sin(side)
                P[rr, ix], P[rr, ix + 1] = -nx, -ny
                m[rr] = -(nx * 0.5 * (px + qx) + ny * 0.5 * (py + qy) + d_sep / 2)
            else:
                sg = 1.0 if px + py >= qx + qy else -1.0
                P[rr, ix], P[rr, ix + 1] = -sg, -sg
                m[rr] = -(sg * (qx + qy) + np.sqrt(2.0) * d_sep)
    return H, f, C, b, P, m, xr, z_ref


def build_fast_mpc_qp(c: FastMpcConfig, x0: np.ndarray, u_ref: np.ndarray, target_xy: np.ndarray,
                      others_xy: Sequence[np.ndarray]) -> FastMpcQp:
    """Stack the QP (module docstring) for state ``x0`` (3,), reference inputs ``u_ref`` (M, 2), predicted target
    positions ``target_xy`` (M, 2) at steps 1..M and same-altitude teammates' predicted positions (M, 2) each.

    Variables and rows are ordered stage by stage: block ``[u_k, X_{k+1}, e_{k+1}]``, its three dynamics rows, and
    its 5 + (teammates) inequality rows (speed and turn-rate bounds, e ≥ 0, separation), which makes each
    interior-point iteration cost O(M) (:mod:`autonomy.guidance.pdip`)."""
    M = c.horizon
    u_ref = np.ascontiguousarray(u_ref, dtype=np.float64)
    q = np.ascontiguousarray(np.asarray(others_xy, dtype=np.float64).reshape(-1, M, 2))
    h_diag = 2.0 * np.array([c.w_v, c.w_o, c.w_x, c.w_y, c.theta_reg, c.slack_l2])
    H, f, C, b, P, m, xr, z_ref = _assemble(np.asarray(x0, dtype=np.float64), u_ref,
                                     np.ascontiguousarray(target_xy, dtype=np.float64), q, float(c.dt), h_diag,
                                     float(c.slack_l1), float(c.v_min), float(c.v_max), float(c.omega_max),
                                     float(c.separation_distance + c.separation_margin),
                                     c.separation_mode == "buffered")
    return FastMpcQp(H=H, f=f, C=C, b=b, P=P, m=m, x_ref=xr, u_ref=u_ref, z_ref=z_ref)


class FastMpcGuidance(Guidance):
    """Fast MPC tracking of the predicted target with separation from same-altitude teammates (module docstring)."""

    def __init__(self, config: FastMpcConfig) -> None:
        super().__init__()
        self.config = config
        self.plan_dt = config.dt
        self._u: np.ndarray | None = None
        self._plan: np.ndarray | None = None
        self.last_qp: FastMpcQp | None = None
        self._steps = config.dt * np.arange(1, config.horizon + 1)  # t_k − t, k = 1..M (s)
        self._shift = np.minimum(np.arange(1, config.horizon + 1), config.horizon - 1)  # u_{k+1}, last one repeated
        self._u_lo = np.array([config.v_min, -config.omega_max])
        self._u_hi = np.array([config.v_max, config.omega_max])

    def plan_step_s(self) -> float:
        """Time between the points of :meth:`planned_path` (s): the planner's step."""
        return float(self.config.dt)

    def planned_path(self) -> np.ndarray | None:
        """(M, 2) positions of the last plan at t + kT, k = 1..M (nonlinear rollout of the planned inputs) (m)."""
        return None if self._plan is None else self._plan[1:, :2].copy()

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> UnicycleSetpoint:
        """Solve the QP at time ``t`` (s) and return the first (speed, heading rate)."""
        c = self.config
        self.stats.calls += 1
        alt = float(own.p_W[2]) if c.altitude is None else c.altitude
        x0 = np.array([own.p_W[0], own.p_W[1], own.course(min_speed=0.5)])
        if target is None:
            return UnicycleSetpoint(speed=c.v_min, heading_rate=0.0, altitude=alt)
        tk = t + self._steps
        if self._u is None:
            u_ref = np.tile([min(max(own.speed, c.v_min), c.v_max), 0.0], (c.horizon, 1))
        else:
            u_ref = self._u[self._shift]
            if self._plan is not None:  # keep θ on the plan's branch
                x0[2] += 2 * np.pi * round((self._plan[1, 2] - x0[2]) / (2 * np.pi))
        u_ref[:, 0] = np.clip(u_ref[:, 0], max(c.v_min, c.linearization_min_speed), c.v_max)
        others = [tm.predict_xy(tk) for tm in teammates if abs(tm.p_W[2] - own.p_W[2]) <= c.altitude_tolerance]
        qp = build_fast_mpc_qp(c, x0, u_ref, target.predict_xy(tk), others)
        self.last_qp = qp
        t0, c0 = time.perf_counter(), time.thread_time()
        sol = solve_qp_pdip(qp.H, qp.f, qp.C, qp.b, qp.P, qp.m, c.pdip, z0=qp.z_ref)
        self.stats.solve_times_s.append(time.perf_counter() - t0)
        self.stats.solve_cpu_times_s.append(time.thread_time() - c0)
        self.stats.solves += 1
        self.stats.iterations.append(sol.iterations)
        self.stats.last_status = "converged" if sol.converged else f"iteration cap, residual {sol.residual:.2e}"
        if not sol.converged:
            self.stats.inexact += 1
        u = sol.z.reshape(c.horizon, _NB)[:, :_NU]
        if not np.all(np.isfinite(u)):
            self.stats.failures += 1
            self.stats.fallbacks_shifted += 1
            u = u_ref
        u = np.clip(u, self._u_lo, self._u_hi)
        self._u = u
        self._plan = euler_rollout(x0, u, c.dt)
        return UnicycleSetpoint(speed=float(u[0, 0]), heading_rate=float(u[0, 1]), altitude=alt)
