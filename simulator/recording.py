"""The record side of the tick: truth, detections and agent rows in their streams (:mod:`simulator.streams`),
collision checks and events."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np
import pybullet as p

from autonomy.agent import AgentOutput, TargetEstimator
from autonomy.diagnostics import CountsSensorUse, HoldsRoad, HoldsTracks
from interfaces.setpoints import UnicycleSetpoint, VelocitySetpoint
from interfaces.state import TargetEstimate, TrackReport
from autonomy.sensing.measurement import SensorOutput
from simulator.comms import Outage
from simulator.record import RunRecorder
from simulator.scene import Scene
from simulator.streams import STREAMS
from simulator.truth import GroundFleet, UavFleet

__all__ = ["ContactSource", "PybulletContacts", "Recording", "estimate_row", "track_columns"]

_ESTIMATES, _COMMANDS, _TRACKS = STREAMS["estimates"], STREAMS["commands"], STREAMS["tracks"]


class ContactSource(Protocol):
    """Which bodies touch the UAVs now, and what each body is."""

    def contacts(self) -> set[tuple[int, int]]:
        """(UAV index, other body id) of every contact of a UAV now."""
        ...

    def body_name(self, body: int) -> str:
        """What ``body`` is: ``ground``, ``building``, ``uav <id>``, ``vehicle <id>``."""
        ...


class PybulletContacts:
    """:class:`ContactSource` of a PyBullet scene."""

    def __init__(self, scene: Scene, quads: UavFleet, cars: GroundFleet | None, uav_ids: Sequence[str],
                 car_ids: Sequence[str]) -> None:
        self.client = scene.client
        self.quads = quads
        names = {scene.ground_id: "ground"}
        names.update({b: "building" for b in scene.building_ids})
        names.update({int(b): f"uav {u}" for b, u in zip(quads.body_ids, uav_ids, strict=True)})
        if cars is not None:
            names.update({int(b): f"vehicle {c}" for b, c in zip(cars.body_ids, car_ids, strict=True)})
        self.names = names

    def contacts(self) -> set[tuple[int, int]]:
        return {(i, c[2]) for i, body in enumerate(self.quads.body_ids)
                for c in p.getContactPoints(bodyA=int(body), physicsClientId=self.client)}

    def body_name(self, body: int) -> str:
        return self.names.get(body, f"body {body}")


class Recording:
    """Writes what the tick produced (module docstring).

    Parameters
    ----------
    recorder : RunRecorder
        The run's record.
    uav_ids, car_ids : sequence of str
        The world's UAVs and ground vehicles, in order.
    contacts : ContactSource | None
        Collision source; None without UAVs.
    """

    def __init__(self, recorder: RunRecorder, uav_ids: Sequence[str], car_ids: Sequence[str],
                 contacts: ContactSource | None) -> None:
        self.recorder = recorder
        self.uav_ids = list(uav_ids)
        self.car_ids = list(car_ids)
        self.contacts = contacts
        self.event_counts_by_uav: dict[tuple[str, int], int] = {}
        self._touching: set[tuple[int, int]] = set()
        self._target_track: dict[int, int | None] = {}  # per UAV, the track its estimator last took for the target

    def truth(self, tick: int, t: float, quads: UavFleet | None, cars: GroundFleet | None) -> None:
        """One ``uav_truth`` row per UAV and one ``vehicle_truth`` row per ground vehicle."""
        if quads is not None:
            st = quads.state
            n = len(self.uav_ids)
            self.recorder.append_rows("uav_truth", {
                "tick": np.full(n, tick), "t": np.full(n, t), "uav": np.arange(n),
                "x": st.p_W[:, 0], "y": st.p_W[:, 1], "z": st.p_W[:, 2],
                "qx": st.q_WB[:, 0], "qy": st.q_WB[:, 1], "qz": st.q_WB[:, 2], "qw": st.q_WB[:, 3],
                "vx": st.v_W[:, 0], "vy": st.v_W[:, 1], "vz": st.v_W[:, 2]})
        if cars is not None:
            st = cars.state
            n = len(self.car_ids)
            self.recorder.append_rows("vehicle_truth", {
                "tick": np.full(n, tick), "t": np.full(n, t), "vehicle": np.arange(n),
                "x": st.p_W[:, 0], "y": st.p_W[:, 1], "z": st.p_W[:, 2], "yaw": np.asarray(st.yaw),
                "vx": st.v_W[:, 0], "vy": st.v_W[:, 1], "vz": st.v_W[:, 2],
                "ax": st.a_W[:, 0], "ay": st.a_W[:, 1], "az": st.a_W[:, 2], "speed": np.asarray(st.speed),
                "road": np.asarray(list(st.road_id), dtype=str), "s": np.asarray(st.s),
                "lateral": np.asarray(st.lateral),
                "active": np.ones(n, dtype=bool) if getattr(st, "active", None) is None else np.asarray(st.active)})

    def detections(self, tick: int, uav: int, sensor: str, out: SensorOutput) -> None:
        """One ``detections`` row per detection of a scan of UAV ``uav``'s sensor ``sensor``."""
        dets = out.detections
        n = len(dets)
        if not n:
            return
        z = np.full((n, 4), np.nan)
        for k, d in enumerate(dets):
            z[k, : min(4, d.z.size)] = d.z[:4]
        self.recorder.append_rows("detections", {
            "tick": [tick] * n, "t_meas": [d.t_meas for d in dets], "t_arrival": [d.t_arrival for d in dets],
            "uav": [uav] * n, "sensor": [sensor] * n, "kind": [d.model.name for d in dets],
            "truth_id": [int(tid) for tid in out.truth_ids], "z0": z[:, 0], "z1": z[:, 1], "z2": z[:, 2],
            "z3": z[:, 3]})

    def agent(self, tick: int, t: float, uav: int, estimator: TargetEstimator, result: AgentOutput,
              fused: bool) -> None:
        """An agent step's ``estimates`` row, its ``fused_estimates`` row when it ``fused`` and its ``commands``
        row."""
        road = estimator.road_held() if isinstance(estimator, HoldsRoad) else ""
        self.recorder.append("estimates", **estimate_row(tick, t, uav, result.local_estimate,
                                                         result.used_detections, road))
        if fused:
            self.recorder.append("fused_estimates", **estimate_row(tick, t, uav, result.estimate, 0))
        sp = result.setpoint
        cmd = _COMMANDS.blank(tick=tick, t=t, uav=uav, kind=type(sp).__name__)
        if isinstance(sp, UnicycleSetpoint):
            cmd.update(speed=sp.speed, heading_rate=sp.heading_rate, altitude=sp.altitude)
        elif isinstance(sp, VelocitySetpoint):
            cmd.update(vx=sp.v_W[0], vy=sp.v_W[1], vz=sp.v_W[2])
        self.recorder.append("commands", **cmd)

    def tracks(self, tick: int, t: float, uav: int, estimator: TargetEstimator) -> None:
        """One ``tracks`` row per live track of a multi-target estimator (:class:`~autonomy.diagnostics.HoldsTracks`)
        after its step, and a ``target_track_changed`` event when the track it takes for the target is another than
        at its last step (``from_track`` / ``to_track``, None for no track; ``from_alive``: whether the old track
        still lives, so a switch between live tracks tells from a lost or merged one; the new track's ``p`` and
        position); nothing for other estimators."""
        if not isinstance(estimator, HoldsTracks):
            return
        target = estimator.target_track_id
        reports = estimator.track_reports()
        if reports:
            self.recorder.append_rows("tracks", track_columns(tick, t, uav, reports, target))
        before = self._target_track.get(uav)
        if target == before:
            return
        self._target_track[uav] = target
        now = next((r for r in reports if r.track_id == target), None)
        self.event(tick, t, {"type": "target_track_changed", "uav": uav, "from_track": before, "to_track": target,
                             "from_alive": any(r.track_id == before for r in reports),
                             "p": None if now is None else float(now.target_probability),
                             "x": None if now is None else float(now.estimate.p_W[0]),
                             "y": None if now is None else float(now.estimate.p_W[1])})

    def sharing(self, tick: int, t: float, uav: int, estimator: TargetEstimator, received: int,
                own_sensors: set[str]) -> None:
        """``measurement_sharing``: per agent step, the teammates' detections delivered to UAV ``uav`` so far
        (``received``) and those its tracker's updates used so far (counted by the sensor ids that are not among the
        UAV's ``own_sensors``)."""
        used: Mapping[str, int] = estimator.used_by_sensor if isinstance(estimator, CountsSensorUse) else {}
        self.recorder.append("measurement_sharing", tick=tick, t=t, uav=uav, received=received,
                             own_used=sum(n for k, n in used.items() if k in own_sensors),
                             mates_used=sum(n for k, n in used.items() if k not in own_sensors))

    def collisions(self, tick: int, t: float) -> None:
        """A ``collision`` event for each contact of a UAV that began since the last check."""
        if self.contacts is None:
            return
        now = self.contacts.contacts()
        for i, other in sorted(now - self._touching):
            self.event(tick, t, {"type": "collision", "uav": i, "uav_id": self.uav_ids[i],
                                 "other": self.contacts.body_name(other)})
        self._touching = now

    def outage_events(self, tick: int, t: float, outages: Sequence[Outage]) -> None:
        """``link_outage_start`` / ``link_outage_end`` at the first and last tick of each scheduled outage."""
        for a, b, start, end in outages:
            if tick == max(start, 1):
                self.event(tick, t, {"type": "link_outage_start", "link": [a, b]})
            elif tick == end:
                self.event(tick, t, {"type": "link_outage_end", "link": [a, b]})

    def event(self, tick: int, t: float, ev: dict) -> None:
        """Append the event ``ev`` (its ``type`` and fields), counted per UAV when it names one."""
        kind = ev.pop("type")
        if "uav" in ev:
            key = (kind, int(ev["uav"]))
            self.event_counts_by_uav[key] = self.event_counts_by_uav.get(key, 0) + 1
        self.recorder.event(kind, tick, t, **ev)


