"""The observation and action of a learning UAV as Gymnasium spaces, and the conversions to and from the autonomy's
types.

The observation is what the UAV's autonomy knows at its step (:class:`~simulator.envs.episode.Knowledge`), never
truth, in the world frame (ENU, m, m/s, s), as a ``Dict`` of ``float32`` boxes:

- ``own`` (8,): ``x, y, z, vx, vy, vz, cos(yaw), sin(yaw)``, the UAV's navigation state;
- ``target`` (6,): ``valid, age_s, x, y, vx, vy``, the target estimate guidance flies on (fused when the UAV fuses;
  ``age_s`` = step time - estimate time; all zero with ``valid = 0`` when there is none);
- ``target_cov`` (4, 4): the estimate's covariance of ``(x, y, vx, vy)`` (m², m²/s, m²/s²; zero without one);
- ``teammates`` (N-1, 8): ``valid, age_s, x, y, z, vx, vy, vz`` of each other UAV in world order, as last heard
  (``valid = 0`` until a state has arrived); absent in a world of one UAV;
- ``image`` (H, W, 3) ``uint8``, when asked for: the onboard camera, gimballed on the target estimate.

The action is the set-point itself (:mod:`interfaces.setpoints`), clipped to the box: ``unicycle`` = (speed m/s,
heading rate rad/s, altitude m) within the airframe's ``max_speed`` and ``max_heading_rate``; ``velocity`` = (vx, vy,
vz) m/s within ``max_speed`` per horizontal axis and ``max_climb_rate``. For a learner that wants [-1, 1] actions,
``gymnasium.wrappers.RescaleAction`` maps onto these boxes.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from interfaces.setpoints import Setpoint, UnicycleSetpoint, VelocitySetpoint
from simulator.envs.episode import Knowledge
from vehicles.quadrotor.params import QuadrotorParams

__all__ = ["ActionCodec", "ObservationCodec", "OWN", "TARGET", "TEAMMATE"]

OWN = ("x", "y", "z", "vx", "vy", "vz", "cos_yaw", "sin_yaw")
TARGET = ("valid", "age_s", "x", "y", "vx", "vy")
TEAMMATE = ("valid", "age_s", "x", "y", "z", "vx", "vy", "vz")


def _box(*shape: int) -> spaces.Box:
    return spaces.Box(-np.inf, np.inf, shape=shape, dtype=np.float32)


class ObservationCodec:
    """The observation space of UAV ``uav`` in a world of ``n_uavs`` and the encoding of its knowledge.

    Parameters
    ----------
    n_uavs : int
        UAVs in the world.
    uav : int
        The learning UAV's index.
    image : (int, int) | None
        (height, width) of the camera image, or None for none.
    """

    def __init__(self, n_uavs: int, uav: int, image: tuple[int, int] | None) -> None:
        self.uav = uav
        self.others = [j for j in range(n_uavs) if j != uav]
        parts: dict[str, spaces.Space] = {"own": _box(len(OWN)), "target": _box(len(TARGET)), "target_cov": _box(4, 4)}
        if self.others:
            parts["teammates"] = _box(len(self.others), len(TEAMMATE))
        if image is not None:
            parts["image"] = spaces.Box(0, 255, shape=(int(image[0]), int(image[1]), 3), dtype=np.uint8)
        self.space = spaces.Dict(parts)

    def encode(self, k: Knowledge, image: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """The observation of knowledge ``k`` (and the camera ``image`` when the space has one)."""
        own = np.concatenate([k.own.p_W, k.own.v_W, [np.cos(k.own.yaw), np.sin(k.own.yaw)]])
        target, cov = np.zeros(len(TARGET)), np.zeros((4, 4))
        est = k.target
        if est is not None:
            target[:] = (1.0, k.t - est.t, est.p_W[0], est.p_W[1], est.v_W[0], est.v_W[1])
            if est.P is not None:
                n = est.p_W.size
                idx = [0, 1, n, n + 1]
                cov = np.asarray(est.P, dtype=float)[np.ix_(idx, idx)]
        obs = {"own": own.astype(np.float32), "target": target.astype(np.float32),
               "target_cov": cov.astype(np.float32)}
        if self.others:
            mates = np.zeros((len(self.others), len(TEAMMATE)))
            row = {j: r for r, j in enumerate(self.others)}
            for m in k.teammates:
                if m.id in row:
                    mates[row[m.id]] = (1.0, k.t - m.t, *m.p_W, *m.v_W)
            obs["teammates"] = mates.astype(np.float32)
        if "image" in self.space.spaces:
            if image is None:
                raise ValueError("the observation space has an image: pass the camera image")
            obs["image"] = np.asarray(image, dtype=np.uint8)
        return obs


class ActionCodec:
    """The action space of one UAV and the set-point of an action (module docstring).

    Parameters
    ----------
    kind : {"unicycle", "velocity"}
        The set-point type.
    airframe : QuadrotorParams
        The UAV's airframe (its envelope bounds the box).
    altitude_range_m : (float, float)
        Bounds of a unicycle altitude (m).
    """

    def __init__(self, kind: str, airframe: QuadrotorParams, altitude_range_m: tuple[float, float]) -> None:
        self.kind = kind
        v, r, c = float(airframe.max_speed), float(airframe.max_heading_rate), float(airframe.max_climb_rate)
        if kind == "unicycle":
            low, high = [0.0, -r, altitude_range_m[0]], [v, r, altitude_range_m[1]]
        elif kind == "velocity":
            low, high = [-v, -v, -c], [v, v, c]
        else:
            raise ValueError(f"action kind must be 'unicycle' or 'velocity', got {kind!r}")
        self.space = spaces.Box(np.array(low, dtype=np.float32), np.array(high, dtype=np.float32), dtype=np.float32)

    def setpoint(self, action: np.ndarray) -> Setpoint:
        """The set-point of ``action``, clipped to the box; raises ``ValueError`` on a wrong shape or a non-finite
        value."""
        a = np.asarray(action, dtype=float).reshape(-1)
        if a.shape != self.space.shape or not np.all(np.isfinite(a)):
            raise ValueError(f"action must be {self.space.shape[0]} finite numbers ({self.kind}), got {action!r}")
        a = np.clip(a, self.space.low, self.space.high)
        if self.kind == "unicycle":
            return UnicycleSetpoint(speed=float(a[0]), heading_rate=float(a[1]), altitude=float(a[2]))
        return VelocitySetpoint(v_W=a.copy())

    def action(self, setpoint: Setpoint) -> np.ndarray:
        """The action of ``setpoint`` (of this codec's kind), clipped to the box: for scripted policies written in
        set-points."""
        if self.kind == "unicycle" and isinstance(setpoint, UnicycleSetpoint):
            a = [setpoint.speed, setpoint.heading_rate, setpoint.altitude]
        elif self.kind == "velocity" and isinstance(setpoint, VelocitySetpoint):
            a = list(setpoint.v_W)
        else:
            raise ValueError(f"a {self.kind} action cannot hold a {type(setpoint).__name__}")
        return np.clip(np.asarray(a, dtype=np.float32), self.space.low, self.space.high)
