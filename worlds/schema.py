"""The world-file schema: pydantic models for every section of a world file.

Every model forbids unknown keys, so a typo is an error, not a silently ignored setting. Units: SI, except angles, which
world files give in degrees (``*_deg`` keys) and the code converts at load. Cross-field checks that need the whole world
(rates dividing the physics rate, references between sections) live in :mod:`worlds.checks`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import ConfigDict, Field, model_validator

from worlds.schema_autonomy import (AutonomySpec, EstimatorSpec, FormationSpec, FusionSpec, GuidanceSpec, ImmSpec,
                                    InfoPlanSpec, JacobiGainsSpec, SearchSpec, SetMembershipSpec)
from worlds.schema_base import NonNegFloat, PositiveFloat, Strict, Vec2, Vec3

__all__ = [
    "AutonomySpec",
    "BearingSpec",
    "BoxSpec",
    "BuildingSpec",
    "CameraSpec",
    "CommsSection",
    "DecoySpec",
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
    "OsmSection",
    "OutageSpec",
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

class SimSection(Strict):
    physics_hz: int = Field(240, gt=0, description="physics step rate, Hz; every other rate must divide it")
    duration_s: PositiveFloat = Field(60.0, description="simulated duration, s")
    seed: int = Field(0, ge=0, description="root of the run's SeedSequence")
    record_hz: int = Field(20, gt=0, description="rate at which truth / estimates / commands are recorded, Hz")
    flush_every_s: PositiveFloat = Field(2.0, description="simulated seconds between flushes of the run record to disk")


class TurbulenceSection(Strict):
    sigma: NonNegFloat = Field(1.0, description="turbulence intensity (std of each gust component), m/s")
    length_scale: PositiveFloat = Field(50.0, description="Dryden length scale, m")


class WindSection(Strict):
    mean_W: Vec3 = Field((0.0, 0.0, 0.0), description="constant wind in the world frame (ENU), m/s")
    turbulence: TurbulenceSection | None = None


class EnvironmentSection(Strict):
    gravity: PositiveFloat = Field(9.81, description="gravitational acceleration, m/s^2")
    wind: WindSection | None = None
    downwash: bool = False
    ground_effect: bool = False


class TerrainSection(Strict):
    kind: Literal["flat"] = "flat"
    size: Vec2 = Field((2000.0, 2000.0), description="extent of the ground plane (x, y), m")

    @model_validator(mode="after")
    def _positive(self) -> TerrainSection:
        if min(self.size) <= 0:
            raise ValueError(f"size must be positive, got {list(self.size)}")
        return self


class StreetSpec(Strict):
    id: str
    nodes: tuple[str, str]
    via: list[Vec2] = Field(default_factory=list, description="intermediate centre-line vertices, m")
    lanes: int = Field(1, ge=1, description="lanes per direction")
    lane_width: PositiveFloat = 3.5
    speed_limit: PositiveFloat = Field(13.9, description="m/s")
    two_way: bool = True


class OsmSection(Strict):
    path: str = Field(description="an .osm.pbf or .osm file; relative paths resolve against the world file, "
                                  "then assets/maps")
    bbox: tuple[float, float, float, float] | None = Field(None, description="lon_min, lat_min, lon_max, lat_max")
    default_height: PositiveFloat = Field(9.0, description="height of buildings without height tags, m")


class TownSection(Strict):
    """Procedural town; fields map onto ``worlds.town.TownConfig`` (unknown fields are rejected there)."""

    model_config = ConfigDict(extra="allow")


class RoadsSection(Strict):
    nodes: dict[str, Vec2] = Field(default_factory=dict, description="junction positions, m")
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


class BuildingSpec(Strict):
    center: Vec2 = Field(description="footprint centre (x, y), m")
    size: Vec3 = Field(description="(length along yaw, width, height), m")
    yaw_deg: float = 0.0

    @model_validator(mode="after")
    def _positive(self) -> BuildingSpec:
        if min(self.size) <= 0:
            raise ValueError(f"size must be positive in every axis, got {list(self.size)}")
        return self


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
    type: str = Field("sedan", description="car parameter file name (vehicles/cars)")
    role: Literal["target", "decoy", "traffic"] = "target"
    route: RouteSpec
    driver: dict[str, Any] = Field(default_factory=dict, description="overrides of the driver configuration")
    dynamics: Literal["physics", "kinematic"] = Field(
        "physics", description="how the car moves under its driver: 'physics' = a PyBullet multibody (chassis, four "
        "wheel joints with motors, Ackermann steering, tyre contacts); 'kinematic' = a kinematic bicycle model "
        "integrated at the physics rate, carrying one rigid box of the car's body size in the scene (sensors, "
        "cameras and contact checks see it; no wheels, tyre slip or contact forces act on it; much cheaper to step). "
        "Same driver, route, lane following, car following and stops either way")


class InitialPose(Strict):
    position: Vec3 = Field(description="initial position (ENU), m")
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
    outer_loop_hz: int = Field(48, gt=0, description="velocity/position loop rate, Hz; must divide sim.physics_hz")
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
    base_station: Vec3 | None = Field(None, description="position of the base station (the radio node 'base'), m")
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
    position: Vec3 = Field(description="centre of the decoy's body, m")
    yaw_deg: float = Field(0.0, description="azimuth of the visibility cone's axis, and heading of the body, deg")
    cone_half_angle_deg: float = Field(45.0, gt=0, le=180, description="half-angle of the visibility cone")
    tilt_deg: float | None = Field(None, ge=0, le=180, description="angle of the cone's axis from the vertical, deg "
                                                                   "(None: twice the half-angle, the paper's cones)")


class World(Strict):
    """A whole world file."""

    name: str = "unnamed"
    description: str = ""
    sim: SimSection = Field(default_factory=SimSection)
    environment: EnvironmentSection = Field(default_factory=EnvironmentSection)
    terrain: TerrainSection = Field(default_factory=TerrainSection)
    roads: RoadsSection = Field(default_factory=RoadsSection)
    buildings: list[BuildingSpec] = Field(default_factory=list)
    ground_vehicles: list[GroundVehicleSpec] = Field(default_factory=list)
    targets: list[str] | None = Field(None, description="ids of ground vehicles the team tracks (default: role target)")
    decoys: list[DecoySpec] = Field(default_factory=list)
    uavs: list[UavSpec] = Field(default_factory=list)
    comms: CommsSection = Field(default_factory=CommsSection)
    render: RenderSection = Field(default_factory=RenderSection)
