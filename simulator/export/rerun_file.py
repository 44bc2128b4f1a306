"""A run as a Rerun recording (``.rrd``), on the timeline ``sim_time`` (the run's clock, s).

Entity paths (ENU, z up, metres)::

    world/buildings                      static boxes
    world/roads                          static centre-lines, labelled with their road ids
    world/uavs/<id>, world/vehicles/<id> a transform per recorded sample; a static box of the body's size under it
    world/detections/<sensor>            one row per scan: radar / box points, bearing / camera rays
    world/tracks/<uav id>                one row per agent step: each track's 2-sigma ellipse, labelled with its id
    world/estimates/<uav id>             one row per agent step: the UAV's own estimate's 2-sigma ellipse
    world/fused_estimates/<uav id>       the same for its fused estimate
    world/links                          one row per record tick: the UAV pairs' links, coloured by delivery probability
    series/<who>/<stream>/<column>       scalars (every numeric column of the streams, the target track's p_target,
                                         the links' delivery probability)

Bulk data (transforms, scalars) goes in with ``send_columns``: one call per entity, not one per sample.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simulator.export.scene import Body, RunScene

__all__ = ["TIMELINE", "write_rrd"]

TIMELINE = "sim_time"
_APP_ID = "skytrack"
_BUILDING_RGB = (0.62, 0.62, 0.66)
_ROAD_RGB = (0.35, 0.35, 0.38)
_CAR_RGB = {"target": (0.86, 0.08, 0.24), "decoy": (0.8, 0.6, 0.1)}
_TRAFFIC_RGB = (0.7, 0.7, 0.7)
_CLUTTER_RGB = (0.6, 0.6, 0.6)


def _rgb(c: tuple[float, float, float], a: float = 1.0) -> list[int]:
    return [int(round(255 * v)) for v in (*c, a)]


def uav_rgb(u: int) -> tuple[float, float, float]:
    """The colour of UAV ``u`` (the replay's palette)."""
    from simulator.render.stage import UAV_COLORS

    return UAV_COLORS[u % len(UAV_COLORS)]


def write_rrd(scene: RunScene, out: Path) -> Path:
    """Write ``scene`` to the Rerun file ``out`` and return its path."""
    import rerun as rr

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    rec = rr.RecordingStream(_APP_ID, recording_id=scene.title)
    rec.save(out)
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    if scene.buildings:
        rec.log("world/buildings", rr.Boxes3D(
            centers=[b.center for b in scene.buildings], half_sizes=[b.size / 2 for b in scene.buildings],
            rotation_axis_angles=[rr.RotationAxisAngle(axis=[0, 0, 1], radians=b.yaw) for b in scene.buildings],
            colors=_rgb(_BUILDING_RGB), labels=[b.name for b in scene.buildings], show_labels=False,
            fill_mode="solid"), static=True)
    if scene.roads:  # one entity: a city's thousands of roads as entities of their own slow a viewer down
        strips = [np.c_[line[:, :2], np.full(len(line), 0.05)] for _r, line in scene.roads]
        rec.log("world/roads", rr.LineStrips3D(strips, labels=[rid for rid, _l in scene.roads], colors=_rgb(_ROAD_RGB),
                                               radii=0.5, show_labels=False), static=True)
    uav_index = {b.name: k for k, b in enumerate(b for b in scene.bodies if b.kind == "uav")}
    for body in scene.bodies:
        _log_body(rr, rec, body, uav_index)
    for scan in scene.detections:
        rec.set_time(TIMELINE, duration=scan.t)
        colors = [_rgb(_CLUTTER_RGB) if c else _rgb(uav_rgb(scan.uav)) for c in scan.clutter]
        path = f"world/detections/{scan.sensor}"
        if len(scan.points_W):
            rec.log(path, rr.Points3D(scan.points_W, colors=colors, radii=1.5))
        else:
            rec.log(path, rr.LineStrips3D(list(scan.rays_W), colors=colors, radii=0.2))
    names = {k: n for n, k in uav_index.items()}
    for layer, steps in scene.tracks.items():
        for step in steps:
            rec.set_time(TIMELINE, duration=step.t)
            z = 0.3 if layer == "tracks" else 0.4
            strips = [np.c_[np.vstack([e.outline, e.outline[:1]]), np.full(len(e.outline) + 1, z)]
                      for e in step.ellipses]
            rec.log(f"world/{layer}/{names.get(step.uav, f'uav{step.uav}')}", rr.LineStrips3D(
                strips, labels=[e.label for e in step.ellipses],
                radii=[0.6 if e.is_target else 0.25 for e in step.ellipses], colors=_rgb(uav_rgb(step.uav))))
    if scene.links:
        from simulator.render.world_marks import probability_rgb

        for sample in scene.links:
            rec.set_time(TIMELINE, duration=sample.t)
            rec.log("world/links", rr.LineStrips3D([[pa, pb] for _a, _b, pa, pb, _pr in sample.links],
                                                   colors=[_rgb(probability_rgb(pr)) for *_x, pr in sample.links],
                                                   labels=[f"{a}-{b} {pr:.2f}" for a, b, _pa, _pb, pr in sample.links],
                                                   radii=0.4))
    for s in scene.series:
        rec.send_columns("series/" + "/".join(s.path), indexes=[rr.TimeColumn(TIMELINE, duration=s.t)],
                         columns=rr.Scalars.columns(scalars=s.v))
    rec.flush()
    rec.disconnect()
    return out


def _log_body(rr: object, rec: object, body: Body, uav_index: dict[str, int]) -> None:
    group = "uavs" if body.kind == "uav" else "vehicles"
    path = f"world/{group}/{body.name}"
    colour = uav_rgb(uav_index[body.name]) if body.kind == "uav" else _CAR_RGB.get(body.role, _TRAFFIC_RGB)
    rec.send_columns(path, indexes=[rr.TimeColumn(TIMELINE, duration=body.t)],  # centred there, as in a replay
                     columns=rr.Transform3D.columns(translation=body.p_W, quaternion=body.q_WB))
    rec.log(f"{path}/body", rr.Boxes3D(half_sizes=[body.size / 2], colors=_rgb(colour), labels=[body.name],
                                       fill_mode="solid"), static=True)
