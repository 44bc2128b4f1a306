"""A run as an MCAP file that Foxglove opens as a 3D scene and plots, messages in JSON on the run's clock.

Topics (frame ``world``: ENU, z up, metres; a message's log and publish time is its simulation time in ns)::

    /scene/static           foxglove.SceneUpdate     once: buildings (cubes), roads (line strips)
    /tf                     foxglove.FrameTransform  every body's pose per recorded sample (child frame = its id)
    /scene/bodies           foxglove.SceneUpdate     once: a box per body in its own frame, frame-locked to /tf
    /scene/detections       foxglove.SceneUpdate     per scan: radar / box points (spheres), bearing rays (lines)
    /scene/tracks           foxglove.SceneUpdate     per UAV agent step: its tracks' 2-sigma ellipses and ids
    /scene/estimates        foxglove.SceneUpdate     per UAV agent step: its own estimate's ellipse
    /scene/fused_estimates  foxglove.SceneUpdate     per UAV agent step: its fused estimate's ellipse
    /scene/links            foxglove.SceneUpdate     per record tick: the radio links, coloured by delivery probability
    /series/<who>/<stream>  skytrack.Series          per sample: ``t`` and the stream's numeric columns for that
                                                     UAV, vehicle or link (plain JSON objects, for the Plot panel)
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from simulator.export.foxglove_schemas import FRAME_TRANSFORM, SCENE_UPDATE, series_schema
from simulator.export.rerun_file import uav_rgb
from simulator.export.scene import Body, RunScene, Series

__all__ = ["WORLD_FRAME", "write_mcap"]

WORLD_FRAME = "world"
_SCAN_HOLD_NS = 1_000_000_000  # a scan stays drawn for 1 s, as in a replay
_BUILDING = (0.62, 0.62, 0.66, 0.9)
_ROAD = (0.35, 0.35, 0.38, 1.0)
_CAR = {"target": (0.86, 0.08, 0.24, 1.0), "decoy": (0.8, 0.6, 0.1, 1.0)}
_TRAFFIC = (0.7, 0.7, 0.7, 1.0)
_CLUTTER = (0.6, 0.6, 0.6, 1.0)
_IDENTITY = {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}


def _ns(t: float) -> int:
    return int(round(float(t) * 1e9))


def _time(t: float) -> dict[str, int]:
    ns = max(_ns(t), 0)
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _color(c: tuple[float, ...]) -> dict[str, float]:
    r, g, b, *a = c
    return {"r": float(r), "g": float(g), "b": float(b), "a": float(a[0]) if a else 1.0}


def _xyz(p: Any) -> dict[str, float]:
    return {"x": float(p[0]), "y": float(p[1]), "z": float(p[2])}


def _pose(p: Any, yaw: float = 0.0) -> dict[str, Any]:
    return {"position": _xyz(p), "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}}


def _entity(t: float, eid: str, frame: str = WORLD_FRAME, lifetime_ns: int = 0, locked: bool = False,
            **prims: Any) -> dict[str, Any]:
    return {"timestamp": _time(t), "frame_id": frame, "id": eid,
            "lifetime": {"sec": lifetime_ns // 1_000_000_000, "nsec": lifetime_ns % 1_000_000_000},
            "frame_locked": locked, "metadata": [], **prims}


def _line(points: Any, color: tuple[float, ...], kind: int = 0, thickness: float = 0.5,
          colors: list[tuple[float, ...]] | None = None) -> dict[str, Any]:
    return {"type": kind, "pose": _IDENTITY, "thickness": thickness, "scale_invariant": False,
            "points": [_xyz(p) for p in points], "color": _color(color),
            "colors": [_color(c) for c in colors or []], "indices": []}


class _Out:
    """An MCAP writer whose channels are registered on first use (schema per name, channel per topic)."""

    def __init__(self, f: Any) -> None:
        from mcap.writer import Writer

        self.writer = Writer(f)
        self.writer.start(profile="", library="skytrack")
        self.schemas: dict[str, int] = {}
        self.channels: dict[str, int] = {}

    def write(self, topic: str, schema: dict[str, Any], t: float, message: dict[str, Any]) -> None:
        if topic not in self.channels:
            key = json.dumps(schema, sort_keys=True)
            if key not in self.schemas:
                self.schemas[key] = self.writer.register_schema(name=schema["title"], encoding="jsonschema",
                                                                data=key.encode())
            self.channels[topic] = self.writer.register_channel(topic=topic, message_encoding="json",
                                                                schema_id=self.schemas[key])
        ns = max(_ns(t), 0)
        self.writer.add_message(self.channels[topic], log_time=ns, publish_time=ns,
                                data=json.dumps(message, allow_nan=False).encode())


def write_mcap(scene: RunScene, out: Path) -> Path:
    """Write ``scene`` to the MCAP file ``out`` and return its path."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    t0 = scene.t_start
    with open(out, "wb") as f:
        w = _Out(f)
        _static(w, scene, t0)
        uav_index = {b.name: k for k, b in enumerate(b for b in scene.bodies if b.kind == "uav")}
        _bodies(w, scene.bodies, uav_index, t0)
        names = {k: n for n, k in uav_index.items()}
        for scan in scene.detections:
            colors = [_CLUTTER if c else uav_rgb(scan.uav) for c in scan.clutter]
            prims = ({"spheres": [{"pose": _pose(p), "size": _xyz((3.0, 3.0, 3.0)), "color": _color(c)}
                                  for p, c in zip(scan.points_W, colors, strict=True)]} if len(scan.points_W) else
                     {"lines": [_line(scan.rays_W.reshape(-1, 3), uav_rgb(scan.uav), kind=2, thickness=0.3,
                                      colors=[c for c in colors for _ in (0, 1)])]})
            w.write("/scene/detections", SCENE_UPDATE, scan.t,
                    {"deletions": [], "entities": [_entity(scan.t, scan.sensor, lifetime_ns=_SCAN_HOLD_NS, **prims)]})
        for layer, steps in scene.tracks.items():
            for step in steps:
                who = names.get(step.uav, f"uav{step.uav}")
                z = 0.3 if layer == "tracks" else 0.4
                lines = [_line(np.c_[e.outline, np.full(len(e.outline), z)], uav_rgb(step.uav), kind=1,
                               thickness=0.8 if e.is_target else 0.3) for e in step.ellipses]
                texts = [{"pose": _pose((*e.xy, z + 2.0)), "billboard": True, "font_size": 12.0,
                          "scale_invariant": True, "color": _color(uav_rgb(step.uav)), "text": e.label}
                         for e in step.ellipses]
                w.write(f"/scene/{layer}", SCENE_UPDATE, step.t, {"deletions": [], "entities": [
                    _entity(step.t, f"{layer}/{who}", lines=lines, texts=texts)]})
        _links(w, scene)
        _series(w, scene.series)
        w.writer.finish()
    return out


