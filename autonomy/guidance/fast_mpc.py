"""Linearised tracking MPC with inter-UAV separation, solved by a fixed-iteration interior point ("fast MPC",
Hu, Zhang, Tao, Wang 2018, section IV).

Model (Euler unicycle, step T): X = (x, y, θ), u = (v, ω), X⁺ = X + T (v cos θ, v sin θ, ω). Each step the model is
linearised about a reference (x^r_k, u^r_k): the previous inputs shifted by one step, rolled out through the nonlinear
model from the current state, so the reference is dynamically consistent and the first predicted step is exact
(the paper's R_es with shifted previous *states* is not, when the plant deviates). Then X_{k+1} = A_k X_k + B_k u_k
+ r_k with A_k = I + T [[0, 0, −v^r sin θ^r], [0, 0, v^r cos θ^r], 0], B_k = T [[cos θ^r, 0], [sin θ^r, 0], [0, 1]] and
r_k = f(x^r_k, u^r_k) − A_k x^r_k − B_k u^r_k. Cost (paper eq. 19, plus a heading regulariser ε θ² and the slack
penalty): Σ_{k=1}^M w_x (x_k − x^t_k)² + w_y (y_k − y^t_k)² + Σ_{k=0}^{M−1} w_v v_k² + w_o ω_k².
Decision vector z = [u_0, X_1, …, u_{M−1}, X_M, e_1, …, e_M] (e: separation slacks, penalised ρ₁ e + ρ₂ e²).

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

import numpy as np

from autonomy.guidance.base import Guidance
from autonomy.guidance.blas import blas_threads
from autonomy.guidance.pdip import PdipOptions, solve_qp_pdip
from autonomy.guidance.setpoints import UnicycleSetpoint
from autonomy.guidance.types import OwnState, TargetEstimate, TeammateState

__all__ = ["FastMpcConfig", "FastMpcQp", "FastMpcGuidance", "build_fast_mpc_qp", "euler_rollout"]

_NX, _NU = 3, 2


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
    (x_ref (M+1, 3), u_ref (M, 2))."""

    H: np.ndarray
    f: np.ndarray
    C: np.ndarray
    b: np.ndarray
    P: np.ndarray
    m: np.ndarray
    x_ref: np.ndarray
    u_ref: np.ndarray


def euler_rollout(x0: np.ndarray, u: np.ndarray, dt: float) -> np.ndarray:
    """States (M+1, 3) of the Euler unicycle from ``x0`` (3,) under inputs ``u`` (M, 2)."""
    xs = [np.asarray(x0, dtype=float)]
    for v, om in u:
        x, y, th = xs[-1]
        xs.append(np.array([x + dt * v * np.cos(th), y + dt * v * np.sin(th), th + dt * om]))
    return np.array(xs)


def build_fast_mpc_qp(c: FastMpcConfig, x0: np.ndarray, u_ref: np.ndarray, target_xy: np.ndarray,
                      others_xy: Sequence[np.ndarray]) -> FastMpcQp:
    """Stack the QP (module docstring) for state ``x0`` (3,), reference inputs ``u_ref`` (M, 2), predicted target
    positions ``target_xy`` (M, 2) at steps 1..M and same-altitude teammates' predicted positions (M, 2) each."""
    M, T = c.horizon, c.dt
    nb = _NX + _NU
    n = nb * M + M
    xr = euler_rollout(x0, u_ref, T)
    H = np.zeros(n)
    f = np.zeros(n)
    C = np.zeros((_NX * M, n))
    b = np.zeros(_NX * M)
    rows_P, rows_m = [], []
    D2 = c.separation_distance + c.separation_margin
    for k in range(M):
        iu, ix, ie = nb * k, nb * k + _NU, nb * M + k
        H[iu:iu + 2] = 2 * np.array([c.w_v, c.w_o])
        H[ix:ix + 3] = 2 * np.array([c.w_x, c.w_y, c.theta_reg])
        f[ix:ix + 2] = -2 * np.array([c.w_x, c.w_y]) * target_xy[k]
        H[ie], f[ie] = 2 * c.slack_l2, c.slack_l1
        th, v = xr[k, 2], u_ref[k, 0]
        A = np.eye(3)
        A[0, 2], A[1, 2] = -T * v * np.sin(th), T * v * np.cos(th)
        B = T * np.array([[np.cos(th), 0.0], [np.sin(th), 0.0], [0.0, 1.0]])
        r = xr[k + 1] - A @ xr[k] - B @ u_ref[k]
        rows = slice(_NX * k, _NX * (k + 1))
        C[rows, ix:ix + 3] = np.eye(3)
        C[rows, iu:iu + 2] = -B
        if k == 0:
            b[rows] = A @ x0 + r
        else:
            C[rows, ix - nb:ix - nb + 3] = -A
            b[rows] = r
        for j, (lo, hi) in enumerate(((c.v_min, c.v_max), (-c.omega_max, c.omega_max))):
            row = np.zeros(n)
            row[iu + j] = 1.0
            rows_P += [row, -row]
            rows_m += [hi, -lo]
        row = np.zeros(n)
        row[ie] = -1.0
        rows_P.append(row)
        rows_m.append(0.0)
        for q in others_xy:
            row = np.zeros(n)
            row[ie] = -1.0
            if c.separation_mode == "buffered":
                d = xr[k + 1, :2] - q[k]
                nrm = float(np.linalg.norm(d))
                side = xr[k + 1, 2] + np.pi / 2  # coincident references: push sideways
                nv = d / nrm if nrm > 1e-9 else np.array([np.cos(side), np.sin(side)])
                mid = 0.5 * (xr[k + 1, :2] + q[k])
                row[ix:ix + 2] = -nv
                rows_m.append(-(nv @ mid + D2 / 2))
            else:
                sg = 1.0 if (xr[k + 1, 0] + xr[k + 1, 1]) >= (q[k, 0] + q[k, 1]) else -1.0
                row[ix:ix + 2] = -sg
                rows_m.append(-(sg * (q[k, 0] + q[k, 1]) + np.sqrt(2) * D2))
            rows_P.append(row)
    return FastMpcQp(H=np.diag(H), f=f, C=C, b=b, P=np.array(rows_P), m=np.array(rows_m), x_ref=xr, u_ref=u_ref)


