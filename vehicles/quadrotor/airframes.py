"""Look-up of the shipped airframes (one parameter module per airframe in :mod:`vehicles.airframes`)."""

from __future__ import annotations

import importlib

from vehicles.quadrotor.params import QuadrotorParams

__all__ = ["load_airframe", "list_airframes"]

_AIRFRAMES = ("survey_quad", "crazyflie")


def list_airframes() -> list[str]:
    """Names accepted by :func:`load_airframe`."""
    return list(_AIRFRAMES)


def load_airframe(name: str) -> QuadrotorParams:
    """Parameters of airframe ``name`` (the ``PARAMS`` of ``vehicles/airframes/<name>.py``).

    Raises
    ------
    KeyError
        If ``name`` is not a shipped airframe; the message lists the known names.
    """
    if name not in _AIRFRAMES:
        raise KeyError(f"unknown airframe {name!r}; known airframes: {', '.join(_AIRFRAMES)}")
    module = importlib.import_module(f"vehicles.airframes.{name}")
    params = module.PARAMS
    if not isinstance(params, QuadrotorParams):
        raise TypeError(f"vehicles.airframes.{name}.PARAMS is {type(params).__name__}, expected QuadrotorParams")
    return params
