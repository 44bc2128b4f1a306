"""The world-file schema: pydantic models for every section of a world file.

Every model forbids unknown keys, so a typo is an error, not a silently ignored setting, and every number must be
finite (``.nan`` and ``.inf`` are errors). Units: SI, except angles, which world files give in degrees (``*_deg`` keys)
and the code converts at load. Physical ranges (wind, gravity, building sizes, the terrain) are bounded where the
field is declared, with the reason in its description. Cross-field checks that need the whole world (rates dividing
the physics rate, references between sections, UAVs starting inside the terrain) live in :mod:`worlds.checks`.
"""

from __future__ import annotations

import math
import re
from typing import Annotated, ClassVar, Literal

from pydantic import ConfigDict, Field, field_validator, model_validator

from worlds.schema_autonomy import (AutonomySpec, EstimatorSpec, FormationSpec, FusionSpec, GuidanceSpec, ImmSpec,
                                    InfoPlanSpec, JacobiGainsSpec, SearchSpec, SetMembershipSpec)
from worlds.schema_base import NonNegFloat, PositiveFloat, Strict, Vec2, Vec3
from worlds.schema_traffic import DriverSpec, TrafficSpec

from worlds.catalog import CAR_ATTRIBUTES, CAR_COLOURS, CAR_TYPES

__all__ = [
    "AutonomySpec",
    "BearingSpec",
    "BoxSpec",
    "BodyReadSpec",
    "BuildingSpec",
    "CameraClassifySpec",
    "CameraSpec",
    "ClassReadSpec",
    "ColourReadSpec",
    "CommsSection",
    "DecoySpec",
    "DriverSpec",
    "EnvironmentSection",
    "EstimatorSpec",
    "FormationSpec",
    "FovSpec",
    "FusionSpec",
    "GroundVehicleSpec",
    "GuidanceSpec",
    "ImmSpec",
    "InfoPlanSpec",
    "InitialPose",
    "JacobiGainsSpec",
    "LengthReadSpec",
    "OsmSection",
    "OutageSpec",
    "RadarClassifySpec",
    "RadarSpec",
    "RenderSection",
    "RoadsSection",
    "RouteSpec",
    "SearchSpec",
    "SensorSpec",
    "SetMembershipSpec",
    "SimSection",
    "StreetSpec",
    "TerrainSection",
    "TownSection",
    "TurbulenceSection",
    "UavSpec",
    "WindSection",
    "World",
]

WORLD_HALF_EXTENT = 50_000.0
"""m: every place of a world (road nodes, buildings, decoys, UAV starts, the base station) lies within this distance
of the origin along each axis, half the largest terrain; the road network is sampled along its length, so a node
at 1e9 m would ask for a billion samples."""

Coordinate = Annotated[float, Field(ge=-WORLD_HALF_EXTENT, le=WORLD_HALF_EXTENT)]
Point2 = tuple[Coordinate, Coordinate]
Point3 = tuple[Coordinate, Coordinate, Coordinate]


MIN_PHYSICS_HZ = 100
"""Hz: the attitude-rate loops and the rotors' first-order lag (time constant 0.015 s for the crazyflie, 0.04 s for
the survey quad) are stepped once per physics tick; a coarser step than 10 ms leaves no margin on them."""

MAX_PHYSICS_HZ = 2400
"""Hz: ten times the default 240 Hz; finer steps change no flight and only multiply the run time."""


MAX_DURATION_S = 86_400.0
"""s: the longest simulated run, one day (20.7 million ticks at 240 Hz); the airframes' batteries last well under an
hour."""

MAX_SEED = 2**63 - 1
"""The largest run seed: it fits the signed 64-bit integers of JSON readers and numpy."""


class SimSection(Strict):
    physics_hz: int = Field(240, ge=MIN_PHYSICS_HZ, le=MAX_PHYSICS_HZ,
                            description=f"physics step rate, Hz, in [{MIN_PHYSICS_HZ}, {MAX_PHYSICS_HZ}] (the inner "
                                        "loops and rotor lags step once per tick); every other rate must divide it")
    duration_s: float = Field(60.0, gt=0, le=MAX_DURATION_S,
                              description=f"simulated duration, s, in (0, {MAX_DURATION_S:g}] (one day)")
    seed: int = Field(0, ge=0, le=MAX_SEED, description="root of the run's SeedSequence, in [0, 2^63 - 1]")
    record_hz: int = Field(20, gt=0, description="rate at which truth / estimates / commands are recorded, Hz")
    flush_every_s: PositiveFloat = Field(2.0, description="simulated seconds between flushes of the run record to "
                                                          "disk; at least one physics tick (the record is flushed "
                                                          "every round(flush_every_s * physics_hz) ticks)")


