"""Names of the shipped vehicle types a world file may choose, declared where the world schema can see them.

``worlds`` imports nothing of ``vehicles``, so the loader cannot ask the vehicle packages what they ship; these tuples
name them instead, and ``tests/worlds/test_catalog.py`` fails when they differ from what ``vehicles`` can load
(:func:`vehicles.car.params.list_cars`, :func:`vehicles.quadrotor.airframes.list_airframes`).
"""

from __future__ import annotations

__all__ = ["AIRFRAMES", "CAR_TYPES"]

CAR_TYPES: tuple[str, ...] = ("sedan", "van")
"""Car parameter files of ``vehicles/cars`` (``ground_vehicles[i].type``)."""

AIRFRAMES: tuple[str, ...] = ("crazyflie", "survey_quad")
"""Airframe parameter files of ``vehicles/airframes`` (``uavs[i].airframe``)."""
