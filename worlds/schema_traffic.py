"""World-file settings of ground traffic: a car's driver (:class:`DriverSpec`, the one declaration of the driver's
settings) and the background traffic generated on the roads (:class:`TrafficSpec`)."""

from __future__ import annotations

from typing import Literal

from pydantic import ConfigDict, Field, ValidationInfo, field_validator, model_validator

from worlds.catalog import CAR_COLOURS, CAR_TYPES
from worlds.schema_base import NonNegFloat, PositiveFloat, Strict

__all__ = ["DriverSpec", "FlowSpec", "TrafficSpec"]


class DriverSpec(Strict):
    """Behaviour of one car's road-following driver: the one declaration of its settings.
    ``vehicles.car.driver_config.DriverConfig`` is this model (frozen, plus the driver's tick arithmetic), so a world
    file's ``driver:`` keys, their defaults and their bounds are the driver's own."""

    rate_hz: int = Field(40, gt=0, description="driver update rate, Hz; must divide sim.physics_hz")
    lateral_accel_max: PositiveFloat = Field(
        2.5, description="largest lateral acceleration v^2 |kappa| the speed profile allows, m/s^2")
    accel: PositiveFloat = Field(1.5, description="comfortable acceleration a of the speed law and IDM, m/s^2, "
                                                  "capped by the car's max_accel")
    decel_plan: PositiveFloat = Field(2.0, description="deceleration of the speed envelope and IDM comfortable "
                                                       "deceleration b, m/s^2")
    decel_max: PositiveFloat = Field(6.0, description="hardest braking the driver commands, m/s^2, capped by the "
                                                      "car's max_decel; >= decel_plan")
    speed_gain: PositiveFloat = Field(1.5, description="speed-tracking gain k_v, 1/s")
    stanley_gain: PositiveFloat = Field(2.0, description="Stanley cross-track gain k, 1/s: delta = psi_path - psi - "
                                                         "atan(k e_front / (v + v_soft))")
    stanley_softening: PositiveFloat = Field(1.0, description="Stanley softening speed v_soft, m/s")
    yaw_damping: NonNegFloat = Field(0.05, description="gain on the yaw-rate error, s: delta += -c (omega - v "
                                                       "kappa_path)")
    lookahead_margin: float = Field(20.0, gt=0, le=1000.0,
                                    description="distance beyond the braking distance v^2 / (2 b_plan) scanned for "
                                                "curvature and stops, m, at most 1 km")
    path_horizon: float = Field(150.0, gt=0, le=2000.0,
                                description="lane path kept built ahead of the car, m, at most 2 km (the path is "
                                            "sampled every path_ds and rebuilt as the car drives)")
    path_ds: float = Field(1.0, ge=0.05, le=10.0, description="lane-path sample spacing, m, in [0.05, 10]")
    corner_length: PositiveFloat = Field(7.0, description="junction corner: metres cut from each side of a junction "
                                                          "and replaced by a smooth turn, m")
    stop_probability: float = Field(1.0, ge=0, le=1, description="probability of stopping at a junction when the "
                                                                 "route does not list its stops, in [0, 1]")
    dwell_range: tuple[NonNegFloat, NonNegFloat] = Field((2.0, 8.0), description="uniform range (min, max) of the "
                                                                                 "dwell time at a stop, s")
    stop_window: PositiveFloat = Field(2.5, description="a car slower than stopped_speed within this distance of a "
                                                        "stop line has stopped there, m")
    stopped_speed: PositiveFloat = Field(0.3, description="speed below which a car counts as stopped, m/s")
    cruise_fraction_range: tuple[float, float] = Field(
        (0.7, 1.0), description="uniform range (min, max) of the cruise speed as a fraction of each road's speed "
                                "limit, 0 < min <= max <= 1")
    cruise_change_period: NonNegFloat = Field(30.0, description="mean time between random cruise-speed changes, s, "
                                                                "exponentially distributed; 0 disables changes")
    idm_s0: PositiveFloat = Field(2.0, description="IDM standstill gap s0, m, bumper to bumper")
    idm_time_headway: PositiveFloat = Field(1.5, description="IDM time headway T, s")
    follow_range: PositiveFloat = Field(80.0, description="distance ahead searched for a leading car, m")
    random_walk_chunk: int = Field(5, ge=1, le=100, description="roads asked from the network per random-walk "
                                                                "extension")

    @model_validator(mode="after")
    def _consistent(self) -> DriverSpec:
        if self.decel_max < self.decel_plan:
            raise ValueError(f"decel_max >= decel_plan ({self.decel_plan:g} m/s^2), got decel_max {self.decel_max:g}")
        lo, hi = self.dwell_range
        if lo > hi:
            raise ValueError(f"dwell_range with 0 <= min <= max, got {list(self.dwell_range)}")
        lo, hi = self.cruise_fraction_range
        if not (0.0 < lo <= hi <= 1.0):
            raise ValueError(f"cruise_fraction_range with 0 < min <= max <= 1, got {list(self.cruise_fraction_range)}")
        if self.path_horizon < 4 * self.corner_length:
            raise ValueError(f"path_horizon >= 4 x corner_length ({4 * self.corner_length:g} m), got "
                             f"{self.path_horizon:g}")
        return self