MAX_WIND_SPEED = 25.0
"""m/s: the fastest shipped airframe (survey_quad, max_speed 20 m/s) holds its position against at most about 24 m/s
of air: there its drag (0.10 v + 0.020 v^2 N) equals the horizontal thrust at its 37 deg commanded tilt limit. A
stronger mean wind blows every UAV away; 25 m/s is the bottom of Beaufort 10 (storm)."""

MAX_GUST_SIGMA = 5.0
"""m/s: MIL-F-8785C's severe low-altitude turbulence (exceeded with probability 1e-5) has a horizontal sigma of about
3-5 m/s; on top of the mean-wind bound, larger gusts exceed what the airframes can fly through."""


class TurbulenceSection(Strict):
    sigma: float = Field(1.0, ge=0, le=MAX_GUST_SIGMA,
                         description=f"turbulence intensity (std of each gust component), m/s, in [0, "
                                     f"{MAX_GUST_SIGMA:g}]: severe low-altitude turbulence (MIL-F-8785C) is 3-5 m/s")
    length_scale: float = Field(50.0, ge=1.0, le=1000.0,
                                description="Dryden length scale, m, in [1, 1000]: MIL-F-8785C's scales run from "
                                            "tens of metres near the ground to 533 m aloft")


class WindSection(Strict):
    mean_W: Vec3 = Field((0.0, 0.0, 0.0), description=f"constant wind in the world frame (ENU), m/s; its speed at "
                                                      f"most {MAX_WIND_SPEED:g} m/s, about what the fastest shipped "
                                                      f"airframe (survey_quad) can hold its position against")
    turbulence: TurbulenceSection | None = None

    @field_validator("mean_W")
    @classmethod
    def _flyable(cls, value: tuple[float, float, float]) -> tuple[float, float, float]:
        speed = math.sqrt(sum(c * c for c in value))
        if speed > MAX_WIND_SPEED:
            raise ValueError(f"a wind of at most {MAX_WIND_SPEED:g} m/s (this one is {speed:.4g} m/s): no shipped "
                             "airframe holds its position against more (survey_quad, the fastest, about 24 m/s)")
        return value


class EnvironmentSection(Strict):
    gravity: float = Field(9.81, ge=1.0, le=20.0,
                           description="gravitational acceleration, m/s^2, in [1, 20]: the crazyflie's rotors lift "
                                       "2.25 times its Earth weight, so it hovers up to about 22 m/s^2 (20 keeps a "
                                       "margin to manoeuvre); the Moon's 1.62 is inside")
    wind: WindSection | None = None
    downwash: bool = False
    ground_effect: bool = False


TerrainLength = Annotated[float, Field(gt=0, le=100_000.0)]
"""m: one side of the terrain, > 0 and at most 100 km (a city and its surroundings)."""


class TerrainSection(Strict):
    kind: Literal["flat"] = "flat"
    size: tuple[TerrainLength, TerrainLength] = Field(
        (2000.0, 2000.0), description="extent of the ground plane (x, y), m, centred on the origin; each side in "
                                      "(0, 100 km]; visual only (the ground's collision plane is infinite)")


class StreetSpec(Strict):
    id: str
    nodes: tuple[str, str]
    via: list[Point2] = Field(default_factory=list, description="intermediate centre-line vertices, m, within "
                                                                "50 km of the origin")
    lanes: int = Field(1, ge=1, le=8, description="lanes per direction (at most 8)")
    lane_width: float = Field(3.5, ge=2.0, le=6.0, description="m, in [2, 6]: narrower than 2 m no car fits, wider "
                                                               "than 6 m is no lane")
    speed_limit: float = Field(13.9, gt=0, le=70.0, description="m/s, at most 70 m/s (252 km/h: no road is faster)")
    two_way: bool = True