def estimate_row(tick: int, t: float, uav: int, est: TargetEstimate | None, used: int, road: str = "") -> dict:
    """One row of ``estimates``; ``road`` is the road a road-constrained estimator holds the target on ("" off the
    map or for unconstrained estimators)."""
    row = _ESTIMATES.blank(tick=tick, t=t, uav=uav, valid=est is not None, detections=used, road=road)
    if est is not None:
        row.update(x=est.p_W[0], y=est.p_W[1], vx=est.v_W[0], vy=est.v_W[1])
        if est.P is not None:
            n = est.p_W.size
            row.update(pxx=est.P[0, 0], pxy=est.P[0, 1], pyy=est.P[1, 1], pvxvx=est.P[n, n], pvyvy=est.P[n + 1, n + 1])
    return row


def track_columns(tick: int, t: float, uav: int, reports: Sequence[TrackReport], target: int | None) -> dict:
    """The ``tracks`` rows of the tracks ``reports`` of UAV ``uav`` column by column, in the stream's order: one
    per track, its estimate's position, velocity and horizontal covariance entries (NaN without a covariance), and
    whether it is the track ``target`` names."""
    n = len(reports)
    ests = [r.estimate for r in reports]
    p, v = np.array([e.p_W[:2] for e in ests]), np.array([e.v_W[:2] for e in ests])
    cov = np.full((n, 3), np.nan)
    has = [k for k, e in enumerate(ests) if e.P is not None]
    if has:
        P = np.array([ests[k].P[:2, :2] for k in has])
        cov[has] = np.column_stack((P[:, 0, 0], P[:, 0, 1], P[:, 1, 1]))
    cols = {"tick": [tick] * n, "t": [t] * n, "uav": [uav] * n, "track": [int(r.track_id) for r in reports],
            "x": p[:, 0].tolist(), "y": p[:, 1].tolist(), "vx": v[:, 0].tolist(), "vy": v[:, 1].tolist(),
            "pxx": cov[:, 0].tolist(), "pxy": cov[:, 1].tolist(), "pyy": cov[:, 2].tolist(),
            "p_target": [float(r.target_probability) for r in reports],
            "evidence": [float(r.evidence) for r in reports], "confirmed": [bool(r.confirmed) for r in reports],
            "is_target": [r.track_id == target for r in reports]}
    return {c: cols[c] for c in _TRACKS.columns}
