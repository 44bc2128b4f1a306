"""A recorded run as functions of time: interpolated poses, the estimates held at each instant, the last radar scan.

Truth is recorded at ``sim.record_hz`` (10–20 Hz) and video frames fall between samples, so poses are interpolated:
positions linearly, attitudes by normalised linear interpolation of quaternions (``q = normalise((1 - a) q0 + a q1)``
after flipping ``q1`` to the hemisphere of ``q0``; within 1/20 s of a quadrotor's motion it differs from slerp by far
less than a pixel). Estimates are what a UAV believed, so they are *held* (the last valid sample at or before ``t``),
never interpolated. Times outside the record clamp to its ends. A multi-target tracker's tracks (the ``tracks``
stream) are held the same way: the live tracks of a UAV's last agent step at or before ``t``, found by a binary search
over the steps, which are indexed once (rows sorted by UAV and tick, one slice per step).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["EstimateTrack", "PoseTrack", "RadarScan", "Timeline", "TrackSet", "TrackSteps", "interp_positions",
           "nlerp_quaternions"]


def _bracket(t_samples: np.ndarray, t: float) -> tuple[int, int, float]:
    """Indices (i, j) and weight a in [0, 1] with t ≈ (1 - a) t_i + a t_j; clamped at the ends."""
    n = len(t_samples)
    if n == 1 or t <= t_samples[0]:
        return 0, 0, 0.0
    if t >= t_samples[-1]:
        return n - 1, n - 1, 0.0
    j = int(np.searchsorted(t_samples, t, side="right"))
    i = j - 1
    dt = t_samples[j] - t_samples[i]
    return i, j, float((t - t_samples[i]) / dt) if dt > 0 else 0.0


def interp_positions(t_samples: np.ndarray, p: np.ndarray, t: float) -> np.ndarray:
    """Linear interpolation of positions ``p`` (N, 3) sampled at increasing ``t_samples`` (N,) s, at time ``t`` s."""
    i, j, a = _bracket(t_samples, t)
    return (1.0 - a) * p[i] + a * p[j]


def nlerp_quaternions(q0: np.ndarray, q1: np.ndarray, a: float) -> np.ndarray:
    """Normalised linear interpolation between unit quaternions (x, y, z, w), along the shorter arc."""
    q1 = -q1 if float(np.dot(q0, q1)) < 0.0 else q1
    q = (1.0 - a) * q0 + a * q1
    return q / np.linalg.norm(q)


@dataclass(frozen=True)
class PoseTrack:
    """One body's recorded poses: times (N,) s, positions p_W (N, 3) m, attitudes q_WB (N, 4) (x, y, z, w)."""

    t: np.ndarray
    p_W: np.ndarray
    q_WB: np.ndarray

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(p_W (3,), q_WB (4,)) at time ``t`` s."""
        i, j, a = _bracket(self.t, t)
        return (1.0 - a) * self.p_W[i] + a * self.p_W[j], nlerp_quaternions(self.q_WB[i], self.q_WB[j], a)

    def trail(self, t: float, span: float) -> np.ndarray:
        """Positions (K, 3) from ``t - span`` to ``t`` s: the recorded samples in between plus the pose at ``t``."""
        keep = (self.t > t - span) & (self.t < t)
        return np.vstack([self.p_W[keep], self.at(t)[0][None]])


HIDDEN_Z = -100.0
"""Height (m) at which a replay keeps a traffic source's free slot (no vehicle): below the ground, out of sight."""


def hidden_when_free(d: dict[str, np.ndarray]) -> np.ndarray:
    """Positions (N, 3) of one vehicle's ``vehicle_truth`` rows, at :data:`HIDDEN_Z` where the slot held no vehicle
    (``active`` false; records without the column: always on the road)."""
    p = np.c_[d["x"], d["y"], d["z"]].astype(float)
    if "active" in d:
        p[~np.asarray(d["active"], dtype=bool), 2] = HIDDEN_Z
    return p


@dataclass(frozen=True)
class EstimateTrack:
    """One UAV's target estimates: times (N,) s, positions (N, 2) m, covariances (N, 2, 2) m², validity (N,)."""

    t: np.ndarray
    xy: np.ndarray
    P_xy: np.ndarray
    valid: np.ndarray
    road: np.ndarray | None = None

    def road_at(self, t: float) -> str:
        """Road the estimator held the target on at the last estimate at or before ``t`` s ("" if none)."""
        k = int(np.searchsorted(self.t, t + 1e-9, side="right")) - 1
        if self.road is None or k < 0 or not self.valid[k]:
            return ""
        return str(self.road[k])

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        """(xy (2,), P_xy (2, 2)) of the last valid estimate at or before ``t`` s, or None if there is none yet."""
        k = int(np.searchsorted(self.t, t + 1e-9, side="right")) - 1
        if k < 0 or not self.valid[k]:
            return None
        return self.xy[k], self.P_xy[k]


@dataclass(frozen=True)
class TrackSet:
    """The live tracks of one UAV at one agent step: ids (K,), positions xy (K, 2) m, ``p_target`` (K,) and
    whether the UAV takes each for the target (K,) bool."""

    t: float
    track: np.ndarray
    xy: np.ndarray
    p_target: np.ndarray
    is_target: np.ndarray


