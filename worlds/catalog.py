"""Names of the shipped vehicle types a world file may choose, declared where the world schema can see them.

``worlds`` imports nothing of ``vehicles``, so the loader cannot ask the vehicle packages what they ship; these tuples
name them instead, and ``tests/worlds/test_catalog.py`` fails when they differ from what ``vehicles`` can load
(:func:`vehicles.car.params.list_cars`, :func:`vehicles.quadrotor.airframes.list_airframes`).
"""

from __future__ import annotations

__all__ = ["AIRFRAMES", "CAR_ATTRIBUTES", "CAR_COLOURS", "CAR_TYPES", "LENGTH_CLASSES", "LENGTH_SPLIT_M",
           "car_classes"]

CAR_TYPES: tuple[str, ...] = ("sedan", "van")
"""Car parameter files of ``vehicles/cars`` (``ground_vehicles[i].type``)."""

AIRFRAMES: tuple[str, ...] = ("crazyflie", "survey_quad")
"""Airframe parameter files of ``vehicles/airframes`` (``uavs[i].airframe``)."""

CAR_COLOURS: tuple[str, ...] = ("white", "black", "silver", "red", "blue", "green", "yellow")
"""Paint colours a car may have (``ground_vehicles[i].colour``): the classes of a camera's colour reading."""

LENGTH_SPLIT_M = 5.2
"""m: the car length at which the length class turns from ``short`` to ``long``."""

LENGTH_CLASSES: tuple[str, ...] = ("short", "long")
"""Length classes a radar reads from a car's range profile: ``short`` under 5.2 m, ``long`` from 5.2 m."""

_CAR_LENGTH_CLASS = {"sedan": "short", "van": "long"}  # sedan 4.77 m, van 5.93 m (vehicles/cars); test_catalog checks

CAR_ATTRIBUTES: dict[str, tuple[str, ...]] = {"colour": CAR_COLOURS, "body": CAR_TYPES, "length": LENGTH_CLASSES}
"""The class attributes of a car a sensor may read, each with its list of classes (index = class id): the keys of
``TargetTruth.attributes`` and ``ClassMeasurement.attribute``."""


def car_classes(car_type: str, colour: str) -> dict[str, int]:
    """The class index of each attribute of a car of type ``car_type`` painted ``colour``."""
    return {"colour": CAR_COLOURS.index(colour), "body": CAR_TYPES.index(car_type),
            "length": LENGTH_CLASSES.index(_CAR_LENGTH_CLASS[car_type])}
