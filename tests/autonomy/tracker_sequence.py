"""A recorded detection sequence for the trackers, and a digest of everything a tracker makes of it.

The truth: a car driving east on a straight road at 10 m/s, turning off it at 12 s (ω = 0.08 rad/s for 10 s); no
detections for 22–33 s (the track is lost after ``lost_after_s``); at 36 s the car is 400 m from where it was (the
track rejects every fix and is dropped as diverged). Sensors (scans at 2 Hz): two radars ``[r, az, el]`` and
``[r, az]`` with Poisson clutter, a camera and a passive bearing sensor, and a box sensor every fourth scan; for the
first 3 s only the bearings.
"""

from __future__ import annotations

import hashlib

import numpy as np

from autonomy.estimation.scif import add_information
from autonomy.sensing.measurement import Detection
from tests.numeric_record import summarise
from worlds.roads.network import RoadNetwork

SCAN_DT = 0.5  # s
DURATION = 45.0  # s


def road_network() -> RoadNetwork:
    """The straight street the car starts on."""
    return RoadNetwork.from_spec({"nodes": {"a": [0.0, 0.0], "b": [3000.0, 0.0]},
                                  "streets": [{"id": "main", "nodes": ["a", "b"]}]})


def truth(t: float) -> np.ndarray:
    """The car's ground position (m) at ``t`` (s)."""
    if t <= 12.0:
        return np.array([100.0 + 10.0 * t, 0.0])
    w, tt = 0.08, min(t, 22.0) - 12.0
    p = np.array([220.0 + 10.0 * np.sin(w * tt) / w, 10.0 * (1.0 - np.cos(w * tt)) / w])
    heading = w * tt
    p = p + 10.0 * max(t - 22.0, 0.0) * np.array([np.cos(heading), np.sin(heading)])
    return p + (np.array([400.0, -300.0]) if t >= 36.0 else 0.0)


def _radar(rng, t, p_s, sig, clutter_rate, sensor_id) -> list[Detection]:
    R = np.diag(np.square(sig))
    m = len(sig)
    out = []
    d = np.append(truth(t), 0.0) - p_s
    rho = np.hypot(d[0], d[1])
    z_true = [np.array([np.linalg.norm(d), np.arctan2(d[1], d[0]), np.arctan2(d[2], rho)])[:m]]
    if rng.uniform() > 0.9:
        z_true = []
    for _ in range(rng.poisson(clutter_rate)):
        r = rng.uniform(150.0, 2000.0)
        z_true.append(np.array([r, rng.uniform(-np.pi, np.pi), -np.arcsin(p_s[2] / r)])[:m])
    for z in z_true:
        z = z + rng.standard_normal(m) * np.asarray(sig)
        out.append(Detection(z=z, R=R, t_meas=t, t_arrival=t, sensor_id=sensor_id, p_sensor_W=p_s, kind="radar"))
    return out


def _bearing(rng, t, p_s, sigma, sensor_id, kind) -> list[Detection]:
    d = truth(t) - p_s[:2]
    z = np.array([np.arctan2(d[1], d[0]) + sigma * rng.standard_normal()])
    return [Detection(z=z, R=np.array([[sigma**2]]), t_meas=t, t_arrival=t, sensor_id=sensor_id, p_sensor_W=p_s,
                      kind=kind)]


def sequence(seed: int) -> list[tuple[float, list[Detection]]]:
    """``(step time, detections taken since the last step, in t_meas order)`` at every scan (s)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(int(DURATION / SCAN_DT) + 1):
        t = k * SCAN_DT
        dets: list[Detection] = []
        a = 0.05 * t
        p1 = np.array([600.0 * np.cos(a), 600.0 * np.sin(a) - 300.0, 120.0])
        p2 = np.array([500.0 - 400.0 * np.cos(a), 500.0, 100.0])
        if not 22.0 <= t < 34.0:
            dets += _bearing(rng, t, p1, np.deg2rad(0.5), "uav1/camera", "camera")
            dets += _bearing(rng, t, p2, np.deg2rad(1.0), "uav2/bearing", "bearing")
            if t >= 3.0:
                dets += _radar(rng, t, p1, (10.0, np.deg2rad(1.0), np.deg2rad(1.0)), 1.5, "uav1/radar")
                dets += _radar(rng, t, p2, (20.0, np.deg2rad(2.0)), 1.0, "uav2/radar")
                if k % 4 == 0:
                    b = 5.0
                    z = truth(t) + rng.uniform(-b, b, 2)
                    dets.append(Detection(z=z, R=np.eye(2) * b**2 / 3.0, t_meas=t, t_arrival=t, sensor_id="uav3/box",
                                          p_sensor_W=np.array([*truth(t), 80.0]), kind="box",
                                          bound=np.array([b, b])))
        out.append((t, dets))
    return out


def digest(tracker, seed: int, information: bool = False) -> str:
    """SHA-256 (20 hex digits) of every estimate ``tracker`` makes of :func:`sequence` ``(seed)`` (time, position,
    velocity, covariance, the road it holds the car on) and of its counters at the end; with ``information``, the
    steps go through ``step_information`` and the local update of
    :class:`~autonomy.fusion.base_station.InformationReporter`."""
    return record(tracker, seed, information)[0]


def record(tracker, seed: int, information: bool = False) -> tuple[str, dict[str, list]]:
    """:func:`digest` of what ``tracker`` makes of the sequence, and a summary of it for another machine
    (:mod:`tests.numeric_record`): the estimates' numbers, which steps had one, the roads held and the counters."""
    h = hashlib.sha256()
    rows, present, roads = [], [], []
    for t, dets in sequence(seed):
        if information:
            info = tracker.step_information(t, dets)
            if info is not None and info.contribution is not None:
                tracker.set_information(add_information(info.prior, info.contribution))
            est = None if info is None else tracker.current_estimate()
        else:
            est = tracker.step(t, dets)
        if est is None:
            h.update(b"none")
            present.append(0)
        else:
            parts = [np.ascontiguousarray(a, dtype=float) for a in (np.float64(est.t), est.p_W, est.v_W, est.P)]
            for a in parts:
                h.update(a.tobytes())
            rows.append(np.concatenate([a.ravel() for a in parts]))
            present.append(1)
        road = repr((getattr(tracker, "road_id", None), getattr(tracker, "on_road", None)))
        h.update(road.encode())
        roads.append(road)
    counters = repr((tracker.updates, tracker.initiations, tracker.gated_out, tracker.dropped_diverged,
                     sorted(tracker.used_by_sensor.items())))
    h.update(counters.encode())
    values = {"estimates": summarise(np.array(rows) if rows else np.zeros((0,))), "present": summarise(present),
              "roads": summarise(np.array(roads)), "counters": ["text", counters]}
    return h.hexdigest()[:20], values