class FastMpcGuidance(Guidance):
    """Fast MPC tracking of the predicted target with separation from same-altitude teammates (module docstring)."""

    def __init__(self, config: FastMpcConfig) -> None:
        super().__init__()
        self.config = config
        self.plan_dt = config.dt
        self._u: np.ndarray | None = None
        self._plan: np.ndarray | None = None
        self.last_qp: FastMpcQp | None = None

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
        tk = t + c.dt * np.arange(1, c.horizon + 1)
        if self._u is None:
            u_ref = np.tile([float(np.clip(own.speed, c.v_min, c.v_max)), 0.0], (c.horizon, 1))
        else:
            u_ref = np.vstack([self._u[1:], self._u[-1:]])
            if self._plan is not None:  # keep θ on the plan's branch
                x0[2] += 2 * np.pi * np.round((self._plan[1, 2] - x0[2]) / (2 * np.pi))
        u_ref[:, 0] = np.clip(u_ref[:, 0], max(c.v_min, c.linearization_min_speed), c.v_max)
        others = [tm.predict_xy(tk) for tm in teammates if abs(tm.p_W[2] - own.p_W[2]) <= c.altitude_tolerance]
        qp = build_fast_mpc_qp(c, x0, u_ref, target.predict_xy(tk), others)
        self.last_qp = qp
        z0 = self._stack(qp.x_ref, u_ref)
        t0, c0 = time.perf_counter(), time.thread_time()
        with blas_threads(1):  # tiny dense factorisations: threads only add overhead
            sol = solve_qp_pdip(qp.H, qp.f, qp.C, qp.b, qp.P, qp.m, c.pdip, z0=z0)
        self.stats.solve_times_s.append(time.perf_counter() - t0)
        self.stats.solve_cpu_times_s.append(time.thread_time() - c0)
        self.stats.solves += 1
        self.stats.iterations.append(sol.iterations)
        self.stats.last_status = "converged" if sol.converged else f"iteration cap, residual {sol.residual:.2e}"
        if not sol.converged:
            self.stats.inexact += 1
        u = sol.z[: (_NX + _NU) * c.horizon].reshape(c.horizon, _NX + _NU)[:, :_NU]
        if not np.all(np.isfinite(u)):
            self.stats.failures += 1
            self.stats.fallbacks_shifted += 1
            u = u_ref
        u = np.column_stack([np.clip(u[:, 0], c.v_min, c.v_max), np.clip(u[:, 1], -c.omega_max, c.omega_max)])
        self._u = u
        self._plan = euler_rollout(x0, u, c.dt)
        return UnicycleSetpoint(speed=float(u[0, 0]), heading_rate=float(u[0, 1]), altitude=alt)

    def _stack(self, x_ref: np.ndarray, u_ref: np.ndarray) -> np.ndarray:
        M = self.config.horizon
        blocks = np.hstack([u_ref, x_ref[1:]]).reshape(-1)
        return np.concatenate([blocks, np.zeros(M)])
