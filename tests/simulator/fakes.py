"""Autonomy fakes for the tick on the fake engine: a sensor, an estimator and a guidance law that keep what they
saw."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from interfaces.setpoints import VelocitySetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState
from autonomy.sensing.measurement import Detection, Sensor, SensorOutput
from autonomy.sensing.scene import SceneQuery, SensorPose, TargetTruth

HZ = 12  # physics rate of the fake runs: tick k is at k / 12 s


def tick_of(t: float) -> int:
    return round(t * HZ)


class LogSensor(Sensor):
    """One detection per scan: the sensor's own position, taken now, delivered ``latency_s`` later."""

    def __init__(self, sensor_id: str, log: list, latency_s: float = 0.0) -> None:
        self.sensor_id, self.rate_hz, self.latency_s, self.log = sensor_id, 0.0, latency_s, log

    def measure(self, tick_time_s: float, pose: SensorPose, targets: TargetTruth, scene: SceneQuery,
                rng: np.random.Generator) -> SensorOutput:
        self.log.append((f"sensor {self.sensor_id}", tick_of(tick_time_s)))
        det = Detection(z=pose.p_W[:2], R=np.eye(2), t_meas=tick_time_s, t_arrival=tick_time_s + self.latency_s,
                        sensor_id=self.sensor_id, p_sensor_W=pose.p_W, kind="box")
        return SensorOutput(detections=(det,), truth_ids=np.array([-1]))


class LogEstimator:
    """Keeps, per step, the tick and the (sensor, tick taken) of the detections it got; estimates the mean of their
    positions with a unit covariance."""

    def __init__(self, log: list, name: str) -> None:
        self.log, self.name = log, name
        self.steps: list[tuple[int, list[tuple[str, int]]]] = []
        self.used_by_sensor: dict[str, int] = {}

    def step(self, t: float, detections: Sequence[Detection]) -> TargetEstimate | None:
        self.log.append((f"estimate {self.name}", tick_of(t)))
        self.steps.append((tick_of(t), [(d.sensor_id, tick_of(d.t_meas)) for d in detections]))
        for d in detections:
            self.used_by_sensor[d.sensor_id] = self.used_by_sensor.get(d.sensor_id, 0) + 1
        if not detections:
            return None
        p = np.mean([d.z for d in detections], axis=0)
        return TargetEstimate(t=t, p_W=p, v_W=np.zeros(2), P=np.eye(4))


class LogGuidance:
    """Keeps, per command, the tick and what it knew of its teammates (id, tick of the state) and of the target."""

    def __init__(self) -> None:
        self.calls: list[tuple[int, list[tuple[int, int]], TargetEstimate | None]] = []

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> VelocitySetpoint:
        self.calls.append((tick_of(t), [(m.id, tick_of(m.t)) for m in teammates], target))
        return VelocitySetpoint(v_W=np.zeros(3), yaw=0.0)
