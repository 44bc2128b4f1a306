"""Helpers the builders share: world-file values onto a component's configuration dataclass, field by field."""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from typing import Any

from pydantic import BaseModel

__all__ = ["config_from", "given", "in_radians"]

SENSOR_COMMON = frozenset({"id", "type", "fov"})
"""Sensor-entry keys that are not fields of the sensor's configuration."""


def in_radians(values: dict[str, Any]) -> dict[str, Any]:
    """``values`` with each ``*_deg`` / ``*_deg_s`` key renamed to the field it feeds (suffix dropped) and its value
    converted to radians (per second)."""
    out: dict[str, Any] = {}
    for name, value in values.items():
        for suffix in ("_deg", "_deg_s"):
            if name.endswith(suffix):
                out[name[: -len(suffix)]] = math.radians(value)
                break
        else:
            out[name] = value
    return out


def given(spec: BaseModel, skip: frozenset[str] | set[str] = SENSOR_COMMON) -> dict[str, Any]:
    """Fields of a world-file entry that are set (None = use the component default), less ``skip``, in radians."""
    return in_radians({k: v for k, v in spec.model_dump(exclude_none=True).items() if k not in skip})


def _dataclass_of(hint: Any) -> type | None:
    """The dataclass type a field hint names (also inside ``X | None``), or None."""
    if dataclasses.is_dataclass(hint):
        return hint
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        for arg in typing.get_args(hint):
            if dataclasses.is_dataclass(arg):
                return arg
    return None


def config_from(cls: type, values: dict[str, Any], **context: Any) -> Any:
    """``cls(**context, **values)`` with nested dicts in ``values`` built into the dataclass their field names, and
    lists into tuples: the world file's settings onto the component's configuration by field name, renaming
    nothing."""
    hints = typing.get_type_hints(cls)
    kwargs: dict[str, Any] = {}
    for name, value in values.items():
        nested = _dataclass_of(hints.get(name))
        if nested is not None and isinstance(value, dict):
            value = config_from(nested, value)
        elif isinstance(value, list):
            value = tuple(value)
        kwargs[name] = value
    return cls(**context, **kwargs)