class OsmSection(Strict):
    path: str = Field(description="an .osm.pbf or .osm file; relative paths resolve against the world file, "
                                  "then assets/maps")
    bbox: tuple[float, float, float, float] | None = Field(None, description="lon_min, lat_min, lon_max, lat_max")
    default_height: PositiveFloat = Field(9.0, description="height of buildings without height tags, m")


MAX_TOWN_BLOCKS = 100
"""Most street-grid blocks of a procedural town along each axis (extent / block_size)."""


class TownSection(Strict):
    """Procedural town; fields map onto ``worlds.town.TownConfig``, which checks them here, at load: unknown fields
    and bad values are errors. At most :data:`MAX_TOWN_BLOCKS` blocks along each axis, building footprints from 1 m
    to 2 km and heights up to 1 km (as ``buildings``), so that a town stays a town (the generator fills every block
    with buildings)."""

    model_config = ConfigDict(extra="allow")

    @model_validator(mode="after")
    def _town_config(self) -> TownSection:
        import dataclasses

        from worlds.town import TownConfig

        params = dict(self.model_extra or {})
        names = {f.name for f in dataclasses.fields(TownConfig)}
        unknown = sorted(set(params) - names)
        if unknown:
            raise ValueError(f"only fields of TownConfig ({', '.join(sorted(names))}), got {unknown[0]!r}")
        try:
            cfg = TownConfig(**{k: tuple(v) if isinstance(v, list) else v for k, v in params.items()})
        except (TypeError, ValueError) as exc:
            raise ValueError(f"a valid town ({exc})") from None
        numbers = [*cfg.extent, cfg.block_size, cfg.lane_width, cfg.speed_limit, cfg.arterial_speed_limit,
                   cfg.setback, cfg.building_gap, *cfg.footprint_range, *cfg.height_range]
        if not all(isinstance(v, int | float) and math.isfinite(v) for v in numbers):
            raise ValueError(f"finite numbers in every town setting, got {params}")
        blocks = max(cfg.extent) / cfg.block_size
        if blocks > MAX_TOWN_BLOCKS:
            raise ValueError(f"at most {MAX_TOWN_BLOCKS} blocks along each axis (extent / block_size), got "
                             f"{blocks:.4g}")
        if not (1.0 <= cfg.footprint_range[0] and cfg.footprint_range[1] <= 2000.0):
            raise ValueError(f"building footprints from 1 m to 2 km (footprint_range), got {list(cfg.footprint_range)}")
        if cfg.height_range[1] > 1000.0:
            raise ValueError(f"building heights of at most 1 km (height_range), got {list(cfg.height_range)}")
        return self


class RoadsSection(Strict):
    nodes: dict[str, Point2] = Field(default_factory=dict, description="junction positions, m, within 50 km of the "
                                                                      "origin")
    streets: list[StreetSpec] = Field(default_factory=list)
    osm: OsmSection | None = None
    town: TownSection | None = None

    @model_validator(mode="after")
    def _one_source(self) -> RoadsSection:
        sources = [bool(self.streets), self.osm is not None, self.town is not None]
        if sum(sources) > 1:
            raise ValueError("give roads as streets, osm or town: at most one of them")
        for st in self.streets:
            for n in st.nodes:
                if n not in self.nodes:
                    raise ValueError(f"street {st.id!r} names node {n!r}, which is not in roads.nodes")
        return self


BuildingSide = Annotated[float, Field(ge=0.5, le=2000.0)]
"""m: a building's footprint side, 0.5 m to 2 km (a thinner footprint has no area to cast shadows or block rays)."""

BuildingHeight = Annotated[float, Field(ge=0.5, le=1000.0)]
"""m: a building's height, 0.5 m to 1 km (the tallest building stands 828 m)."""


class BuildingSpec(Strict):
    center: Point2 = Field(description="footprint centre (x, y), m, within 50 km of the origin")
    size: tuple[BuildingSide, BuildingSide, BuildingHeight] = Field(
        description="(length along yaw, width, height), m: sides in [0.5, 2000], height in [0.5, 1000]")
    yaw_deg: float = 0.0


class RouteSpec(Strict):
    roads: list[str] | None = Field(None, description="a fixed sequence of road ids")
    random_walk_from: str | None = Field(None, description="start road of a seeded random walk over the network")
    start_s: NonNegFloat = Field(0.0, description="arc length along the first road where the vehicle starts, m")
    lane: int = Field(0, ge=0, description="lane index, 0 = rightmost")
    stop_at_junctions: bool = True

    @model_validator(mode="after")
    def _exactly_one(self) -> RouteSpec:
        if (self.roads is None) == (self.random_walk_from is None):
            raise ValueError("give exactly one of 'roads' or 'random_walk_from'")
        return self


