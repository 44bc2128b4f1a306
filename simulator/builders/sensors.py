"""Sensor builders: a world file's sensor entry (``worlds.schema``'s ``RadarSpec`` …) → its sensor model, degrees in
radians; fields left out take the model's defaults."""

from __future__ import annotations

import math
from typing import Any

from autonomy.sensing.measurement import Sensor
from simulator.builders.common import given
from worlds.schema import BearingSpec, BoxSpec, CameraSpec, FovSpec, RadarSpec

__all__ = ["build_bearing", "build_box", "build_camera", "build_radar", "field_of_regard"]


def field_of_regard(spec: FovSpec | None) -> Any:
    """The :class:`~autonomy.sensing.fov.FieldOfRegard` of a ``fov`` entry (None: all round)."""
    from autonomy.sensing.fov import FieldOfRegard

    if spec is None:
        return FieldOfRegard()
    return FieldOfRegard(frame=spec.frame, azimuth_limits=tuple(math.radians(a) for a in spec.azimuth_limits_deg),
                         elevation_limits=tuple(math.radians(a) for a in spec.elevation_limits_deg))


def build_radar(spec: RadarSpec, name: str, buildings: Any = ()) -> Sensor:
    from autonomy.sensing.radar import Radar, RadarConfig

    return Radar(RadarConfig(**given(spec), fov=field_of_regard(spec.fov)), sensor_id=name)


def build_camera(spec: CameraSpec, name: str, buildings: Any = ()) -> Sensor:
    from autonomy.sensing.camera import Camera, CameraConfig

    return Camera(CameraConfig(**given(spec)), sensor_id=name)


def build_bearing(spec: BearingSpec, name: str, buildings: Any = ()) -> Sensor:
    from autonomy.sensing.bearing import BearingConfig, BearingSensor

    return BearingSensor(BearingConfig(**given(spec), fov=field_of_regard(spec.fov)), sensor_id=name)


def build_box(spec: BoxSpec, name: str, buildings: Any = ()) -> Sensor:
    """The bounded-error box sensor (``buildings``: its shadow casters)."""
    from autonomy.sensing.box_sensor import BoxSensor, BoxSensorConfig

    return BoxSensor(BoxSensorConfig(**given(spec)), buildings=buildings, sensor_id=name)