class TrackSteps:
    """One UAV's ``tracks`` rows, indexed by agent step once: :meth:`at` returns a step's rows as array slices.

    Parameters
    ----------
    d : dict[str, np.ndarray]
        The UAV's rows of the ``tracks`` stream (any order).
    """

    def __init__(self, d: dict[str, np.ndarray]) -> None:
        order = np.lexsort((d["track"], d["tick"]))
        tick = d["tick"][order]
        starts = np.flatnonzero(np.r_[True, tick[1:] != tick[:-1]])
        self.t = d["t"][order][starts]
        self._bounds = np.r_[starts, len(tick)]
        self._track = d["track"][order].astype(np.int64)
        self._xy = np.c_[d["x"], d["y"]][order]
        self._p = d["p_target"][order].astype(float)
        self._target = d["is_target"][order].astype(bool)

    def at(self, t: float) -> TrackSet | None:
        """The tracks of the last step at or before ``t`` s (None before the first step)."""
        k = int(np.searchsorted(self.t, t + 1e-9, side="right")) - 1
        if k < 0:
            return None
        a, b = self._bounds[k], self._bounds[k + 1]
        return TrackSet(float(self.t[k]), self._track[a:b], self._xy[a:b], self._p[a:b], self._target[a:b])


@dataclass(frozen=True)
class RadarScan:
    """One radar scan: measurement time s, sensor name, carrying UAV, points p_W (K, 3) m, clutter flags (K,)."""

    t_meas: float
    sensor: str
    uav: int
    points_W: np.ndarray
    clutter: np.ndarray


def _group(stream: dict[str, np.ndarray], key: str) -> dict[int, dict[str, np.ndarray]]:
    out = {}
    for value in np.unique(stream[key]):
        mask = stream[key] == value
        order = np.argsort(stream["t"][mask], kind="stable")
        out[int(value)] = {k: v[mask][order] for k, v in stream.items()}
    return out


class Timeline:
    """The streams of a run directory, queried by time.

    Parameters
    ----------
    streams : dict[str, dict[str, np.ndarray]]
        ``RunRecord.streams``: ``uav_truth`` is required; ``vehicle_truth`` (absent in worlds without cars),
        ``estimates``, ``tracks`` and ``detections`` are optional.
    scan_hold : float
        A radar scan is shown for at most this long after its measurement time, s.
    """

    def __init__(self, streams: dict[str, dict[str, np.ndarray]], scan_hold: float = 1.0) -> None:
        if "uav_truth" not in streams or not len(streams["uav_truth"].get("t", ())):
            raise ValueError("a replay needs the 'uav_truth' stream, which the run directory lacks or is empty")
        self.scan_hold = float(scan_hold)
        self.uavs = {u: PoseTrack(d["t"], np.c_[d["x"], d["y"], d["z"]], np.c_[d["qx"], d["qy"], d["qz"], d["qw"]])
                     for u, d in _group(streams["uav_truth"], "uav").items()}
        self.vehicles = {}
        cars = streams.get("vehicle_truth") or {}
        for v, d in (_group(cars, "vehicle").items() if len(cars.get("t", ())) else ()):
            yaw = np.unwrap(d["yaw"])
            q = np.c_[np.zeros((len(yaw), 2)), np.sin(yaw / 2), np.cos(yaw / 2)]
            self.vehicles[v] = PoseTrack(d["t"], hidden_when_free(d), q)
        self.estimates: dict[int, EstimateTrack] = {}
        if "estimates" in streams and len(streams["estimates"].get("t", ())):
            for u, d in _group(streams["estimates"], "uav").items():
                P = np.stack([np.c_[d["pxx"], d["pxy"]], np.c_[d["pxy"], d["pyy"]]], axis=1)
                self.estimates[u] = EstimateTrack(d["t"], np.c_[d["x"], d["y"]], P, d["valid"].astype(bool),
                                                  d.get("road"))
        tracks = streams.get("tracks") or {}
        self.tracks: dict[int, TrackSteps] = ({u: TrackSteps(d) for u, d in _group(tracks, "uav").items()}
                                              if len(tracks.get("t", ())) else {})
        self._det = None
        det = streams.get("detections")
        if det is not None and len(det.get("t_meas", ())):
            radar = det["kind"] == "radar"
            self._det = {k: v[radar] for k, v in det.items()}
        ts = [tr.t for tr in (*self.uavs.values(), *self.vehicles.values())]
        self.t_start = float(max(t[0] for t in ts))
        self.t_end = float(min(t[-1] for t in ts))

    def radar_scans(self, t: float) -> list[RadarScan]:
        """The latest scan of each radar measured at or before ``t`` s (and within ``scan_hold``), as world points.

        A detection ``z = [r, az, el, ...]`` of UAV ``u`` lies at ``p_u(t_meas) + r [cos el cos az, cos el sin az,
        sin el]``.
        """
        d = self._det
        if d is None:
            return []
        scans = []
        for sensor in np.unique(d["sensor"]):
            m = (d["sensor"] == sensor) & (d["t_meas"] <= t + 1e-9) & (d["t_meas"] > t - self.scan_hold)
            if not m.any():
                continue
            t_last = d["t_meas"][m].max()
            m &= d["t_meas"] == t_last
            u = int(d["uav"][m][0])
            if u not in self.uavs:
                continue
            p_s = self.uavs[u].at(float(t_last))[0]
            r, az, el = d["z0"][m], d["z1"][m], d["z2"][m]
            pts = p_s + r[:, None] * np.c_[np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)]
            scans.append(RadarScan(float(t_last), str(sensor), u, pts, d["truth_id"][m] < 0))
        return scans