class GroundVehicleSpec(Strict):
    id: str
    type: str = Field("sedan", description=f"car parameter file name (vehicles/cars: {', '.join(CAR_TYPES)})")
    colour: str = Field("white", description=f"paint colour, one of {', '.join(CAR_COLOURS)}: the class a camera's "
                                             "colour reading (sensors[j].classify.colour) reads; the rendered body "
                                             "keeps the colour the camera detector looks for")
    role: Literal["target", "decoy", "traffic"] = "target"
    route: RouteSpec
    driver: DriverSpec = Field(default_factory=DriverSpec,
                               description="the driver's settings (defaults: DriverSpec's); with "
                                           "route.stop_at_junctions false, stop_probability defaults to 0")
    dynamics: Literal["physics", "kinematic"] = Field(
        "physics", description="how the car moves under its driver: 'physics' = a PyBullet multibody (chassis, four "
        "wheel joints with motors, Ackermann steering, tyre contacts); 'kinematic' = a kinematic bicycle model "
        "integrated at the physics rate, carrying one rigid box of the car's body size in the scene (sensors, "
        "cameras and contact checks see it; no wheels, tyre slip or contact forces act on it; much cheaper to step). "
        "Same driver, route, lane following, car following and stops either way")

    @field_validator("type")
    @classmethod
    def _known_car(cls, value: str) -> str:
        if value not in CAR_TYPES:
            raise ValueError(f"one of the car types of vehicles/cars ({', '.join(CAR_TYPES)})")
        return value

    @field_validator("colour")
    @classmethod
    def _known_colour(cls, value: str) -> str:
        if value not in CAR_COLOURS:
            raise ValueError(f"one of the car colours ({', '.join(CAR_COLOURS)})")
        return value

    @model_validator(mode="after")
    def _no_stops(self) -> GroundVehicleSpec:
        # the resolved world (model_dump) carries the 0 explicitly, so that it reads the same when loaded again
        if not self.route.stop_at_junctions and "stop_probability" not in self.driver.model_fields_set:
            self.driver = DriverSpec(**self.driver.model_dump(exclude_unset=True), stop_probability=0.0)
        return self


class InitialPose(Strict):
    position: Point3 = Field(description="initial position (ENU), m: within 50 km of the origin and above the "
                                         "ground, 0 < z <= 5000 m (worlds.checks)")
    yaw_deg: float = 0.0


class FovSpec(Strict):
    """Field of regard; angles in degrees (see ``autonomy.sensing.fov.FieldOfRegard``)."""

    frame: Literal["all_round", "world", "heading", "body"] = "all_round"
    azimuth_limits_deg: Vec2 = (-180.0, 180.0)
    elevation_limits_deg: Vec2 = (-90.0, 90.0)


class SensorBase(Strict):
    """Fields left out (None) take the sensor model's own defaults, documented in ``autonomy.sensing``."""

    id: str | None = None
    rate_hz: PositiveFloat = Field(description="measurement rate, Hz; must divide sim.physics_hz")
    latency_s: NonNegFloat | None = None


CONFUSION_ROW_TOL = 1e-6
"""Largest accepted ``|sum of a confusion row - 1|`` (``autonomy.sensing.classify.ROW_SUM_TOL``)."""