def _static(w: _Out, scene: RunScene, t0: float) -> None:
    entities = []
    if scene.buildings:
        entities.append(_entity(t0, "buildings", cubes=[{"pose": _pose(b.center, b.yaw), "size": _xyz(b.size),
                                                         "color": _color(_BUILDING)} for b in scene.buildings]))
    for rid, line in scene.roads:
        entities.append(_entity(t0, f"road/{rid}", lines=[_line(np.c_[line[:, :2], np.full(len(line), 0.05)],
                                                                _ROAD, thickness=1.0)]))
    if entities:
        w.write("/scene/static", SCENE_UPDATE, t0, {"deletions": [], "entities": entities})


def _bodies(w: _Out, bodies: list[Body], uav_index: dict[str, int], t0: float) -> None:
    for body in bodies:
        for t, p, q in zip(body.t, body.p_W, body.q_WB, strict=True):
            w.write("/tf", FRAME_TRANSFORM, t, {
                "timestamp": _time(t), "parent_frame_id": WORLD_FRAME, "child_frame_id": body.name,
                "translation": _xyz(p), "rotation": {"x": float(q[0]), "y": float(q[1]), "z": float(q[2]),
                                                     "w": float(q[3])}})
    if bodies:
        entities = [_entity(t0, body.name, frame=body.name, locked=True, cubes=[{
            "pose": _IDENTITY, "size": _xyz(body.size),
            "color": _color(uav_rgb(uav_index[body.name]) if body.kind == "uav" else _CAR.get(body.role, _TRAFFIC))}],
            texts=[{"pose": _pose((0.0, 0.0, body.size[2] + 2.0)), "billboard": True, "font_size": 12.0,
                    "scale_invariant": True, "color": _color((1.0, 1.0, 1.0)), "text": body.name}])
            for body in bodies]
        w.write("/scene/bodies", SCENE_UPDATE, t0, {"deletions": [], "entities": entities})


def _links(w: _Out, scene: RunScene) -> None:
    if not scene.links:
        return
    from simulator.render.world_marks import probability_rgb

    for sample in scene.links:
        pts = [p for _a, _b, pa, pb, _pr in sample.links for p in (pa, pb)]
        colors = [probability_rgb(pr) for *_x, pr in sample.links for _ in (0, 1)]
        meta = [{"key": f"{a}-{b}", "value": f"{pr:.3f}"} for a, b, _pa, _pb, pr in sample.links]
        ent = _entity(sample.t, "links", lines=[_line(pts, (1.0, 1.0, 1.0), kind=2, thickness=0.6, colors=colors)])
        ent["metadata"] = meta
        w.write("/scene/links", SCENE_UPDATE, sample.t, {"deletions": [], "entities": [ent]})


def _series(w: _Out, series: list[Series]) -> None:
    """One topic per (who, stream): a message per sample holding every column of it (NaN written as null)."""
    groups: dict[tuple[str, ...], list[Series]] = {}
    for s in series:
        groups.setdefault(s.path[:-1], []).append(s)
    for key, members in groups.items():
        schema = series_schema([s.path[-1] for s in members])
        t = members[0].t
        for k in range(len(t)):
            msg: dict[str, Any] = {"t": float(t[k])}
            for s in members:
                v = float(s.v[k])
                msg[s.path[-1]] = v if math.isfinite(v) else None
            w.write("/series/" + "/".join(key), schema, float(t[k]), msg)
