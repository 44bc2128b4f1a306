"""Car parameters (:class:`CarParams`) and the loader of the shipped parameter files in :mod:`vehicles.cars`.

Body frame FLU (x forward, y left, z up) with its origin at the centre of mass, which sits midway between the axles
at ``cog_height`` above the ground. SI units, radians.
"""

from __future__ import annotations

import importlib
import math
import pkgutil
from dataclasses import dataclass

__all__ = ["CarParams", "load_car", "list_cars"]


@dataclass(frozen=True, kw_only=True)
class CarParams:
    """Physical parameters of one car type.

    Attributes
    ----------
    name : str
        Type name (``"sedan"``), also the parameter module's name.
    mass : float
        Total mass including wheels (kg).
    wheelbase : float
        Front to rear axle distance L (m).
    track : float
        Left to right wheel-centre distance (m).
    length, width, height : float
        Body outer dimensions (m); ``length`` > ``wheelbase``, ``width`` >= ``track``.
    ground_clearance : float
        Height of the body floor above the ground (m), below ``wheel_radius`` and ``cog_height``.
    wheel_radius : float
        Rolling radius r (m).
    wheel_mass : float
        Mass of one wheel with hub (kg).
    cog_height : float
        Height of the centre of mass above the ground (m), above ``wheel_radius``.
    max_steer : float
        Largest road-wheel steering angle of the virtual bicycle front wheel (rad), in (0, pi/3].
    max_steer_rate : float
        Largest steering rate (rad/s).
    max_drive_torque : float
        Total drive torque at the driven (rear) wheels (N m).
    max_brake_torque : float
        Total brake torque over the four wheels (N m).
    max_accel : float
        Largest longitudinal acceleration the driver may ask for (m/s^2).
    max_decel : float
        Largest braking deceleration the driver may ask for (m/s^2), positive.
    max_speed : float
        Top speed (m/s).
    tyre_friction : float
        Tyre-road Coulomb friction coefficient mu (PyBullet ``lateralFriction``).
    rolling_friction : float
        PyBullet ``rollingFriction`` of the wheels (m; rolling-resistance torque = value x normal force).
    steer_torque : float
        Torque limit of each front wheel's steering actuator (N m).
    hub_mass : float
        Mass of each front steering knuckle (kg), part of ``mass``.
    """

    name: str
    mass: float
    wheelbase: float
    track: float
    length: float
    width: float
    height: float
    ground_clearance: float
    wheel_radius: float
    wheel_mass: float
    cog_height: float
    max_steer: float
    max_steer_rate: float
    max_drive_torque: float
    max_brake_torque: float
    max_accel: float
    max_decel: float
    max_speed: float
    tyre_friction: float
    rolling_friction: float = 0.0
    steer_torque: float = 2000.0
    hub_mass: float = 8.0

    def __post_init__(self) -> None:
        positive = ("mass", "wheelbase", "track", "length", "width", "height", "ground_clearance", "wheel_radius",
                    "wheel_mass", "cog_height", "max_steer", "max_steer_rate", "max_drive_torque", "max_brake_torque",
                    "max_accel", "max_decel", "max_speed", "tyre_friction", "steer_torque", "hub_mass")
        for f in positive:
            v = getattr(self, f)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"CarParams.{f} must be a finite number > 0, got {v!r}")
        if not (math.isfinite(self.rolling_friction) and self.rolling_friction >= 0):
            raise ValueError(f"CarParams.rolling_friction must be >= 0 m, got {self.rolling_friction!r}")
        if not self.name:
            raise ValueError("CarParams.name must be a non-empty string")
        if 4 * self.wheel_mass + 2 * self.hub_mass >= 0.5 * self.mass:
            raise ValueError(f"CarParams.wheel_mass: wheels and hubs must weigh under half of mass {self.mass} kg, "
                             f"got wheel_mass {self.wheel_mass}")
        if self.length <= self.wheelbase:
            raise ValueError(f"CarParams.length must exceed wheelbase {self.wheelbase} m, got {self.length}")
        if self.width < self.track:
            raise ValueError(f"CarParams.width must be >= track {self.track} m, got {self.width}")
        if self.max_steer > math.pi / 3:
            raise ValueError(f"CarParams.max_steer must be <= pi/3 rad, got {self.max_steer}")
        if self.ground_clearance >= min(self.wheel_radius, self.cog_height):
            raise ValueError(f"CarParams.ground_clearance must be below wheel_radius and cog_height, "
                             f"got {self.ground_clearance}")
        if not (self.wheel_radius < self.cog_height < self.height):
            raise ValueError(f"CarParams.cog_height must lie between wheel_radius and height, got {self.cog_height}")
        if self.tyre_friction > 2.0:
            raise ValueError(f"CarParams.tyre_friction must be <= 2, got {self.tyre_friction}")

    @property
    def min_turn_radius(self) -> float:
        """Smallest turning radius of the rear-axle centre, L / tan(max_steer) (m)."""
        return self.wheelbase / math.tan(self.max_steer)


def list_cars() -> list[str]:
    """Names of the shipped car types (modules of :mod:`vehicles.cars`), sorted."""
    import vehicles.cars as pkg

    return sorted(m.name for m in pkgutil.iter_modules(pkg.__path__) if not m.name.startswith("_"))


def load_car(name: str) -> CarParams:
    """The :class:`CarParams` named ``name`` (the ``PARAMS`` of ``vehicles/cars/<name>.py``).

    Raises
    ------
    ValueError
        If no such car type exists.
    """
    names = list_cars()
    if name not in names:
        raise ValueError(f"unknown car type {name!r}; known: {names}")
    module = importlib.import_module(f"vehicles.cars.{name}")
    params = module.PARAMS
    if not isinstance(params, CarParams):
        raise TypeError(f"vehicles.cars.{name}.PARAMS is not a CarParams")
    return params