class ClassReadSpec(Strict):
    """A sensor's reading of one class attribute (``autonomy.sensing.classify.Classifier``): give ``accuracy`` (the
    true class with that probability, each wrong one with ``(1 - accuracy) / (K - 1)``) or the full ``confusion``
    matrix, ``confusion[true][observed]``, K x K for the K classes of the attribute (``worlds.catalog``)."""

    attribute: ClassVar[str]

    accuracy: float | None = Field(None, description="probability of reporting the true class, in (1/K, 1] for "
                                                      "the K classes of the attribute")
    confusion: list[list[float]] | None = Field(None, description="K x K row-stochastic matrix, [true][observed]: "
                                                                  "non-negative rows that sum to 1")

    @classmethod
    def n_classes(cls) -> int:
        return len(CAR_ATTRIBUTES[cls.attribute])

    @field_validator("accuracy")
    @classmethod
    def _better_than_a_guess(cls, value: float | None) -> float | None:
        k = cls.n_classes()
        if value is not None and not (1.0 / k < value <= 1.0):
            raise ValueError(f"an accuracy in (1/{k}, 1] (better than a guess among the {k} classes of "
                             f"{cls.attribute}: {', '.join(CAR_ATTRIBUTES[cls.attribute])})")
        return value

    @field_validator("confusion")
    @classmethod
    def _row_stochastic(cls, value: list[list[float]] | None) -> list[list[float]] | None:
        if value is None:
            return value
        k = cls.n_classes()
        classes = ", ".join(CAR_ATTRIBUTES[cls.attribute])
        if len(value) != k or any(len(row) != k for row in value):
            raise ValueError(f"a {k} x {k} matrix, one row and one column per class of {cls.attribute} ({classes}), "
                             f"got {len(value)} rows of lengths {[len(row) for row in value]}")
        for i, row in enumerate(value):
            if any(c < 0 for c in row) or abs(sum(row) - 1.0) > CONFUSION_ROW_TOL:
                raise ValueError(f"rows of non-negative entries that sum to 1 (row {i} sums to {sum(row):.9g})")
        return value

    @model_validator(mode="after")
    def _one_of(self) -> ClassReadSpec:
        if (self.accuracy is None) == (self.confusion is None):
            raise ValueError("exactly one of accuracy and confusion")
        return self


class LengthReadSpec(ClassReadSpec):
    """A radar's reading of the length class from the range profile (classes ``worlds.catalog.LENGTH_CLASSES``)."""

    attribute: ClassVar[str] = "length"


class ColourReadSpec(ClassReadSpec):
    """A camera's reading of the paint colour (classes ``worlds.catalog.CAR_COLOURS``)."""

    attribute: ClassVar[str] = "colour"


class BodyReadSpec(ClassReadSpec):
    """A camera's reading of the body type (classes ``worlds.catalog.CAR_TYPES``)."""

    attribute: ClassVar[str] = "body"


class RadarClassifySpec(Strict):
    """The class readings a radar attaches to its detections (``RadarConfig.classify``)."""

    length: LengthReadSpec | None = None


class CameraClassifySpec(Strict):
    """The class readings a camera attaches to its detections (``CameraConfig.classify``)."""

    colour: ColourReadSpec | None = None
    body: BodyReadSpec | None = None


class RadarSpec(SensorBase):
    """GMTI radar (``autonomy.sensing.radar.RadarConfig``)."""

    type: Literal["radar"]
    sigma_range: PositiveFloat = Field(description="m")
    sigma_azimuth_deg: PositiveFloat
    sigma_elevation_deg: PositiveFloat | None = Field(None, description="omit for a 2-D radar (range, azimuth)")
    sigma_range_rate: PositiveFloat | None = Field(None, description="m/s; omit for no range-rate channel")
    fov: FovSpec | None = None
    max_range: PositiveFloat | None = Field(None, description="m")
    pd_ref: float | None = Field(None, gt=0, lt=1, description="detection probability at range_ref (Swerling I: < 1)")
    range_ref: PositiveFloat | None = Field(None, description="m")
    pfa: float | None = Field(None, gt=0, lt=1)
    min_detectable_velocity: NonNegFloat | None = Field(None, description="GMTI Doppler notch, m/s")
    clutter_rate: NonNegFloat | None = Field(None, description="mean false alarms per scan")
    clutter_range_rate_max: NonNegFloat | None = Field(None, description="m/s")
    classify: RadarClassifySpec | None = Field(None, description="class readings of each detection (off when "
                                                                 "left out): length")


class CameraSpec(SensorBase):
    """Gimballed camera with a colour detector (``autonomy.sensing.camera.CameraConfig``)."""

    type: Literal["camera"]
    width: int | None = Field(None, gt=0)
    height: int | None = Field(None, gt=0)
    hfov_deg: float | None = Field(None, gt=0, lt=180)
    gimbal_pitch_deg: float | None = Field(None, description="depression below the horizon, degrees")
    stabilised: bool | None = None
    pixel_sigma: NonNegFloat | None = None
    near: PositiveFloat | None = None
    far: PositiveFloat | None = None
    min_blob_area_px: int | None = Field(None, gt=0)
    classify: CameraClassifySpec | None = Field(None, description="class readings of each detection (off when "
                                                                  "left out): colour, body")
    pointing: Literal["body", "track"] = Field("body", description="body: the axis is fixed by gimbal_pitch_deg "
                                               "and stabilised; track: a pan-tilt gimbal points it at the UAV's target "
                                               "estimate (anywhere below the horizon), body pose until there is one")