class FlowSpec(Strict):
    """A stream of SUMO vehicles from the start of one road to the end of another along SUMO's fastest route,
    departing as a Poisson process (:class:`vehicles.sumo.demand.Flow`)."""

    model_config = ConfigDict(populate_by_name=True)

    origin: str = Field(alias="from", min_length=1, description="road id the vehicles depart from (its start)")
    destination: str = Field(alias="to", min_length=1, description="road id the vehicles arrive on (its end)")
    via: list[str] = Field(default_factory=list, description="road ids the route passes, in order")
    per_hour: float = Field(gt=0, le=36000.0, description="mean departures per hour (Poisson), in (0, 36000]")
    begin_s: NonNegFloat = Field(0.0, description="first second of departures, s")
    end_s: PositiveFloat | None = Field(None, description="departures stop here, s (> begin_s); none: never")

    @model_validator(mode="after")
    def _window(self) -> FlowSpec:
        if self.end_s is not None and not self.end_s > self.begin_s:
            raise ValueError(f"end_s > begin_s ({self.begin_s:g} s), got end_s {self.end_s:g}")
        return self


class TrafficSpec(Strict):
    """Background traffic besides the world's listed ``ground_vehicles``, ``cars`` of role traffic. They join the
    ground vehicles as ``<id_prefix>1`` .. ``<id_prefix>N`` after the listed ones, so sensors, trackers, metrics and
    records see them like any car.

    ``engine: builtin``: kinematic cars on seeded random walks of skytrack's own driver, placed at seeded random
    points of the road network (:mod:`worlds.traffic`) and stepped by the compiled built-in fleet at ``rate_hz``.
    ``engine: sumo``: SUMO co-simulation (:mod:`vehicles.sumo`, the ``traffic`` extra) on a network made from the
    world's roads, keeping ``cars`` trips on the road (each car id is a slot a vehicle takes while it drives), stepped
    at ``rate_hz``; the world's physics cars are remote-controlled in SUMO so its traffic reacts to them."""

    engine: Literal["builtin", "sumo"] = Field("builtin", description="what drives the traffic: 'builtin' = the "
                                               "compiled fleet of skytrack's own driver; 'sumo' = SUMO in process "
                                               "(pip install 'skytrack[traffic]')")
    tls: Literal["auto", "map", "guess", "none"] = Field(
        "auto", description="sumo only: traffic lights at the junctions the map's signals control (OSM "
                            "highway=traffic_signals and signalised crossings) and those listed in signals ('map'), "
                            "those plus netconvert's guess elsewhere ('guess'), none at all (priority junctions: "
                            "'none'), or 'map' when there are any and 'guess' when there are none ('auto')")
    cars: int = Field(0, ge=0, le=5000, description="number of traffic cars to generate, 0 to 5000 (sumo: the scene "
                                                    "slots, the most vehicles on the road at once)")
    trips: int | None = Field(None, ge=0, le=5000, description="sumo only: random trips kept on the road, at most "
                                                               "cars; default cars without flows, 0 with them")
    flows: list[FlowSpec] = Field(default_factory=list, description="sumo only: vehicle flows between roads, on the "
                                                                    "slots the trips leave")
    signals: list[str] = Field(default_factory=list, description="sumo only: junction node ids that get traffic "
                                                                 "lights besides those the map's signals control")
    rate_hz: int = Field(20, gt=0, description="the traffic drivers' update rate, Hz; must divide sim.physics_hz")
    types: list[str] = Field(default_factory=lambda: ["sedan", "van"], min_length=1,
                             description="car types, cycled over the generated cars (sumo: the first, for all)")
    colours: list[str] = Field(default_factory=lambda: list(CAR_COLOURS), min_length=1,
                               description="paint colours, cycled over the generated cars")
    min_spacing_m: float = Field(12.0, ge=6.0, le=500.0, description="least distance between two cars' starts, m "
                                                                     "(any two cars of the world), in [6, 500]")
    id_prefix: str = Field("traffic_", pattern=r"^[A-Za-z][A-Za-z0-9_]{0,30}$",
                           description="prefix of the generated cars' ids")
    driver: DriverSpec = Field(default_factory=DriverSpec, description="the generated cars' driver settings "
                                                                       "(rate_hz is the section's)")

    @field_validator("types", "colours")
    @classmethod
    def _known(cls, value: list[str], info: ValidationInfo) -> list[str]:
        known, what = (CAR_TYPES, "car types of vehicles/cars") if info.field_name == "types" else (CAR_COLOURS,
                                                                                                   "car colours")
        bad = [v for v in value if v not in known]
        if bad:
            raise ValueError(f"{what} ({', '.join(known)}), got {bad}")
        return value

    @model_validator(mode="after")
    def _demand(self) -> TrafficSpec:
        if self.engine != "sumo" and (self.flows or self.trips is not None or self.signals):
            raise ValueError("trips, flows and signals need engine: sumo (the built-in cars drive random walks from "
                             "their starts and know no traffic lights)")
        if self.trips is not None and self.trips > self.cars:
            raise ValueError(f"trips <= cars ({self.cars}, the scene slots), got trips {self.trips}")
        if self.flows and self.cars - self.sumo_trips < 1:
            raise ValueError(f"flows need slots the trips leave: cars ({self.cars}) > trips ({self.sumo_trips})")
        return self

    @property
    def sumo_trips(self) -> int:
        """Random trips SUMO keeps on the road: ``trips``, else ``cars`` without flows and 0 with them."""
        return self.trips if self.trips is not None else (0 if self.flows else self.cars)

    @model_validator(mode="after")
    def _rate_is_the_sections(self) -> TrafficSpec:
        if "rate_hz" in self.driver.model_fields_set and self.driver.rate_hz != self.rate_hz:
            raise ValueError(f"traffic.driver.rate_hz ({self.driver.rate_hz}) differs from traffic.rate_hz "
                             f"({self.rate_hz}): give the rate once, as traffic.rate_hz")
        if self.driver.rate_hz != self.rate_hz:  # the resolved world carries the one rate in both places
            self.driver = DriverSpec(**self.driver.model_dump(exclude_unset=True) | {"rate_hz": self.rate_hz})
        return self
