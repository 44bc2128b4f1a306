"""Configuration of the communication-aware information planner (defaults: Liu, Fu & Gao 2018, Table 1 and §5.1)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from autonomy.sensing.channel import ChannelConfig

__all__ = ["InfoPlannerConfig"]


@dataclass(frozen=True, kw_only=True)
class InfoPlannerConfig:
    """Receding-horizon heading planner maximising the information expected to reach the base station.

    Attributes
    ----------
    base_p_W : tuple[float, float]
        Horizontal position of the base station B (m).
    dt : float
        Planning step T_s (s), > 0; each step holds one heading rate.
    horizon : int
        Steps T_p in the horizon, >= 1.
    speed : float
        Constant ground speed of the UAVs (m/s), > 0.
    max_heading_rate : float
        ω_max (rad/s), > 0.
    n_heading_rates : int
        Size of the heading-rate grid, uniform over [−ω_max, ω_max], odd >= 3 (so that 0 is in the set).
    sigma_range : float
        Radar range noise δr (m), > 0.
    sigma_bearing : float
        Radar azimuth noise δθ (rad), > 0.
    target_accel_std : float
        Target process noise δx = δy (m/s²), > 0.
    prior_position_std : float
        Target position standard deviation (m) assumed when the estimate carries no covariance, > 0.
    prior_velocity_std : float
        Target velocity standard deviation (m/s) assumed when the estimate carries no covariance, > 0.
    channel : ChannelConfig
        Radio link model (only its fading and range limit are used).
    d_safe : float
        Minimum planned separation between UAVs (m), >= 0; violating candidates are ranked below all others.
    objective : {"team", "own"}
        ``"own"``: each UAV maximises its own delivered information (the paper's eq. 42). ``"team"``: each UAV
        maximises the team's, so a relay is credited with the information its position lets the others deliver.
    routing : {"mst", "chain", "none"}
        Route model of the objective: the minimum spanning tree (the paper), the fixed relay chain A_i → A_{i−1} → … → B
        (baseline of §5.2), or ``"none"``: β ≡ 1, the "without communication optimisation" baseline of §5.1.
    criterion : {"logdet", "trace"}
        Information measure summed over the horizon: ``"trace"`` = Σ_i β_i tr(I_i) (A-optimality on the information,
        the paper's eq. 41) or ``"logdet"`` = log det of the predicted base-station information with the prior
        (D-optimality; rewards cross-range information, which the trace nearly ignores at the paper's noise values).
    search : {"sequential", "joint"}
        ``"sequential"``: UAVs optimise one after another in the planning hierarchy (hop count, then index), each
        over all its heading sequences with the others' plans fixed, repeated ``sweeps`` times (coordinate ascent).
        ``"joint"``: exhaustive search over all UAVs' sequences together (small problems only).
    sweeps : int
        Passes of the sequential search, >= 1 (1 = the paper's single pass; stops early when no plan changes).
    max_joint_candidates : int
        Largest joint search allowed (number of team plans), >= 1.
    separation_penalty : float
        Objective units subtracted per metre of separation violation (> 0); large, so feasibility comes first.
    altitude : float
        Altitude commanded (m).
    """

    base_p_W: tuple[float, float] = (-500.0, -800.0)
    dt: float = 1.0
    horizon: int = 3
    speed: float = 50.0
    max_heading_rate: float = float(np.deg2rad(30.0))
    n_heading_rates: int = 7
    sigma_range: float = 2.0
    sigma_bearing: float = 0.05
    target_accel_std: float = 0.1
    prior_position_std: float = 5.0
    prior_velocity_std: float = 2.0
    channel: ChannelConfig = field(default_factory=lambda: ChannelConfig(block_by_buildings=False))
    d_safe: float = 100.0
    objective: Literal["team", "own"] = "team"
    routing: Literal["mst", "chain", "none"] = "mst"
    criterion: Literal["logdet", "trace"] = "logdet"
    search: Literal["sequential", "joint"] = "sequential"
    sweeps: int = 2
    max_joint_candidates: int = 200_000
    separation_penalty: float = 1e6
    altitude: float = 60.0

    def __post_init__(self) -> None:
        base = tuple(float(v) for v in self.base_p_W)
        if len(base) != 2 or not all(np.isfinite(base)):
            raise ValueError(f"InfoPlannerConfig.base_p_W must be two finite numbers (m), got {self.base_p_W}")
        object.__setattr__(self, "base_p_W", base)
        for name in ("dt", "speed", "max_heading_rate", "sigma_range", "sigma_bearing", "target_accel_std",
                     "prior_position_std", "prior_velocity_std", "separation_penalty"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"InfoPlannerConfig.{name} must be > 0, got {v}")
        if not (np.isfinite(self.d_safe) and self.d_safe >= 0):
            raise ValueError(f"InfoPlannerConfig.d_safe must be >= 0 m, got {self.d_safe}")
        for name in ("horizon", "sweeps", "max_joint_candidates"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ValueError(f"InfoPlannerConfig.{name} must be an integer >= 1, got {v}")
        k = self.n_heading_rates
        if int(k) != k or k < 3 or k % 2 == 0:
            raise ValueError(f"InfoPlannerConfig.n_heading_rates must be an odd integer >= 3, got {k}")
        choices = {"objective": ("team", "own"), "routing": ("mst", "chain", "none"),
                   "criterion": ("logdet", "trace"), "search": ("sequential", "joint")}
        for name, allowed in choices.items():
            if getattr(self, name) not in allowed:
                raise ValueError(f"InfoPlannerConfig.{name} must be one of {allowed}, got {getattr(self, name)!r}")

    @property
    def heading_rates(self) -> np.ndarray:
        """(K,) the heading-rate grid (rad/s)."""
        return np.linspace(-self.max_heading_rate, self.max_heading_rate, self.n_heading_rates)

    def default_prior_information(self) -> np.ndarray:
        """Information matrix (4 × 4, layout ``TARGET_CV``) of the default prior."""
        return np.diag([self.prior_position_std**-2] * 2 + [self.prior_velocity_std**-2] * 2)
