"""Sensor builders: a world file's sensor entry (``worlds.schema``'s ``RadarSpec`` …) → its sensor model, degrees in
radians; fields left out take the model's defaults."""

from __future__ import annotations

import math
from typing import Any

from autonomy.sensing.measurement import Sensor
from simulator.builders.common import SENSOR_COMMON, given
from worlds.schema import BearingSpec, BoxSpec, CameraClassifySpec, CameraSpec, FovSpec, RadarClassifySpec, RadarSpec

__all__ = ["build_bearing", "build_box", "build_camera", "build_radar", "classifiers", "field_of_regard"]

_NOT_FIELDS = SENSOR_COMMON | {"classify"}
"""Keys of radar and camera entries built into their config by hand (the ``classify`` block: :func:`classifiers`)."""


def field_of_regard(spec: FovSpec | None) -> Any:
    """The :class:`~autonomy.sensing.fov.FieldOfRegard` of a ``fov`` entry (None: all round)."""
    from autonomy.sensing.fov import FieldOfRegard

    if spec is None:
        return FieldOfRegard()
    return FieldOfRegard(frame=spec.frame, azimuth_limits=tuple(math.radians(a) for a in spec.azimuth_limits_deg),
                         elevation_limits=tuple(math.radians(a) for a in spec.elevation_limits_deg))


def classifiers(spec: RadarClassifySpec | CameraClassifySpec | None) -> tuple[Any, ...]:
    """The :class:`~autonomy.sensing.classify.Classifier` of each attribute a ``classify`` block reads, in the
    block's key order (None: none)."""
    from autonomy.sensing.classify import Classifier

    if spec is None:
        return ()
    return tuple(Classifier.for_attribute(attribute, accuracy=read.accuracy, confusion=read.confusion)
                 for attribute, read in spec if read is not None)


def build_radar(spec: RadarSpec, name: str, buildings: Any = ()) -> Sensor:
    from autonomy.sensing.radar import Radar, RadarConfig

    return Radar(RadarConfig(**given(spec, _NOT_FIELDS), fov=field_of_regard(spec.fov),
                             classify=classifiers(spec.classify)), sensor_id=name)


def build_camera(spec: CameraSpec, name: str, buildings: Any = ()) -> Sensor:
    from autonomy.sensing.camera import Camera, CameraConfig

    return Camera(CameraConfig(**given(spec, _NOT_FIELDS), classify=classifiers(spec.classify)), sensor_id=name)


def build_bearing(spec: BearingSpec, name: str, buildings: Any = ()) -> Sensor:
    from autonomy.sensing.bearing import BearingConfig, BearingSensor

    return BearingSensor(BearingConfig(**given(spec), fov=field_of_regard(spec.fov)), sensor_id=name)


def build_box(spec: BoxSpec, name: str, buildings: Any = ()) -> Sensor:
    """The bounded-error box sensor (``buildings``: its shadow casters)."""
    from autonomy.sensing.box_sensor import BoxSensor, BoxSensorConfig

    return BoxSensor(BoxSensorConfig(**given(spec)), buildings=buildings, sensor_id=name)
