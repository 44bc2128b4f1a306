"""JSON schemas of the Foxglove message types an MCAP export writes, under Foxglove's well-known schema names.

Foxglove recognises a channel's messages by the schema name (``foxglove.SceneUpdate``, ``foxglove.FrameTransform``)
with schema encoding ``jsonschema`` and message encoding ``json``. The schemas below declare the fields this export
fills, with the types and names of Foxglove's message reference (time as ``{sec, nsec}``, colours in [0, 1],
quaternions (x, y, z, w)); fields it leaves out are optional there too. The scalar series get a schema of their own
(``skytrack.Series``): an object of numbers, so plot panels can offer every field.
"""

from __future__ import annotations

from typing import Any

__all__ = ["FRAME_TRANSFORM", "SCENE_UPDATE", "series_schema"]

_NUMBER = {"type": "number"}


def _object(title: str, props: dict[str, Any], required: tuple[str, ...] = ()) -> dict[str, Any]:
    out: dict[str, Any] = {"title": title, "type": "object", "properties": props}
    if required:
        out["required"] = list(required)
    return out


def _xyz(title: str, keys: str = "xyz") -> dict[str, Any]:
    return _object(title, {k: _NUMBER for k in keys}, tuple(keys))


_TIME = _object("time", {"sec": {"type": "integer", "minimum": 0},
                         "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}, ("sec", "nsec"))
_DURATION = _object("duration", {"sec": {"type": "integer"},
                                 "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}})
_VECTOR3 = _xyz("foxglove.Vector3")
_POINT3 = _xyz("foxglove.Point3")
_QUATERNION = _xyz("foxglove.Quaternion", "xyzw")
_COLOR = _xyz("foxglove.Color", "rgba")
_POSE = _object("foxglove.Pose", {"position": _VECTOR3, "orientation": _QUATERNION}, ("position", "orientation"))


def _array(items: dict[str, Any]) -> dict[str, Any]:
    return {"type": "array", "items": items}


_CUBE = _object("foxglove.CubePrimitive", {"pose": _POSE, "size": _VECTOR3, "color": _COLOR},
                ("pose", "size", "color"))
_SPHERE = _object("foxglove.SpherePrimitive", {"pose": _POSE, "size": _VECTOR3, "color": _COLOR},
                  ("pose", "size", "color"))
_LINE = _object("foxglove.LinePrimitive", {
    "type": {"title": "foxglove.LineType", "oneOf": [{"title": "LINE_STRIP", "const": 0},
                                                     {"title": "LINE_LOOP", "const": 1},
                                                     {"title": "LINE_LIST", "const": 2}]},
    "pose": _POSE, "thickness": _NUMBER, "scale_invariant": {"type": "boolean"}, "points": _array(_POINT3),
    "color": _COLOR, "colors": _array(_COLOR), "indices": _array({"type": "integer", "minimum": 0})},
    ("type", "pose", "thickness", "scale_invariant", "points", "color"))
_TEXT = _object("foxglove.TextPrimitive", {
    "pose": _POSE, "billboard": {"type": "boolean"}, "font_size": _NUMBER, "scale_invariant": {"type": "boolean"},
    "color": _COLOR, "text": {"type": "string"}},
    ("pose", "billboard", "font_size", "scale_invariant", "color", "text"))
_KEY_VALUE = _object("foxglove.KeyValuePair", {"key": {"type": "string"}, "value": {"type": "string"}},
                     ("key", "value"))
_ENTITY = _object("foxglove.SceneEntity", {
    "timestamp": _TIME, "frame_id": {"type": "string"}, "id": {"type": "string"}, "lifetime": _DURATION,
    "frame_locked": {"type": "boolean"}, "metadata": _array(_KEY_VALUE), "cubes": _array(_CUBE),
    "spheres": _array(_SPHERE), "lines": _array(_LINE), "texts": _array(_TEXT)},
    ("timestamp", "frame_id", "id", "lifetime", "frame_locked"))
_DELETION = _object("foxglove.SceneEntityDeletion", {
    "timestamp": _TIME, "type": {"title": "foxglove.SceneEntityDeletionType",
                                 "oneOf": [{"title": "MATCHING_ID", "const": 0}, {"title": "ALL", "const": 1}]},
    "id": {"type": "string"}}, ("timestamp", "type", "id"))

SCENE_UPDATE: dict[str, Any] = _object("foxglove.SceneUpdate", {"deletions": _array(_DELETION),
                                                                "entities": _array(_ENTITY)})
"""``foxglove.SceneUpdate``: entities (boxes, spheres, lines, texts) to add or replace in a 3D scene."""

FRAME_TRANSFORM: dict[str, Any] = _object("foxglove.FrameTransform", {
    "timestamp": _TIME, "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"},
    "translation": _VECTOR3, "rotation": _QUATERNION},
    ("timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"))
"""``foxglove.FrameTransform``: the pose of a child frame in its parent frame at a time."""


def series_schema(columns: list[str]) -> dict[str, Any]:
    """``skytrack.Series``: the run time ``t`` (s) and the given numeric columns (null where not a number)."""
    props = {"t": {"type": "number", "description": "simulation time, s"}}
    props.update({c: {"type": ["number", "null"]} for c in columns})
    return _object("skytrack.Series", props, ("t",))
