"""Kinematic unicycle with first-order speed and heading-rate lags: the prediction model of the standoff guidance
and the closed-loop plant of its tests and benchmarks.

State layout ``UNICYCLE = ("x", "y", "psi", "v", "omega")`` (m, m, rad, m/s, rad/s); input (u_v, u_omega) (m/s, rad/s)::

    ẋ = v cos ψ,   ẏ = v sin ψ,   ψ̇ = ω,   v̇ = (u_v − v) / τ_v,   ω̇ = (u_ω − ω) / τ_ω

(Oh, Kim, Tsourdos 2015, eq. 4). With τ → 0 the lags vanish and (v, ω) follow the inputs at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["UNICYCLE", "UnicycleParams", "unicycle_rhs", "unicycle_step"]

UNICYCLE = ("x", "y", "psi", "v", "omega")


@dataclass(frozen=True, kw_only=True)
class UnicycleParams:
    """Lags of the unicycle model.

    Attributes
    ----------
    tau_v : float
        Speed response time constant (s), >= 0 (0: speed follows the command at once).
    tau_omega : float
        Heading-rate response time constant (s), >= 0.
    """

    tau_v: float = 1.0 / 3.0
    tau_omega: float = 1.0 / 3.0

    def __post_init__(self) -> None:
        for name in ("tau_v", "tau_omega"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"UnicycleParams.{name} must be >= 0 s, got {v}")


def unicycle_rhs(x: np.ndarray, u: np.ndarray, params: UnicycleParams) -> np.ndarray:
    """Time derivative of the state ``x`` (5,) under input ``u`` (2,); a zero lag gives v̇ = 0 or ω̇ = 0."""
    _, _, psi, v, om = x
    dv = 0.0 if params.tau_v == 0 else (u[0] - v) / params.tau_v
    dom = 0.0 if params.tau_omega == 0 else (u[1] - om) / params.tau_omega
    return np.array([v * np.cos(psi), v * np.sin(psi), om, dv, dom])


def unicycle_step(x: np.ndarray, u: np.ndarray, dt: float, params: UnicycleParams, substeps: int = 4) -> np.ndarray:
    """Integrate the unicycle over ``dt`` (s) with ``substeps`` classical RK4 steps, input held constant.

    With a zero lag the corresponding rate is set to its command before integrating.
    """
    x = np.array(x, dtype=float)
    u = np.asarray(u, dtype=float)
    if params.tau_v == 0:
        x[3] = u[0]
    if params.tau_omega == 0:
        x[4] = u[1]
    h = dt / substeps
    for _ in range(substeps):
        k1 = unicycle_rhs(x, u, params)
        k2 = unicycle_rhs(x + 0.5 * h * k1, u, params)
        k3 = unicycle_rhs(x + 0.5 * h * k2, u, params)
        k4 = unicycle_rhs(x + h * k3, u, params)
        x = x + (h / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)
    return x