class BearingSpec(SensorBase):
    """Bearing-only sensor (``autonomy.sensing.bearing.BearingConfig``)."""

    type: Literal["bearing"]
    sigma_azimuth_deg: PositiveFloat
    sigma_elevation_deg: PositiveFloat | None = None
    fov: FovSpec | None = None
    max_range: PositiveFloat | None = None
    pd: float | None = Field(None, gt=0, le=1)


class BoxSpec(SensorBase):
    """Bounded-error position sensor with a nadir footprint (``autonomy.sensing.box_sensor.BoxSensorConfig``)."""

    type: Literal["box"]
    opening_angle_deg: float | None = Field(None, gt=0, lt=180)
    noise_bound: PositiveFloat | None = Field(None, description="half side of the error box, m")
    footprint_frame: Literal["heading", "world"] | None = None


SensorSpec = Annotated[RadarSpec | CameraSpec | BearingSpec | BoxSpec, Field(discriminator="type")]


class UavSpec(Strict):
    id: str
    airframe: str = "survey_quad"
    initial: InitialPose
    outer_loop_hz: int = Field(48, gt=0, description="velocity/position loop rate, Hz; must divide sim.physics_hz "
                                                     "and be the same for every UAV (one fleet)")
    sensors: list[SensorSpec] = Field(default_factory=list)
    autonomy: AutonomySpec = Field(default_factory=AutonomySpec)


class OutageSpec(Strict):
    link: tuple[str, str]
    start_s: NonNegFloat
    end_s: NonNegFloat


class CommsSection(Strict):
    """Radio between UAVs (``autonomy.sensing.channel.ChannelConfig``): ``perfect`` = every message arrives at once.

    ``rayleigh``: Pr(d) = exp(−N·gamma·d^alpha / (c·P)); the defaults (P = 30 dBm, N = −70 dBm, gamma = 10, c = 1,
    alpha = 3) give exp(−(d / 1000 m)^3), paper 001's Table 1.
    """

    model: Literal["perfect", "rayleigh"] = "perfect"
    transmit_power_dbm: float | None = None
    noise_power_dbm: float | None = None
    gamma: PositiveFloat | None = None
    c: PositiveFloat | None = None
    alpha: PositiveFloat | None = None
    max_range: PositiveFloat | None = Field(None, description="hard range limit, m")
    block_by_buildings: bool | None = Field(None, description="no link through a building (line of sight); under "
                                                              "perfect comms it shapes the graph of the team fusions "
                                                              "(hcmci, sets)")
    latency_s: NonNegFloat | None = Field(None, description="per hop, s; a whole number of physics ticks")
    base_station: Point3 | None = Field(None, description="position of the base station (the radio node 'base'), "
                                                          "m, within 50 km of the origin")
    routing: Literal["mst", "chain"] = Field(
        "mst", description="routes to the base station: the minimum spanning tree of link weights −ln Pr at each step "
                           "(mst), or the fixed relay chain in the order of uavs (chain: uavs[k] relays through "
                           "uavs[k−1], uavs[0] sends to the base)")
    links: list[tuple[str, str]] | None = Field(
        None, description="the radio graph: only these pairs of UAV ids have a link (None: every pair). Under a radio "
                          "model no message crosses another pair; under perfect comms teammates' states stay known "
                          "to all and the links (and outages) shape the hcmci consensus graph")
    outages: list[OutageSpec] = Field(default_factory=list)


class RenderSection(Strict):
    """Video of the run, rendered off-screen after it from its record (``simulator.render``)."""

    enabled: bool = Field(False, description="write video.mp4 into the run directory after the run")
    width: int = Field(1280, ge=16, multiple_of=2, description="frame width, pixels (even: H.264 with yuv420p)")
    height: int = Field(720, ge=16, multiple_of=2, description="frame height, pixels (even)")
    fps: int = Field(30, gt=0, le=240, description="video frame rate, Hz")
    camera: Literal["chase", "orbit", "topdown", "onboard", "split"] = Field(
        "split", description="split = chase view beside a top-down map")
    uav: int = Field(0, ge=0, description="index of the UAV the chase and onboard cameras ride with")


