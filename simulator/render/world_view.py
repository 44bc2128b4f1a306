"""What a replay takes from the run's world file, read through the schema: the UAVs' names, standoff radii and
airframe, the cars' and decoys' bodies.

The run directory's ``world.yaml`` is the resolved world the run used; it is loaded with
:func:`worlds.loader.load_world` and read through the typed fields of :class:`worlds.schema.World`. Sizes come from
the parameter files the run loaded (``vehicles/cars/<type>.py``, ``vehicles/airframes/<name>.py``); what the world
leaves out takes the schema's own defaults. A world file that is missing or does not validate against the current
schema (a run recorded by another version) is replayed as the empty :class:`~worlds.schema.World`, with a warning.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from simulator.decoys import DECOY_CAR
from vehicles.car.params import load_car
from vehicles.quadrotor.airframes import load_airframe
from worlds.loader import load_world
from worlds.schema import GroundVehicleSpec, UavSpec, World

__all__ = ["DecoyBody", "ReplayWorld", "read_world"]

_STANDOFF_GUIDANCE = ("vector_field", "nmpc", "plugin")  # guidance types whose standoff circle is drawn


def read_world(run_dir: Path) -> World:
    """The validated world of a run directory (the empty world, with a warning, when it cannot be read)."""
    path = Path(run_dir) / "world.yaml"
    try:
        return load_world(path).world
    except Exception as exc:  # noqa: BLE001 - an older or newer schema must not stop a replay
        warnings.warn(f"{path} cannot be read against the current schema ({exc}); replaying without its world",
                      stacklevel=3)
        return World()


def car_size(car_type: str) -> tuple[float, float, float]:
    """Body length, width and height of the car type ``car_type`` (``vehicles/cars``), m."""
    car = load_car(car_type)
    return float(car.length), float(car.width), float(car.height)


class DecoyBody(NamedTuple):
    """A decoy's body: size (length, width, height) m, centre (3,) m and heading rad (what
    :class:`~simulator.render.stage.Stage` takes)."""

    size: tuple[float, float, float]
    position: np.ndarray
    yaw: float


@dataclass(frozen=True, eq=False)
class ReplayWorld:
    """The parts of a run's world a replay draws.

    Attributes
    ----------
    world : World
        The validated world.
    """

    world: World

    def uav_name(self, u: int) -> str:
        """The id of UAV ``u`` (``uav<u>`` when the world does not list it)."""
        return self.world.uavs[u].id if u < len(self.world.uavs) else f"uav{u}"

    def standoff(self, u: int) -> float | None:
        """The standoff radius of UAV ``u``'s guidance, m, or None when its guidance holds none."""
        if u >= len(self.world.uavs):
            return None
        g = self.world.uavs[u].autonomy.guidance
        return float(g.standoff_m) if g.type in _STANDOFF_GUIDANCE else None

    def vehicle_size(self, v: int) -> tuple[float, float, float]:
        """Body size of ground vehicle ``v``, m (of the schema's default car type when the world does not list it)."""
        gv = self.world.ground_vehicles
        return car_size(gv[v].type if v < len(gv) else GroundVehicleSpec.model_fields["type"].default)

    def vehicle_role(self, v: int) -> str | None:
        """The role of ground vehicle ``v`` (``target``, ``decoy``, ``traffic``), or None when the world does not list
        it."""
        gv = self.world.ground_vehicles
        return gv[v].role if v < len(gv) else None

    def uav_arm_length(self) -> float:
        """Rotor arm length of the first UAV's airframe (the schema's default airframe without UAVs), m."""
        uavs = self.world.uavs
        name = uavs[0].airframe if uavs else UavSpec.model_fields["airframe"].default
        return float(load_airframe(name).arm_length)

    def decoys(self) -> list[DecoyBody]:
        """The bodies of the world's decoys (cars of type :data:`simulator.decoys.DECOY_CAR`)."""
        size = car_size(DECOY_CAR)
        return [DecoyBody(size, np.asarray(d.position, dtype=float), float(np.radians(d.yaw_deg)))
                for d in self.world.decoys]
