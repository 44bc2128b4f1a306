"""Typed settings of the built-in estimators and guidance laws: what a world file may give in ``params`` (and an
estimator's ``road``).

Each model lists the fields of one component configuration that a world file sets, by the configuration's own names,
in its own units and with its own defaults (worlds/ imports nothing of autonomy/, so the names are declared here once
more; ``tests/simulator/test_settings_mirror.py`` fails if a name or a default here differs from the field it
feeds). The builders of :mod:`simulator.builders` pass the given values on field by field, renaming nothing. Bounds
here are the configurations' own checks, made at load so that a bad value is a world error before anything runs.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

__all__ = [
    "FastMpcSettings",
    "FormationSettings",
    "InfoPlanSettings",
    "NmpcSettings",
    "NmpcWeightsSettings",
    "NoSettings",
    "PdipSettings",
    "RoadConstraintSettings",
    "RoadSettings",
    "SearchSettings",
    "SetMembershipSettings",
    "TrackerSettings",
    "UnicycleSettings",
    "VectorFieldSettings",
    "WaypointSettings",
]

Pos = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNeg = Annotated[float, Field(ge=0, allow_inf_nan=False)]
Prob = Annotated[float, Field(gt=0, lt=1)]


class Settings(BaseModel):
    """Base of every settings model: unknown keys are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    def given(self) -> dict:
        """The fields the world file set (the others keep the component's own default), nested models as dicts."""
        return self.model_dump(exclude_unset=True)


class NoSettings(Settings):
    """A type without further settings: its ``params`` must be empty."""


class TrackerSettings(Settings):
    """``autonomy.estimation.tracker.TrackerConfig`` less ``filter`` and ``model`` (the estimator's ``type`` and
    ``model``), the ``imm_*`` fields (the estimator's ``imm`` block) and ``stack_scans`` (the fusion method's)."""

    q: Pos = 1.0
    singer_alpha: Pos = 0.1
    singer_sigma_a: Pos = 1.0
    gate_probability: Prob = 0.999
    max_target_speed: Pos = 30.0
    tentative_window_s: Pos = 3.0
    lost_after_s: Pos = 10.0
    max_missed_scans: int = Field(4, ge=1)
    confirm_fixes: Literal[2, 3] = 2
    max_target_accel: Pos = 4.0
    initial_speed_sigma: Pos | None = 15.0
    target_height: float = Field(0.0, allow_inf_nan=False)
    min_crossing_angle: float = Field(math.radians(10.0), gt=0, le=math.pi / 2)
    ekf_iterations: int = Field(1, ge=1, le=20)


class RoadConstraintSettings(Settings):
    """``autonomy.estimation.road.constraint.RoadConstraintParams``."""

    sigma_lateral: Pos | None = None
    sigma_keep: Pos = 0.5
    sigma_normal_speed: Pos = 1.0
    velocity_update: Literal["auto", "partial", "joint", "off"] = "auto"
    lateral_offset: float | None = None
    switch_gate: Pos | None = None
    follow_road_heading: bool = True


class RoadSettings(Settings):
    """``autonomy.estimation.road.config.RoadFilterConfig`` less ``variant`` (the estimator's ``type``)."""

    ecukf_stage2: Literal["pseudo", "project"] = "project"
    constraint: RoadConstraintSettings = Field(default_factory=RoadConstraintSettings)
    vertex_spacing: Pos | None = 10.0
    line_curvature: NonNeg = 1e-4
    spawn_distance: Pos = 30.0
    prune_threshold: Prob = 1e-6
    merge_threshold: float = Field(1.0, gt=0, le=1)
    switch_probability: Prob = 0.99
    max_hypotheses: int = Field(8, ge=1)
    off_road_probability: Prob = 0.999
    off_road_scans: int = Field(2, ge=1)
    attach_probability: Prob = 0.99
    attach_scans: int = Field(2, ge=1)
    direction_weighting: bool = True
    wrong_way_z: Pos | None = 3.0


class SetMembershipSettings(Settings):
    """``autonomy.estimation.setmem.estimator.SetMembershipConfig``'s numerical settings (its ``max_target_speed`` is
    the estimator's ``set_membership`` block's)."""

    quad_segs: int = Field(2, ge=1)
    simplify_tol: NonNeg = 0.2
    max_vertices: int = Field(600, ge=3)
    max_hole_area: NonNeg = 1.0
    containment_tol: NonNeg = 1e-6


class WaypointSettings(Settings):
    """``autonomy.guidance.waypoints.WaypointConfig`` less ``waypoints`` and ``speed`` (the guidance's)."""

    gain: Pos = 0.8
    acceptance_radius: Pos = 3.0
    loop: bool = False


class VectorFieldSettings(Settings):
    """``autonomy.guidance.vector_field.VectorFieldConfig`` less what the guidance section gives (``standoff_radius``
    ← ``standoff_m``, ``nominal_speed`` ← ``speed``, ``altitude``) and ``team_size`` (the world's)."""

    min_speed: NonNeg = 0.0
    max_speed: Pos = 20.0
    max_heading_rate: Pos = 0.6
    heading_gain: Pos = 1.0
    phase_gain: NonNeg = 0.5
    relative_speed_bounds: tuple[float, float] = (0.5, 1.5)
    phase_separation: float | None = Field(None, gt=0, le=2 * math.pi)
    direction: Literal[1, -1] = 1
    min_course_speed: NonNeg = 0.5
    feedforward_dt: Pos = 0.05


