"""The NMPC's optimisation problem, built symbolically with CasADi: decision variables, the least-squares cost with
its Gauss–Newton Hessian, the dynamics, separation and keep-out constraints, and their bounds.

The formulation (cost terms, phase residuals, soft constraints with the scaled slack) is stated in
:mod:`autonomy.guidance.nmpc`, which builds solvers on this problem; the reasons for it are in ``docs/nmpc.md``. The
decision vector is ``w = (vec(X), vec(U), S)``: the N predicted states (5 each: x, y, heading, speed, heading rate),
the N controls (speed and heading-rate commands) and the N slacks; the parameter vector ``p`` is laid out by
:class:`autonomy.guidance.nmpc_layout.ParameterLayout` (initial state, target, teammate and keep-out slots), which
unpacks it here and packs it in the guidance.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from autonomy.guidance.nmpc_config import NmpcConfig
from autonomy.guidance.nmpc_layout import NU, NX, ParameterLayout

__all__ = ["NX", "NU", "NmpcProblem", "build_problem", "rk4_model"]

_NX, _NU = NX, NU


def rk4_model(c: NmpcConfig) -> ca.Function:
    """Discrete prediction model x_{k+1} = f_d(x_k, u_k) of the lagged unicycle (RK4, ``c.substeps`` substeps)."""
    x, u = ca.SX.sym("x", _NX), ca.SX.sym("u", _NU)

    def rhs(z: ca.SX) -> ca.SX:
        dv = (u[0] - z[3]) / c.model.tau_v if c.model.tau_v > 0 else 0
        dw = (u[1] - z[4]) / c.model.tau_omega if c.model.tau_omega > 0 else 0
        return ca.vertcat(z[3] * ca.cos(z[2]), z[3] * ca.sin(z[2]), z[4], dv, dw)

    z = ca.vertcat(x[0], x[1], x[2], u[0] if c.model.tau_v == 0 else x[3], u[1] if c.model.tau_omega == 0 else x[4])
    h = c.dt / c.substeps
    for _ in range(c.substeps):
        k1 = rhs(z)
        k2 = rhs(z + h / 2 * k1)
        k3 = rhs(z + h / 2 * k2)
        k4 = rhs(z + h * k3)
        z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return ca.Function("f_d", [x, u], [z])


@dataclass(frozen=True, eq=False)
class NmpcProblem:
    """The built problem.

    Attributes
    ----------
    nlp : dict
        CasADi NLP ``{"x": w, "p": p, "f": J, "g": g}``.
    f_d : casadi.Function
        Discrete prediction model ``x_{k+1} = f_d(x_k, u_k)``.
    lam_f, lam_g : casadi.SX
        Symbols of the cost multiplier and the constraint multipliers (for Hessians of the Lagrangian).
    H_gn : casadi.SX
        Gauss–Newton Hessian of the Lagrangian, ``λ_f (J_Rᵀ J_R + 1e-6 I)``.
    layout : ParameterLayout
        Layout of the parameter vector ``p``.
    n_par, n_g : int
        Sizes of the parameter vector and of the constraint vector.
    lbx, ubx, lbg, ubg : np.ndarray
        Bounds of the decision variables and of the constraints (dynamics rows are equalities).
    """

    nlp: dict
    f_d: ca.Function
    lam_f: ca.SX
    lam_g: ca.SX
    H_gn: ca.SX
    layout: ParameterLayout
    n_par: int
    n_g: int
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray

    def curvature_hessian(self) -> ca.SX:
        """Gauss–Newton Hessian plus the exact constraint curvature Σ λ_j ∇²g_j (the constraint-curvature SQP's)."""
        return self.H_gn + ca.hessian(ca.dot(self.lam_g, self.nlp["g"]), self.nlp["x"])[0]


def build_problem(config: NmpcConfig, n_teammates: int, n_buildings: int, slack_scale: float) -> NmpcProblem:
    """The problem for ``n_teammates`` teammate slots and ``n_buildings`` keep-out slots, with the slack decision
    variable scaled by ``slack_scale`` (cost units; see ``docs/nmpc.md``)."""
    c, w = config, config.weights
    n, m, nb = c.horizon, n_teammates, n_buildings
    f_d = rk4_model(c)
    layout = ParameterLayout(n, m, nb)
    n_par = layout.size
    P = ca.SX.sym("p", n_par)
    X = ca.SX.sym("X", _NX, n)
    U = ca.SX.sym("U", _NU, n)
    S = ca.SX.sym("S", n)
    x0, pt0, vt, tms, bls = layout.unpack(P)
    Sk = S / slack_scale  # the slack in constraint units; the decision variable is slack_scale times it
    rd2 = c.standoff_radius ** 2
    vmax, wmax = c.speed_deviation, c.max_heading_rate
    w_nom = c.direction * c.nominal_speed / c.standoff_radius
    res, lin, g = [], 0, []  # cost = ½|res|² + lin (least squares, for the Gauss-Newton Hessian)
    xk = x0
    for k in range(n):
        xn = f_d(xk, U[:, k])
        g.append(X[:, k] - xn)
        xk = X[:, k]
        res += [np.sqrt(w.r_v) * (U[0, k] - c.nominal_speed) / vmax, np.sqrt(w.r_omega) * (U[1, k] - w_nom) / wmax]
        p = X[0:2, k]
        pt = pt0 + vt * (k + 1) * c.dt
        r = p - pt
        rr = ca.sumsqr(r)
        rt = (rd2 - rr) / rd2
        qr, qd = (w.p_r, w.p_d) if k == n - 1 else (w.q_r, w.q_d)
        res.append(np.sqrt(qr) * rt)
        if m > 0:
            u_me = r / ca.sqrt(rr + 1.0)
            n_act = sum(tm.active for tm in tms)
            scale = np.sqrt(qd) / ca.sqrt(ca.fmax(n_act, 1))
            for act, cph, sph, Q in tms:
                rj = Q[:, k] - pt
                if c.phase_cost == "paper":
                    dt_ = (ca.dot(r, rj) + ca.sqrt(rr + 1e-6) * ca.sqrt(ca.sumsqr(rj) + 1e-6)) / rd2
                    res.append(scale * act * dt_)
                else:
                    uj = rj / ca.sqrt(ca.sumsqr(rj) + 1.0)
                    ujr = ca.vertcat(cph * uj[0] - sph * uj[1], sph * uj[0] + cph * uj[1])
                    res += [scale * act * (u_me[0] - ujr[0]), scale * act * (u_me[1] - ujr[1])]
                g.append(act * (ca.sumsqr(p - Q[:, k]) / c.separation_distance ** 2 - 1) + (1 - act) + Sk[k])
        for bp in bls:
            d = p - bp[1:3]
            lx = (bp[3] * d[0] + bp[4] * d[1]) * bp[5]
            ly = (-bp[4] * d[0] + bp[3] * d[1]) * bp[6]
            g.append(bp[0] * (lx ** 2 + ly ** 2 - 1) + (1 - bp[0]) + Sk[k])
        res.append(np.sqrt(2 * w.slack_l2) * Sk[k])
        lin += w.slack_l1 * Sk[k]
    wvar = ca.vertcat(ca.vec(X), ca.vec(U), S)
    R = ca.vertcat(*res)
    J = 0.5 * ca.sumsqr(R) + lin
    # Gauss-Newton Hessian of the Lagrangian: σ J_Rᵀ J_R (+ a small regulariser), constraint curvature ignored
    lam_f = ca.SX.sym("lam_f")
    JR = ca.jacobian(R, wvar)
    H_gn = lam_f * (ca.mtimes(JR.T, JR) + 1e-6 * ca.SX.eye(wvar.shape[0]))
    g_all = ca.vertcat(*g)
    n_g = int(g_all.shape[0])
    lam_g = ca.SX.sym("lam_g", n_g)
    lo, hi = c.speed_bounds
    inf = np.inf
    lbx = np.concatenate([np.full(_NX * n, -inf), np.tile([lo, -wmax], n), np.zeros(n)])
    ubx = np.concatenate([np.full(_NX * n, inf), np.tile([hi, wmax], n), np.full(n, inf)])
    # the equality rows are interleaved per step: mark them by structure
    eq_mask = np.zeros(n_g, dtype=bool)
    row = 0
    for _ in range(n):
        eq_mask[row:row + _NX] = True
        row += _NX + m + nb
    return NmpcProblem(nlp={"x": wvar, "p": P, "f": J, "g": g_all}, f_d=f_d, lam_f=lam_f, lam_g=lam_g,
                       H_gn=H_gn, layout=layout, n_par=n_par, n_g=n_g, lbx=lbx, ubx=ubx, lbg=np.zeros(n_g),
                       ubg=np.where(eq_mask, 0.0, inf))
