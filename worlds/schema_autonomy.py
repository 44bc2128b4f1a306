"""The autonomy section of a world file: a UAV's estimator, fusion method and guidance law.

Each of the three is a variant picked by its tag (``estimator.type``, ``guidance.type``, ``fusion.method``) from the
open registries of :mod:`worlds.variants`; the variant's typed settings (:mod:`worlds.schema_settings`) check the
section's ``params`` (and an estimator's ``road``) at load, so that a bad key or value is a world error naming its path
before anything runs. Settings that a world file gives in degrees (``*_deg``, ``*_deg_s``) feed the component field of
the same name without the suffix, in radians; every other setting feeds the field of its own name.
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import BaseModel, Field, ValidationInfo, field_validator, model_validator

from worlds.schema_base import NonNegFloat, PositiveFloat, Strict, Vec3
from worlds.variants import ESTIMATORS, FUSIONS, GUIDANCES, FusionVariant, check_tag, settings_models, split_params

__all__ = [
    "AutonomySpec",
    "EstimatorSpec",
    "FormationSpec",
    "FusionSpec",
    "GuidanceSpec",
    "ImmSpec",
    "InfoPlanSpec",
    "JacobiGainsSpec",
    "SearchSpec",
    "SetMembershipSpec",
]

SWITCH_RULE = ("keys that the chosen type does not know but another type does are dropped with a note, so that "
               "switching the type needs no reset of params; keys no type knows are errors")


def _check_plugin(kind: str, plugin: str | None) -> None:
    if (kind == "plugin") != (plugin is not None):
        raise ValueError("type 'plugin' and the 'plugin' import path go together")
    if plugin is not None and ":" not in plugin:
        raise ValueError(f"plugin must look like 'package.module:Class', got {plugin!r}")


def _checked(value: dict[str, Any], info: ValidationInfo, table: dict[str, Any], attribute: str,
             family: str) -> dict[str, Any]:
    """``value`` (a section's ``params`` or ``road``) validated against the chosen type's settings model, less the
    settings of other types (dropped with a note); unchanged where the type takes unchecked settings (a plugin) or
    none of this kind (checked by ``worlds.checks``), or where the type itself is bad (reported on its own)."""
    tag = info.data.get("type")
    model = getattr(table.get(tag), attribute, None) if tag is not None else None
    if model is None:
        return value
    kept = split_params(value, model, settings_models(table, attribute), f"{family} type {tag!r}")
    model.model_validate(kept)
    return kept


def _typed(model: type[BaseModel] | None, value: dict[str, Any]) -> BaseModel | None:
    return None if model is None else model.model_validate(value)


class ImmSpec(Strict):
    """The IMM's modes: paper 003's (``cv_ct``, ``autonomy.estimation.imm.cv_ct_imm``: EKFs on CV and on coordinated
    turns at ±ω; the CV mode's white-acceleration density is the tracker's ``params.q``; model ``cv``), or a car that
    moves and stops (``move_stop``, ``autonomy.estimation.imm.move_stop_imm``: EKFs on the estimator's ``model`` and
    on a stopped car, switching with the mean times below). Each setting ``x`` feeds the tracker's ``imm_x``
    (``TrackerConfig``; ``turn_rate_deg_s`` in rad/s)."""

    modes: Literal["cv_ct", "move_stop"] = Field("cv_ct", description="the mode set")
    turn_rate_deg_s: PositiveFloat = Field(math.degrees(0.3), description="cv_ct: ω of the two turn modes, deg/s "
                                                                          "(0.3 rad/s)")
    q_turn: PositiveFloat = Field(0.05, description="cv_ct: white-acceleration density of the turn modes, m^2/s^3")
    p_stay: float = Field(0.95, gt=0, lt=1, description="cv_ct: diagonal of the mode-transition matrix")
    mean_moving_s: PositiveFloat = Field(30.0, description="move_stop: mean time a car drives before it stops, s")
    mean_stopped_s: PositiveFloat = Field(10.0, description="move_stop: mean time a stopped car stays stopped, s")
    stopped_q: NonNegFloat = Field(0.01, description="move_stop: position random-walk density of a stopped car, "
                                                    "m^2/s")


class SetMembershipSpec(Strict):
    """Paper 004's set-membership estimator (``autonomy.estimation.setmem``): the search area it keeps its sets in
    (the area less the buildings' footprints is ``X_s``) and the targets' speed bound behind its guarantee; the
    estimator's numerical settings (``quad_segs``, ``simplify_tol``, ``max_vertices``, ``max_hole_area``) go in the
    estimator's ``params``."""

    area: tuple[float, float, float, float] = Field(description="search area x_min, y_min, x_max, y_max, m")
    max_target_speed: PositiveFloat = Field(5.0 / 3.6, description="bound on every target's ground speed, m/s "
                                                                   "(the paper's 5 km/h)")

    @model_validator(mode="after")
    def _box(self) -> SetMembershipSpec:
        x0, y0, x1, y1 = self.area
        if not (x1 > x0 and y1 > y0):
            raise ValueError(f"area must be [x_min, y_min, x_max, y_max] with max > min, got {list(self.area)}")
        return self


class TrackingSpec(Strict):
    """How many cars the UAV's tracker holds, and how it keeps the target among them
    (``autonomy.estimation.tracking.multi.MultiTrackerConfig``, ``...tracking.identity.IdentityConfig``)."""

    mode: Literal["auto", "single", "multi"] = Field(
        "auto", description="single: one track, the target's (the papers' trackers); multi: a track per car in view "
        "and a belief of which is the target; auto: multi when the world has more than one ground vehicle that is "
        "not a decoy, single otherwise")
    associator: Literal["gnn", "jpda"] = Field("gnn", description="global nearest neighbour or JPDA")
    confirm_m: int = Field(3, ge=2, le=50, description="M of the M-of-N confirmation (the two starting fixes count)")
    confirm_n: int = Field(4, ge=2, le=50, description="N of the M-of-N confirmation, >= confirm_m")
    detection_probability: float = Field(0.9, gt=0, le=1, description="jpda: probability of detecting a car in view")
    clutter_density: float = Field(1e-6, gt=0, le=1e3, description="jpda: false alarms per unit of measurement "
                                                                   "space (e.g. per m*rad for a range-azimuth radar)")
    merge_distance_m: float = Field(4.0, gt=0, le=100, description="two confirmed tracks this close (and "
                                                                   "merge_speed_mps) are one car, m")
    merge_speed_mps: float = Field(2.0, gt=0, le=50, description="velocity difference under which close tracks "
                                                                 "merge, m/s")
    max_tracks: int = Field(500, ge=1, le=100000, description="most live tracks")
    class_aided: bool = Field(True, description="a detection's class readings (colour, body type, length class) "
                              "weigh in its association with the tracks, against each track's readings: where cars "
                              "pass within the sensors' resolution a track keeps the car that looks like the one it "
                              "has been reading; false: position alone")
    camera_detection_probability: float = Field(
        0.0, ge=0, lt=1, description="negative information from cameras: the probability that a camera detects a car "
        "it has in view (in its image, near enough, not hidden behind a building by its depth image); each frame that "
        "shows no car where a confirmed track has one in view makes the track less likely to be there, and a track "
        "the camera keeps looking at without seeing (the likelihood of its misses below 0.02) is dropped, so a target "
        "track that lost its car is given up and the target searched for; 0: off")
    min_target_probability: float = Field(0.2, gt=0, le=1, description="the most probable track is taken for the "
                                          "target when its probability reaches this (following the best candidate "
                                          "lets a pointed camera confirm or reject it)")
    search_speed: float = Field(8.0, gt=0, le=100, description="growth of the region a lost (or cued) target is "
                                                               "searched in, m/s per axis")
    swap_probability: float = Field(0.02, ge=0, lt=1, description="probability that the car under a track is another "
                                    "one since the track's last class reading (a swap where cars pass close): old "
                                    "readings are discounted so a swapped track's class evidence turns in a few "
                                    "readings; 0 keeps every reading")
    search_detection_probability: float | Literal["auto"] = Field(
        "auto", description="probability that one radar scan detects a target in the region it is searched in "
        "(detection probability times the chance it is in line of sight): each scan that starts no track there makes "
        "'the target is in no track' less likely by this factor; 0 never; auto: 0.3 when every radar of the UAV sees "
        "stopped cars (min_detectable_velocity 0) all around (no fov), else 0 (a stopped target in the Doppler notch "
        "or outside a sector is unseen however often the radar looks)")

    @field_validator("search_detection_probability")
    @classmethod
    def _search_q(cls, value: float | str) -> float | str:
        if value != "auto" and not 0 <= value < 1:
            raise ValueError(f"a probability in [0, 1) or auto, got {value!r}")
        return value

    @model_validator(mode="after")
    def _m_of_n(self) -> TrackingSpec:
        if self.confirm_m > self.confirm_n:
            raise ValueError(f"confirm_m <= confirm_n ({self.confirm_n}), got confirm_m {self.confirm_m}")
        return self


class EstimatorSpec(Strict):
    """The UAV's target estimator: a single-target tracker with an ``ekf``/``ukf``/``ckf``/``scif`` filter or an ``imm``
    (paper 003's CV + CT ±ω EKFs on model ``cv``, or move–stop EKFs; the ``imm`` block), a road-constrained tracker
    (paper 002: ``maekf`` pseudo-measurement EKF or ``ecukf`` two-stage constrained UKF on the world's road map, with
    junction hypotheses and an unconstrained fallback off the map), paper 004's ``set_membership`` estimator (sets
    that hold every target, from a bounded-error ``box`` sensor; settings in ``set_membership``), or a user plugin."""

    type: str = Field("ekf", description="the estimator type: a tag of worlds.variants.ESTIMATORS")
    model: Literal["cv", "singer"] = "cv"
    plugin: str | None = Field(None, description="'package.module:Class' of a user estimator (type: plugin)")
    params: dict[str, Any] = Field(default_factory=dict, description=(
        "the type's settings, checked at load: TrackerConfig fields (worlds.schema_settings.TrackerSettings) for the "
        "trackers, SetMembershipConfig's numerical ones for set_membership, keyword arguments of a plugin class "
        "(unchecked); " + SWITCH_RULE))
    road: dict[str, Any] = Field(default_factory=dict, description="maekf/ecukf: RoadFilterConfig fields "
                                                                   "(worlds.schema_settings.RoadSettings)")
    imm: ImmSpec | None = Field(None, description="imm: the mode set's settings (None: the defaults)")
    set_membership: SetMembershipSpec | None = Field(None, description="set_membership: the search area and the "
                                                                       "targets' speed bound")
    tracking: TrackingSpec = Field(default_factory=TrackingSpec, description="single- or multi-target tracking "
                                   "(the trackers and plugins; set_membership holds every target as sets anyway)")

    @field_validator("type")
    @classmethod
    def _known(cls, value: str) -> str:
        return check_tag(ESTIMATORS, value)

    @field_validator("params")
    @classmethod
    def _params(cls, value: dict[str, Any], info: ValidationInfo) -> dict[str, Any]:
        return _checked(value, info, ESTIMATORS, "settings", "estimator")

    @field_validator("road")
    @classmethod
    def _road(cls, value: dict[str, Any], info: ValidationInfo) -> dict[str, Any]:
        return _checked(value, info, ESTIMATORS, "road", "estimator")

    @model_validator(mode="after")
    def _plugin(self) -> EstimatorSpec:
        _check_plugin(self.type, self.plugin)
        return self

    @property
    def settings(self) -> BaseModel | None:
        """The typed ``params`` of this type (None for a plugin)."""
        return _typed(ESTIMATORS[self.type].settings, self.params)

    @property
    def road_settings(self) -> BaseModel | None:
        """The typed ``road`` settings of a road-constrained type (None for the others)."""
        return _typed(ESTIMATORS[self.type].road, self.road)


class JacobiGainsSpec(Strict):
    """PD gains of the formation law in Jacobi coordinates (``autonomy.guidance.formation.jacobi.JacobiGains``)."""

    kp_shape: PositiveFloat = Field(0.25, description="shape stiffness, 1/s^2")
    kd_shape: PositiveFloat = Field(1.0, description="shape damping, 1/s")
    kp_center: PositiveFloat = Field(0.25, description="centroid stiffness, 1/s^2")
    kd_center: PositiveFloat = Field(1.0, description="centroid damping, 1/s")


class FormationSpec(Strict):
    """Paper 003's FIM-optimal formation (``autonomy.guidance.formation.guidance.FormationConfig``); the team is every
    UAV of the world (agent i = uavs[i]), the speed limit is the guidance ``speed`` and the altitude its ``altitude``;
    the guidance step is the agent's period."""

    sigma_bearing_deg: PositiveFloat | None = Field(
        None, description="bearing noise σ behind det F, deg (None: the UAV's bearing sensor's sigma_azimuth_deg)")
    ranges: list[PositiveFloat] | None = Field(None, description="desired range of each UAV to the target, m (None: "
                                                                 "each keeps its current range, as Algorithm 1)")
    gains: JacobiGainsSpec = Field(default_factory=JacobiGainsSpec)
    backward_weight: NonNegFloat = Field(10.0, description="penalty on moves against the target's travel")
    n_rotations: int = Field(72, ge=4, description="coarse grid of the free rotation search")
    altitude_gain: NonNegFloat = Field(1.0, description="k_z of the altitude hold, 1/s")
    geometry: Literal["optimal", "trail"] = Field("optimal", description="Algorithm 1, or the trailing-fan baseline")
    trail_fan_deg: float = Field(15.0, gt=0, le=90, description="half-angle of the trailing fan, deg")


class SearchSpec(Strict):
    """Paper 004's sequential one-step search MPC (``autonomy.guidance.search.planner.SearchConfig``): constant speed
    and altitude (the guidance ``speed`` and ``altitude``), one heading change per agent step (the step ``T`` is the
    agent's period), chosen on a grid to shrink the predicted sets; the search area and the targets' speed bound are
    the UAV's ``set_membership`` estimator's."""

    max_turn_deg: float = Field(45.0, gt=0, le=180, description="bound on the heading change per step, deg")
    n_controls: int = Field(7, ge=3, description="grid of heading changes, odd")
    horizon: int = Field(2, ge=1, description="steps the held heading change is rolled out over")
    alpha_m: NonNegFloat = Field(1.3, description="weight of the undetected set's area")
    alpha_d: NonNegFloat = Field(4.5, description="weight of the pull towards the nearest large set")
    alpha_s: NonNegFloat = Field(3500.0, description="weight of the obstacle risk")
    alpha_s1: float = Field(10.0, description="centre of the obstacle-risk transition, m")
    alpha_s2: PositiveFloat = Field(3.0, description="width of the obstacle-risk transition, m")
    d_col: NonNegFloat = Field(5.0, description="distance to an obstacle counted as a collision, m")
    loiter_safety: bool = Field(True, description="admit only turns after which a maximum-turn loiter stays clear "
                                                  "of the obstacles (beyond the paper)")
    clearance_margin: NonNegFloat = Field(1.0, description="margin over d_col the safe loiters keep, m: must cover "
                                                           "the quadrotor's deviation from the planned chords")
    window_margin: NonNegFloat = Field(10.0, description="extra margin of the planning window, m")
    tail_steps: int = Field(0, ge=0, description="steps the leftover sets grow before they are measured (0: paper)")
    altitude_gain: NonNegFloat = Field(1.0, description="vertical speed per metre of altitude error, 1/s")
    velocity_lag_s: NonNegFloat = Field(0.0, description="time constant of the UAV's velocity response, s, that the "
                                                         "set-points compensate so that the UAV ends each step where "
                                                         "the planner's chord does (0: none)")

    @field_validator("n_controls")
    @classmethod
    def _odd(cls, value: int) -> int:
        if value % 2 == 0:
            raise ValueError(f"an odd number (so that 0 is on the grid), got {value}")
        return value


class InfoPlanSpec(Strict):
    """Paper 001's communication-aware information planner (``autonomy.guidance.infoplan``): every UAV of the world
    flies it with the same settings and plans the whole team (UAV i = uavs[i]); the speed is the guidance ``speed``,
    the altitude its ``altitude``, the step T_s the agent's period, the radar noise (δr, δθ) the UAV's radar's, the base
    station ``comms.base_station`` and the link model the radio's (``comms``). Defaults: the paper's."""

    routing: Literal["mst", "chain", "none"] | None = Field(
        None, description="route model of the objective: the radio's minimum spanning tree (mst) or fixed relay chain "
                          "(chain), or none (β ≡ 1: no communication term, the paper's 'without communication "
                          "optimisation'); None: the radio's comms.routing")
    objective: Literal["team", "own"] = Field("team", description="each UAV maximises the team's delivered "
                                                                  "information (team) or only its own (own, eq. 42)")
    criterion: Literal["logdet", "trace"] = Field("logdet", description="log det of the base's predicted information "
                                                                        "(D-optimal) or Σ β tr I (eq. 41)")
    horizon: int = Field(3, ge=1, description="steps T_p in the horizon")
    heading_rates: int = Field(7, ge=3, description="size of the heading-rate grid over ±max_heading_rate (odd)")
    max_heading_rate_deg_s: PositiveFloat = Field(30.0, description="ω_max, deg/s")
    d_safe: NonNegFloat = Field(100.0, description="planned separation between UAVs, m")
    target_accel_std: PositiveFloat = Field(0.1, description="target process noise δx = δy of the prediction, m/s^2")
    search: Literal["sequential", "joint"] = Field("sequential", description="UAVs in hierarchy order (coordinate "
                                                                             "ascent), or all jointly")
    sweeps: int = Field(2, ge=1, description="passes of the sequential search")

    @field_validator("heading_rates")
    @classmethod
    def _odd(cls, value: int) -> int:
        if value % 2 == 0:
            raise ValueError("an odd number (so that straight flight is in the grid)")
        return value


class GuidanceSpec(Strict):
    """The UAV's guidance law: ``hold`` its start, fly ``waypoints``, orbit the target at ``standoff_m`` with the
    Lyapunov ``vector_field`` or the ``nmpc``, paper 000's ``fast_mpc``, paper 003's ``formation``, paper 004's
    ``search``, paper 001's ``infoplan``, a type registered by :func:`simulator.registry.register_guidance`, or a user
    ``plugin``. ``speed``, ``altitude`` and ``standoff_m`` are the mission every law is given (each feeds the law's
    own field of that meaning: e.g. ``nominal_speed`` and ``standoff_radius`` of the vector field)."""

    type: str = Field("hold", description="the guidance type: a tag of worlds.variants.GUIDANCES")
    plugin: str | None = Field(None, description="'package.module:Class' of a user guidance law (type: plugin)")
    standoff_m: PositiveFloat = Field(100.0, description="standoff radius around the target, m")
    speed: PositiveFloat = Field(12.0, description="nominal speed, m/s")
    altitude: PositiveFloat = Field(60.0, description="m")
    waypoints: list[Vec3] = Field(default_factory=list, description="for type waypoints, m")
    params: dict[str, Any] = Field(default_factory=dict, description=(
        "further fields of the law's config, checked at load against the type's settings "
        "(worlds.schema_settings), or keyword arguments of a plugin (unchecked); " + SWITCH_RULE))
    formation: FormationSpec | None = Field(None, description="type formation: its settings (None: the defaults)")
    search: SearchSpec | None = Field(None, description="type search: its settings (None: the defaults)")
    infoplan: InfoPlanSpec | None = Field(None, description="type infoplan: its settings (None: the defaults)")

    @field_validator("type")
    @classmethod
    def _known(cls, value: str) -> str:
        return check_tag(GUIDANCES, value)

    @field_validator("params")
    @classmethod
    def _params(cls, value: dict[str, Any], info: ValidationInfo) -> dict[str, Any]:
        return _checked(value, info, GUIDANCES, "settings", "guidance")

    @model_validator(mode="after")
    def _plugin(self) -> GuidanceSpec:
        _check_plugin(self.type, self.plugin)
        if self.type == "waypoints" and not self.waypoints:
            raise ValueError("type 'waypoints' needs a non-empty 'waypoints' list")
        return self

    @property
    def settings(self) -> BaseModel | None:
        """The typed ``params`` of this type (None for a plugin)."""
        return _typed(GUIDANCES[self.type].settings, self.params)


class FusionSpec(Strict):
    """Fusion across the team: track-to-track fusion of the teammates' shared estimates (``convex``,
    ``covariance_intersection``: ``autonomy.fusion.track_fusion``), HCMCI consensus on information (``hcmci``:
    ``autonomy.fusion.hcmci_team``; needs the ``scif`` estimator; the UAVs due at a tick fuse as a team over the radio
    links that are up), raw measurement sharing (``measurements``: ``autonomy.fusion.measurement_sharing``; every
    teammate's detections reach this UAV over the radio, and its tracker stacks them with its own per scan time:
    paper 003's centralised augmented measurement), set fusion (``sets``: ``autonomy.fusion.set_team``; needs the
    ``set_membership`` estimator; the UAVs due at a tick fuse their sets with the teammates their links reach, paper
    004's fusion over lines of sight with ``comms.block_by_buildings``), or fusion at the base station
    (``base_station``: ``autonomy.fusion.base_station``; needs the ``scif`` estimator, ``comms.base_station`` and a
    radio model: the UAV runs a local information filter and sends the information of each scan to the base along its
    route of ``comms.routing``; the base fuses the packets that arrive — paper 001)."""

    method: str = Field("none", description="the fusion method: a tag of worlds.variants.FUSIONS")
    max_age_s: PositiveFloat = Field(2.0, description="shared estimates older than this are ignored, s")
    q: NonNegFloat = Field(1.0, description="white-acceleration density used to age shared estimates, m^2/s^3")
    switch_margin: float = Field(0.0, ge=0.0, lt=1.0, description="among traffic (convex, covariance_intersection): "
                                 "team probability by which another candidate must beat the team's target of the "
                                 "previous step to be taken instead (0: the most probable at every step)")
    rounds: int = Field(3, ge=1, description="hcmci: consensus iterations L per step")
    b: float | Literal["safe"] = Field("safe", description="hcmci: gain on the averaged measurement information, "
                                                           "'safe' (no measurement counted twice) or a number > 0 "
                                                           "(e.g. the team size N)")

    @field_validator("method")
    @classmethod
    def _known(cls, value: str) -> str:
        return check_tag(FUSIONS, value)

    @property
    def variant(self) -> FusionVariant:
        """What the method asks of the UAV's other parts (e.g. stacked scans for its tracker)."""
        return FUSIONS[self.method]

    @field_validator("b", mode="before")
    @classmethod
    def _gain(cls, value: Any) -> Any:
        if value == "safe" or (isinstance(value, int | float) and not isinstance(value, bool) and value > 0
                               and value != float("inf")):
            return value
        raise ValueError("'safe' or a finite number > 0")

    @model_validator(mode="after")
    def _hcmci_keys(self) -> FusionSpec:
        # a resolved world (model_dump) carries both at their defaults: only other values are errors
        extra = [k for k in ("b", "rounds") if getattr(self, k) != type(self).model_fields[k].default]
        if extra and self.method != "hcmci":
            raise ValueError(f"{' and '.join(extra)} only with method hcmci (method is {self.method!r})")
        return self


class AutonomySpec(Strict):
    rate_hz: PositiveFloat = Field(10.0, description="agent decision rate, Hz; must divide sim.physics_hz")
    fusion: FusionSpec = Field(default_factory=FusionSpec)
    estimator: EstimatorSpec = Field(default_factory=EstimatorSpec)
    guidance: GuidanceSpec = Field(default_factory=GuidanceSpec)