class UnicycleSettings(Settings):
    """``autonomy.guidance.unicycle.UnicycleParams``."""

    tau_v: Pos = 1.0 / 3.0
    tau_omega: Pos = 1.0 / 3.0


class NmpcWeightsSettings(Settings):
    """``autonomy.guidance.nmpc_config.NmpcWeights``."""

    p_r: NonNeg = 2e4
    p_d: NonNeg = 2e3
    q_r: NonNeg = 1e4
    q_d: NonNeg = 1e3
    r_v: NonNeg = 2.0
    r_omega: NonNeg = 2.0
    slack_l1: NonNeg = 1e5
    slack_l2: NonNeg = 1e5


class NmpcSettings(Settings):
    """``autonomy.guidance.nmpc_config.NmpcConfig`` less what the guidance section gives (``standoff_radius`` ←
    ``standoff_m``, ``nominal_speed`` ← ``speed``, ``altitude``), ``team_size`` (the world's) and ``fallback`` (the
    vector field derived from these settings)."""

    speed_deviation: Pos = 6.0
    min_speed: NonNeg = 0.0
    max_heading_rate: Pos = 0.5
    model: UnicycleSettings = Field(default_factory=UnicycleSettings)
    horizon: int = Field(20, ge=2)
    dt: Pos = 0.5
    substeps: int = Field(2, ge=1)
    weights: NmpcWeightsSettings = Field(default_factory=NmpcWeightsSettings)
    phase_cost: Literal["chord", "paper"] = "chord"
    phase_separation: float | None = Field(None, gt=0, le=2 * math.pi)
    direction: Literal[1, -1] = 1
    separation_distance: Pos = 20.0
    building_margin: NonNeg = 8.0
    building_vertical_clearance: NonNeg = 5.0
    max_buildings: int = Field(4, ge=0)
    min_altitude: float = 20.0
    max_altitude: float = 120.0
    solver: Literal["sqp", "fatrop", "ipopt", "rti"] = "sqp"
    hessian: Literal["gauss_newton", "constraint_curvature", "tiered"] = "tiered"
    convexify: Literal["eigen-clip", "eigen-reflect", "regularize"] = "eigen-clip"
    convexify_margin: NonNeg = 1e-6
    max_iter: int = Field(15, ge=1)
    gauss_newton_max_iter: int = Field(6, ge=1)
    cold_start_max_iter: int = Field(200, ge=1)
    fatrop_max_iter: int = Field(100, ge=1)
    fatrop_tol: Pos = 1e-6
    robust_retry: bool = True
    time_budget_s: Pos = 0.02
    enforce_time_budget: bool = False
    fallback_max_shift: int = Field(10, ge=0)
    restart_probe: bool = False
    restart_probe_interval_s: NonNeg = 2.0
    compiled: bool = True


class PdipSettings(Settings):
    """``autonomy.guidance.pdip.PdipOptions``."""

    max_iter: int = Field(30, ge=1)
    step_fraction: float = Field(0.99, gt=0, lt=1)
    regularization: NonNeg = 1e-8
    slack_floor: Pos = 1.0
    tol: Pos = 1e-9


class FastMpcSettings(Settings):
    """``autonomy.guidance.fast_mpc.FastMpcConfig`` less ``altitude`` (the guidance section's)."""

    dt: Pos = 0.5
    horizon: int = Field(10, ge=1)
    v_min: NonNeg = 0.0
    v_max: Pos = 18.0
    omega_max: Pos = 1.0
    w_x: NonNeg = 0.5
    w_y: NonNeg = 0.5
    w_v: NonNeg = 5.0
    w_o: NonNeg = 180.0
    theta_reg: NonNeg = 1e-4
    separation_distance: NonNeg = 10.0
    separation_margin: NonNeg = 4.0
    separation_mode: Literal["buffered", "paper"] = "buffered"
    altitude_tolerance: NonNeg = 5.0
    slack_l1: NonNeg = 1e4
    slack_l2: NonNeg = 100.0
    linearization_min_speed: NonNeg = 2.0
    pdip: PdipSettings = Field(default_factory=PdipSettings)


class FormationSettings(NoSettings):
    """Every field of ``FormationConfig`` comes from the guidance's ``formation`` block, speed and altitude."""


class SearchSettings(NoSettings):
    """Every field of ``SearchConfig`` comes from the guidance's ``search`` block, speed and altitude."""


class InfoPlanSettings(Settings):
    """``autonomy.guidance.infoplan.config.InfoPlannerConfig``'s fields that the guidance's ``infoplan`` block,
    speed, altitude, the UAV's radar and the radio do not give."""

    prior_position_std: Pos = 5.0
    prior_velocity_std: Pos = 2.0
    max_joint_candidates: int = Field(200_000, ge=1)
    separation_penalty: NonNeg = 1e6
