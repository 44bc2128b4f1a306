"""A synthetic run directory with a ``tracks`` stream (no simulation): two cars, two hovering UAVs, and trackers
whose target track changes at known times.

Car 0 (the designated target) drives east along y = 0 at 10 m/s, car 1 (traffic) west along y = 20 m from x = 100 m.
Agent steps at 2 Hz, t = 0, 0.5, ..., 9.5 s.

UAV 0: track 1 on car 0 and taken for the target until t < 4 s; at 4 s none is taken; track 3 on car 0 from 4.5 s,
taken from 5 s, except at 7 and 7.5 s when track 2 (on car 1 all run) is taken: ID switches at 5, 7 and 8 s.
UAV 1: track 10 on car 0 taken all run, track 11 on car 1; at 3 s both are flagged, 10 with the larger ``p_target``:
no ID switch.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from simulator.record import RunRecorder
from simulator.streams import STREAMS

PHYSICS_HZ = 240
STEPS = np.arange(0.0, 10.0, 0.5)
SWITCHES = {0: [5.0, 7.0, 8.0], 1: []}


def car_xy(vehicle: int, t: float) -> tuple[float, float]:
    return (10.0 * t, 0.0) if vehicle == 0 else (100.0 - 10.0 * t, 20.0)


def uav0_rows(t: float) -> list[tuple[int, int, float, bool]]:
    """(track, car, p_target, is_target) of UAV 0 at step ``t``."""
    rows = [(2, 1, 0.6 if t in (7.0, 7.5) else 0.1, t in (7.0, 7.5))]
    if t < 4.0:
        rows.append((1, 0, 0.9, True))
    elif t >= 4.5:
        rows.append((3, 0, 0.3 if t == 4.5 else 0.4 if t in (7.0, 7.5) else 0.8, t >= 5.0 and t not in (7.0, 7.5)))
    return rows


def uav1_rows(t: float) -> list[tuple[int, int, float, bool]]:
    return [(10, 0, 0.7 if t == 3.0 else 0.95, True), (11, 1, 0.5 if t == 3.0 else 0.05, t == 3.0)]


def write_track_run(out: Path, with_tracks: bool = True) -> Path:
    """Write the run directory ``out`` and return it."""
    rec = RunRecorder(out, STREAMS)
    for t in np.arange(0.0, 10.0, 0.1):
        t = round(float(t), 3)
        for v in (0, 1):
            x, y = car_xy(v, t)
            rec.append("vehicle_truth", **STREAMS["vehicle_truth"].blank(
                tick=int(round(t * PHYSICS_HZ)), t=t, vehicle=v, x=x, y=y, z=0.7, yaw=0.0 if v == 0 else np.pi,
                speed=10.0, road="r0" if v == 0 else "r1", s=0.0, lateral=0.0))
        for u in (0, 1):
            rec.append("uav_truth", **STREAMS["uav_truth"].blank(
                tick=int(round(t * PHYSICS_HZ)), t=t, uav=u, x=50.0, y=-150.0 + 300.0 * u, z=60.0, qx=0.0, qy=0.0,
                qz=0.0, qw=1.0, vx=0.0, vy=0.0, vz=0.0))
    for t in STEPS:
        t = float(t)
        tick = int(round(t * PHYSICS_HZ))
        for u, rows in ((0, uav0_rows(t)), (1, uav1_rows(t))):
            x0, y0 = car_xy(0, t)
            rec.append("estimates", **STREAMS["estimates"].blank(
                tick=tick, t=t, uav=u, valid=True, x=x0 + 2.0, y=y0, vx=10.0, vy=0.0, pxx=4.0, pxy=0.0, pyy=4.0,
                pvxvx=1.0, pvyvy=1.0, detections=2, road=""))
            if not with_tracks:
                continue
            for track, car, p, is_target in rows:
                x, y = car_xy(car, t)
                rec.append("tracks", **STREAMS["tracks"].blank(
                    tick=tick, t=t, uav=u, track=track, x=x + 1.0, y=y + 0.5, vx=10.0, vy=0.0, pxx=4.0, pxy=0.0,
                    pyy=4.0, p_target=p, evidence=np.log(p / (1 - p)), confirmed=True, is_target=is_target))
    rec.close()
    (out / "metrics.json").write_text(json.dumps({"target_index": 0}))
    (out / "run.json").write_text(json.dumps({"world": "synthetic_tracks", "seed": 1}))
    return out