class DecoySpec(Strict):
    """A static object that looks like a target to every sensor, except that a bounded-error ``box`` sensor detects it
    only from inside its visibility cone (paper 004): vertex at the decoy, axis at azimuth ``yaw_deg`` tilted
    ``tilt_deg`` from the vertical, half aperture ``cone_half_angle_deg``. The paper draws the aperture 2λ in
    [12°, 36°] and tilts the axis by the aperture (``tilt_deg`` left out = twice the half-angle)."""

    id: str
    position: Point3 = Field(description="centre of the decoy's body, m, within 50 km of the origin")
    yaw_deg: float = Field(0.0, description="azimuth of the visibility cone's axis, and heading of the body, deg")
    cone_half_angle_deg: float = Field(45.0, gt=0, le=180, description="half-angle of the visibility cone")
    tilt_deg: float | None = Field(None, ge=0, le=180, description="angle of the cone's axis from the vertical, deg "
                                                                   "(None: twice the half-angle, the paper's cones)")


class CueSpec(Strict):
    """The hand-off that designates a target to the team: its position at the start, with this uncertainty."""

    sigma_m: float = Field(20.0, gt=0, le=5000, description="standard deviation of the cued position per axis, m")


class TargetSpec(Strict):
    """A designated target (``targets: [car1]`` is short for ``targets: [{id: car1}]``)."""

    id: str
    cue: CueSpec = Field(default_factory=CueSpec, description="the team's hand-off of where the target starts")


WORLD_NAME = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9_.-]{0,99}")
"""A world's name: ASCII letters, digits, ``_``, ``-`` and ``.`` (not first), at most 100 characters. It names the
default run directory ``runs/<name>``, so it must be one plain path component: no separators, no ``..``, not
absolute, not hidden."""


class World(Strict):
    """A whole world file."""

    name: str = Field("unnamed", description="the world's name, also the default run directory runs/<name>: "
                                             "letters, digits, '_', '-' and '.' (not first), at most 100 characters")
    description: str = ""
    sim: SimSection = Field(default_factory=SimSection)
    environment: EnvironmentSection = Field(default_factory=EnvironmentSection)
    terrain: TerrainSection = Field(default_factory=TerrainSection)
    roads: RoadsSection = Field(default_factory=RoadsSection)
    buildings: list[BuildingSpec] = Field(default_factory=list)
    ground_vehicles: list[GroundVehicleSpec] = Field(default_factory=list)
    targets: list[TargetSpec] | None = Field(None, description="the ground vehicles the team tracks, each an id or "
                                             "{id, cue: {sigma_m}} (default: the vehicles of role target, cue "
                                             "sigma 20 m)")
    decoys: list[DecoySpec] = Field(default_factory=list)
    traffic: TrafficSpec = Field(default_factory=TrafficSpec, description="background traffic generated on the "
                                 "roads besides the listed ground_vehicles (default: none)")
    uavs: list[UavSpec] = Field(default_factory=list)
    comms: CommsSection = Field(default_factory=CommsSection)
    render: RenderSection = Field(default_factory=RenderSection)

    @field_validator("name")
    @classmethod
    def _plain_name(cls, value: str) -> str:
        if not WORLD_NAME.fullmatch(value):
            raise ValueError("a plain name: ASCII letters, digits, '_', '-' and '.' (not first), at most 100 "
                             "characters (it names the run directory runs/<name>: no '/', no '..')")
        return value

    @field_validator("targets", mode="before")
    @classmethod
    def _target_ids(cls, value: object) -> object:
        if isinstance(value, list):
            return [{"id": v} if isinstance(v, str) else v for v in value]
        return value

    def designated(self) -> list[TargetSpec]:
        """The designated targets: ``targets``, or every vehicle of role target with the default cue."""
        if self.targets is not None:
            return list(self.targets)
        return [TargetSpec(id=g.id) for g in self.ground_vehicles if g.role == "target"]

    def target_ids(self) -> list[str]:
        """Ids of the designated targets (:meth:`designated`)."""
        return [t.id for t in self.designated()]
