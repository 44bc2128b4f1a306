"""Configuration of the NMPC standoff-tracking guidance (Oh, Kim, Tsourdos 2015, Table I, generalised).

Defaults are at quadrotor scale (120 m standoff, 12 m/s nominal speed, 0.5 s step, 20-step horizon); the paper's
fixed-wing numbers are r_d = 500 m, v_0 = 40 m/s, v_max = 10 m/s, ω_max = 0.2 rad/s, N = 4, T = 0.5 s,
(p_r, p_d, q_r, q_d, r_v, r_ω) = (2e5, 1e6, p_r/N, p_d/N, 1e2, 5e1).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from autonomy.guidance.unicycle import UnicycleParams
from autonomy.guidance.vector_field import VectorFieldConfig

__all__ = ["NmpcConfig", "NmpcWeights"]


@dataclass(frozen=True, kw_only=True)
class NmpcWeights:
    """Cost weights (all dimensionless, >= 0).

    Attributes
    ----------
    p_r, p_d : float
        Terminal standoff and phase weights.
    q_r, q_d : float
        Stage standoff and phase weights.
    r_v, r_omega : float
        Stage weights on the normalised speed and heading-rate deviations from the nominal orbit.
    slack_l1, slack_l2 : float
        Linear and quadratic weights of the keep-out / separation slack (exact penalty: large ``slack_l1``).
    """

    p_r: float = 2e4
    p_d: float = 2e3
    q_r: float = 1e4
    q_d: float = 1e3
    r_v: float = 2.0
    r_omega: float = 2.0
    slack_l1: float = 1e5
    slack_l2: float = 1e5

    def __post_init__(self) -> None:
        for name, v in self.__dict__.items():
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"NmpcWeights.{name} must be finite and >= 0, got {v}")


@dataclass(frozen=True, kw_only=True)
class NmpcConfig:
    """NMPC standoff tracking.

    Attributes
    ----------
    standoff_radius : float
        Desired horizontal distance r_d to the target (m), > 0.
    nominal_speed : float
        Nominal ground speed v_0 (m/s), > 0.
    speed_deviation : float
        Bound v_max of |u_v − v_0| (m/s), > 0.
    min_speed : float
        Lower bound of the speed command (m/s), >= 0 (a quadrotor may hover; the paper's aircraft may not).
    max_heading_rate : float
        Bound ω_max of |u_ω| (rad/s), > 0.
    model : UnicycleParams
        Speed and heading-rate lags of the prediction model.
    horizon : int
        Number of steps N, >= 2.
    dt : float
        Step T (s), > 0.
    substeps : int
        RK4 substeps per step in the prediction model, >= 1.
    weights : NmpcWeights
        Cost weights.
    phase_cost : {"chord", "paper"}
        "chord": q_d |u − R(φ_ij) u_j|² with unit vectors u = r/|r| (quadratic in the phase error, any spacing);
        "paper": q_d d̃², d̃ = (rᵀ r_j + |r||r_j|)/r_d² (paper eq. 28, 180° spacing only; quartic in the error).
    team_size : int
        UAVs on the orbit, >= 1.
    phase_separation : float | None
        Phase spacing between consecutive slots (rad); ``None`` means 2π / team_size.
    direction : int
        +1 counter-clockwise, −1 clockwise orbit (sets the nominal heading rate d·v_0/r_d).
    separation_distance : float
        Minimum horizontal distance between UAVs (m), > 0.
    building_margin : float
        Keep-out margin around building footprints (m), >= 0.
    building_vertical_clearance : float
        Buildings whose top is below altitude − this are flown over (m), >= 0.
    max_buildings : int
        Keep-out slots of the solver (nearest buildings first), >= 0.
    altitude, min_altitude, max_altitude : float
        Planning altitude and the band it is clamped to (m); the plan is 2-D at the clamped altitude.
    solver : {"sqp", "fatrop", "ipopt", "rti"}
        "sqp": CasADi sqpmethod + qrqp with the ``hessian`` below (see :mod:`autonomy.guidance.nmpc_tiers`);
        "fatrop": the structure-exploiting interior point Fatrop with the exact Hessian on the stage-wise problem
        (:mod:`autonomy.guidance.nmpc_stage`); "ipopt": interior point, warm-started; "rti": one SQP iteration per
        call (real-time iteration).
    hessian : {"tiered", "gauss_newton", "constraint_curvature"}
        Hessian of the fast solver's QPs: "gauss_newton" σ J_Rᵀ J_R of the least-squares cost only;
        "constraint_curvature" adds the exact curvature Σ λ_j ∇²g_j of the dynamics and constraints, made positive
        definite block by block (``convexify``); "tiered" (default) runs the Gauss–Newton SQP with the cap
        ``gauss_newton_max_iter`` and, when it does not converge, the constraint-curvature SQP from its iterate (the
        tiers are :mod:`autonomy.guidance.nmpc_tiers`; their measured effect is in ``docs/nmpc.md``).
    convexify : {"eigen-clip", "eigen-reflect", "regularize"}
        How sqpmethod makes the constraint-curvature Hessian positive definite (CasADi ``convexify_strategy``):
        clip or reflect the negative eigenvalues of each diagonal block of the Hessian (its strongly connected
        components: 5 × 5 at most here), or add one multiple of the identity to the whole matrix (Gershgorin bound).
    convexify_margin : float
        Smallest eigenvalue (or diagonal margin) the convexification leaves, >= 0 (CasADi ``convexify_margin``).
    max_iter : int
        Iteration cap of the solver (the deterministic time-out; of the constraint-curvature tier when tiered), >= 1.
    gauss_newton_max_iter : int
        Iteration cap of the Gauss–Newton tier of ``hessian="tiered"``, >= 1; a capped iterate is not used but handed
        to the next tier.
    cold_start_max_iter : int
        Iteration cap of the exact-Hessian IPOPT used for cold starts (no previous plan), >= 1.
    fatrop_max_iter : int
        Iteration cap of Fatrop (``solver="fatrop"``), >= 1; a capped solve fails (and is retried, ``robust_retry``).
    fatrop_tol : float
        Convergence tolerance of Fatrop (its ``tol``), > 0.
    robust_retry : bool
        When the warm-started fast solver fails, solve once more from the same guess with the exact-Hessian IPOPT of
        cold starts before falling back (slower, counted in ``retries``). Measured in ``road_standoff`` (seed 2,
        40 s): with the Gauss–Newton Hessian the SQP hit its iteration cap on 37 of 158 solves and IPOPT solved all 37
        (median 24 ms); with the constraint-curvature Hessian 5 retries remain.
    time_budget_s : float
        Wall-time budget of one solve (s); overruns are counted, and treated as failures if ``enforce_time_budget``.
    enforce_time_budget : bool
        Treat overruns as failures (makes runs depend on machine speed; off by default).
    fallback_max_shift : int
        Oldest previous plan (in steps) the shifted-plan fallback may use, >= 0.
    fallback : VectorFieldConfig | None
        Vector-field fallback; ``None`` derives one from this configuration.
    restart_probe : bool
        When a warm-started plan rides the speed floor on half the horizon or more, solve again from the vector-field
        guess and keep the cheaper plan (multi-start against the slow looping local minimum after a target stops;
        counted in ``stats.restart_probes`` / ``stats.restarts``; measured in ``docs/nmpc.md``).
    restart_probe_interval_s : float
        After a probe whose plan was not kept, the next probe waits this long (s), >= 0.
    compiled : bool
        Compile the fast solver's functions to C (cached on disk, :mod:`autonomy.guidance.codegen`); the solutions
        are the same as uncompiled, each solve ≈ 20 % faster. The first construction of a problem on a machine
        pays the compiler (a few seconds). Without a C compiler the solver runs uncompiled.
    """

    standoff_radius: float = 120.0
    nominal_speed: float = 12.0
    speed_deviation: float = 6.0
    min_speed: float = 0.0
    max_heading_rate: float = 0.5
    model: UnicycleParams = UnicycleParams()
    horizon: int = 20
    dt: float = 0.5
    substeps: int = 2
    weights: NmpcWeights = NmpcWeights()
    phase_cost: Literal["chord", "paper"] = "chord"
    team_size: int = 2
    phase_separation: float | None = None
    direction: int = 1
    separation_distance: float = 20.0
    building_margin: float = 8.0
    building_vertical_clearance: float = 5.0
    max_buildings: int = 4
    altitude: float = 60.0
    min_altitude: float = 20.0
    max_altitude: float = 120.0
    solver: Literal["sqp", "fatrop", "ipopt", "rti"] = "sqp"
    hessian: Literal["gauss_newton", "constraint_curvature", "tiered"] = "tiered"
    convexify: Literal["eigen-clip", "eigen-reflect", "regularize"] = "eigen-clip"
    convexify_margin: float = 1e-6
    max_iter: int = 15
    gauss_newton_max_iter: int = 6
    cold_start_max_iter: int = 200
    fatrop_max_iter: int = 100
    fatrop_tol: float = 1e-6
    robust_retry: bool = True
    time_budget_s: float = 0.02
    enforce_time_budget: bool = False
    fallback_max_shift: int = 10
    fallback: VectorFieldConfig | None = None
    restart_probe: bool = False
    restart_probe_interval_s: float = 2.0
    compiled: bool = True

    def __post_init__(self) -> None:
        for name in ("standoff_radius", "nominal_speed", "speed_deviation", "max_heading_rate", "dt",
                     "separation_distance", "time_budget_s", "fatrop_tol"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"NmpcConfig.{name} must be > 0, got {v}")
        for name in ("min_speed", "building_margin", "building_vertical_clearance", "convexify_margin",
                     "restart_probe_interval_s"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"NmpcConfig.{name} must be >= 0, got {v}")
        if self.min_speed >= self.nominal_speed + self.speed_deviation:
            raise ValueError(f"NmpcConfig.min_speed must be < nominal_speed + speed_deviation, got {self.min_speed}")
        for name, lo in (("horizon", 2), ("substeps", 1), ("team_size", 1), ("max_buildings", 0), ("max_iter", 1),
                         ("gauss_newton_max_iter", 1),
                         ("cold_start_max_iter", 1), ("fatrop_max_iter", 1), ("fallback_max_shift", 0)):
            v = getattr(self, name)
            if int(v) != v or v < lo:
                raise ValueError(f"NmpcConfig.{name} must be an integer >= {lo}, got {v}")
        if self.phase_cost not in ("chord", "paper"):
            raise ValueError(f"NmpcConfig.phase_cost must be 'chord' or 'paper', got {self.phase_cost!r}")
        if self.phase_cost == "paper" and not np.isclose(self.separation, np.pi):
            raise ValueError(f"NmpcConfig.phase_cost 'paper' needs a phase separation of π, got {self.separation}")
        if self.phase_separation is not None and not (0 < self.phase_separation <= 2 * np.pi):
            raise ValueError(f"NmpcConfig.phase_separation must be in (0, 2π] rad, got {self.phase_separation}")
        if self.direction not in (1, -1):
            raise ValueError(f"NmpcConfig.direction must be +1 or -1, got {self.direction}")
        if not (self.min_altitude <= self.max_altitude):
            raise ValueError(f"NmpcConfig.min_altitude must be <= max_altitude, "
                             f"got ({self.min_altitude}, {self.max_altitude})")
        if self.hessian not in ("gauss_newton", "constraint_curvature", "tiered"):
            raise ValueError(f"NmpcConfig.hessian must be 'gauss_newton', 'constraint_curvature' or 'tiered', "
                             f"got {self.hessian!r}")
        if self.convexify not in ("eigen-clip", "eigen-reflect", "regularize"):
            raise ValueError(f"NmpcConfig.convexify must be 'eigen-clip', 'eigen-reflect' or 'regularize', "
                             f"got {self.convexify!r}")
        if self.solver not in ("sqp", "fatrop", "ipopt", "rti"):
            raise ValueError(f"NmpcConfig.solver must be 'sqp', 'fatrop', 'ipopt' or 'rti', got {self.solver!r}")

    @property
    def separation(self) -> float:
        """Phase spacing between consecutive slots (rad)."""
        return 2 * np.pi / self.team_size if self.phase_separation is None else float(self.phase_separation)

    @property
    def planning_altitude(self) -> float:
        """``altitude`` clamped to [min_altitude, max_altitude] (m)."""
        return float(np.clip(self.altitude, self.min_altitude, self.max_altitude))

    @property
    def speed_bounds(self) -> tuple[float, float]:
        """(lower, upper) bound of the speed command (m/s): max(min_speed, v_0 − v_max), v_0 + v_max."""
        return max(self.min_speed, self.nominal_speed - self.speed_deviation), self.nominal_speed + self.speed_deviation

    def fallback_config(self) -> VectorFieldConfig:
        """The vector-field fallback: ``fallback`` or one with the same orbit, team and bounds."""
        if self.fallback is not None:
            return self.fallback
        lo, hi = self.speed_bounds
        return VectorFieldConfig(standoff_radius=self.standoff_radius, nominal_speed=self.nominal_speed, min_speed=lo,
                                 max_speed=hi, max_heading_rate=self.max_heading_rate, team_size=self.team_size,
                                 phase_separation=self.phase_separation, direction=self.direction,
                                 altitude=self.planning_altitude)
