"""Configuration and messages of the road-following driver."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["DriverConfig", "DriveCommand", "LeaderInfo"]


@dataclass(frozen=True, kw_only=True)
class DriverConfig:
    """Behaviour of one driver.

    Attributes
    ----------
    rate_hz : int
        Driver update rate (Hz); must divide the physics rate.
    lateral_accel_max : float
        Largest lateral acceleration v^2 |kappa| the speed profile allows (m/s^2).
    accel : float
        Comfortable acceleration a of the speed law and IDM (m/s^2), capped by the car's ``max_accel``.
    decel_plan : float
        Deceleration of the speed envelope and IDM comfortable deceleration b (m/s^2).
    decel_max : float
        Hardest braking the driver commands (m/s^2), capped by the car's ``max_decel``; >= ``decel_plan``.
    speed_gain : float
        Speed-tracking gain k_v (1/s).
    stanley_gain : float
        Stanley cross-track gain k (1/s): delta = psi_path - psi - atan(k e_front / (v + v_soft)).
    stanley_softening : float
        Stanley softening speed v_soft (m/s).
    yaw_damping : float
        Gain on the yaw-rate error (s): delta += -c (omega - v kappa_path).
    lookahead_margin : float
        Distance beyond the braking distance v^2 / (2 b_plan) scanned for curvature and stops (m).
    path_horizon : float
        Lane path kept built ahead of the car (m).
    path_ds : float
        Lane-path sample spacing (m).
    corner_length : float
        Junction corner: metres cut from each side of a junction and replaced by a smooth turn (m).
    stop_probability : float
        Probability of stopping at a junction when the route does not list its stops, in [0, 1].
    dwell_range : tuple[float, float]
        Uniform range of the dwell time at a stop (s).
    stop_window : float
        A car slower than ``stopped_speed`` within this distance of a stop line has stopped there (m).
    stopped_speed : float
        Speed below which a car counts as stopped (m/s).
    cruise_fraction_range : tuple[float, float]
        Uniform range of the cruise speed as a fraction of each road's speed limit, in (0, 1].
    cruise_change_period : float
        Mean time between random cruise-speed changes (s), exponentially distributed; 0 disables changes.
    idm_s0 : float
        IDM standstill gap s0 (m), bumper to bumper.
    idm_time_headway : float
        IDM time headway T (s).
    follow_range : float
        Distance ahead searched for a leading car (m).
    random_walk_chunk : int
        Roads asked from the network per random-walk extension.
    """

    rate_hz: int = 40
    lateral_accel_max: float = 2.5
    accel: float = 1.5
    decel_plan: float = 2.0
    decel_max: float = 6.0
    speed_gain: float = 1.5
    stanley_gain: float = 2.0
    stanley_softening: float = 1.0
    yaw_damping: float = 0.05
    lookahead_margin: float = 20.0
    path_horizon: float = 150.0
    path_ds: float = 1.0
    corner_length: float = 7.0
    stop_probability: float = 1.0
    dwell_range: tuple[float, float] = (2.0, 8.0)
    stop_window: float = 2.5
    stopped_speed: float = 0.3
    cruise_fraction_range: tuple[float, float] = (0.7, 1.0)
    cruise_change_period: float = 30.0
    idm_s0: float = 2.0
    idm_time_headway: float = 1.5
    follow_range: float = 80.0
    random_walk_chunk: int = 5

    def __post_init__(self) -> None:
        if not (isinstance(self.rate_hz, int) and self.rate_hz > 0):
            raise ValueError(f"DriverConfig.rate_hz must be a positive integer (Hz), got {self.rate_hz!r}")
        positive = ("lateral_accel_max", "accel", "decel_plan", "decel_max", "speed_gain", "stanley_gain",
                    "stanley_softening", "lookahead_margin", "path_horizon", "path_ds", "corner_length",
                    "stop_window", "stopped_speed", "idm_s0", "idm_time_headway", "follow_range")
        for f in positive:
            v = getattr(self, f)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"DriverConfig.{f} must be a finite number > 0, got {v!r}")
        for f in ("yaw_damping", "cruise_change_period"):
            v = getattr(self, f)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"DriverConfig.{f} must be >= 0, got {v!r}")
        if self.decel_max < self.decel_plan:
            raise ValueError(f"DriverConfig.decel_max must be >= decel_plan {self.decel_plan}, got {self.decel_max}")
        if not (0.0 <= self.stop_probability <= 1.0):
            raise ValueError(f"DriverConfig.stop_probability must be in [0, 1], got {self.stop_probability}")
        lo, hi = self.dwell_range
        if not (0.0 <= lo <= hi and math.isfinite(hi)):
            raise ValueError(f"DriverConfig.dwell_range must satisfy 0 <= min <= max, got {self.dwell_range}")
        lo, hi = self.cruise_fraction_range
        if not (0.0 < lo <= hi <= 1.0):
            raise ValueError(f"DriverConfig.cruise_fraction_range must satisfy 0 < min <= max <= 1, "
                             f"got {self.cruise_fraction_range}")
        if not (isinstance(self.random_walk_chunk, int) and self.random_walk_chunk >= 1):
            raise ValueError(f"DriverConfig.random_walk_chunk must be an integer >= 1, got {self.random_walk_chunk!r}")
        if self.path_horizon < 4 * self.corner_length:
            raise ValueError(f"DriverConfig.path_horizon must be >= 4 x corner_length, got {self.path_horizon}")

    def ticks_per_update(self, physics_hz: int) -> int:
        """Physics ticks between driver updates; raises if ``rate_hz`` does not divide ``physics_hz``."""
        if physics_hz % self.rate_hz:
            raise ValueError(f"DriverConfig.rate_hz {self.rate_hz} Hz does not divide physics_hz {physics_hz} Hz")
        return physics_hz // self.rate_hz


@dataclass(frozen=True, kw_only=True)
class LeaderInfo:
    """The nearest car ahead in the same lane.

    Attributes
    ----------
    gap : float
        Bumper-to-bumper distance along the lane (m).
    speed : float
        Its speed along the lane (m/s).
    index : int
        Its index in the fleet.
    """

    gap: float
    speed: float
    index: int = -1


@dataclass(frozen=True, kw_only=True)
class DriveCommand:
    """Driver output, held until the next driver update.

    Attributes
    ----------
    accel : float
        Longitudinal acceleration command (m/s^2); negative brakes.
    steer : float
        Bicycle-model front-wheel steering angle (rad), positive left.
    hold : bool
        Stand still with the brakes on (stopped at a junction or at the end of the route).
    tick : int
        Physics tick of the update that produced it.
    """

    accel: float
    steer: float
    hold: bool = False
    tick: int = 0
