"""The engine side of a run as the tick sees it: the vehicle fleets (typed protocols, so a scripted fleet can stand
in for PyBullet's) and the ground truth read from them."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from interfaces.state import OwnState
from autonomy.sensing.scene import TargetTruth
from simulator.decoys import StaticDecoys
from vehicles.car.fleet import CarState
from interfaces.setpoints import FlightSetpoint
from vehicles.quadrotor.state import FleetState

__all__ = ["Fleet", "GroundFleet", "Truth", "UavFleet", "yaw_of"]


class Fleet(Protocol):
    """Vehicles stepped by the tick: actuation before the physics step, low-level control after it."""

    body_ids: np.ndarray

    def apply_actuation(self) -> None: ...

    def after_step(self, tick: int) -> None: ...

    def pop_events(self) -> list[dict]: ...


class UavFleet(Fleet, Protocol):
    """The quadrotors: their state and the command each UAV's controllers follow."""

    @property
    def state(self) -> FleetState: ...

    def set_command(self, i: int, cmd: FlightSetpoint) -> None: ...


class GroundFleet(Fleet, Protocol):
    """The cars: their state."""

    @property
    def state(self) -> CarState: ...


class Truth:
    """Ground truth of a run: the UAVs' own states and the targets a sensor may see.

    Parameters
    ----------
    quads : UavFleet | None
        The UAVs.
    cars : GroundFleet | None
        The ground vehicles.
    car_kinds : tuple of str
        Each car's kind as the sensors see it (``car`` or ``decoy``).
    decoys : StaticDecoys | None
        Static decoys, rows after the cars.
    """

    def __init__(self, quads: UavFleet | None, cars: GroundFleet | None, car_kinds: tuple[str, ...],
                 decoys: StaticDecoys | None) -> None:
        self.quads = quads
        self.cars = cars
        self.car_kinds = car_kinds
        self.decoys = decoys

    def targets(self) -> TargetTruth:
        """The ground vehicles, then the static decoys (rows ``len(cars) + k``; cars' cone rows are unused)."""
        if self.cars is None and self.decoys is None:
            return TargetTruth.empty()
        if self.cars is None:
            p, v, yaw, kinds, segs = np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), (), np.zeros(0, int)
        else:
            st = self.cars.state
            p, v, yaw, kinds, segs = st.p_W, st.v_W, np.asarray(st.yaw), self.car_kinds, np.asarray(self.cars.body_ids)
        if self.decoys is None:
            return TargetTruth(ids=np.arange(len(kinds)), p_W=p, v_W=v, kind=kinds, yaw=yaw, seg_ids=segs)
        d, n = self.decoys, len(kinds)
        return TargetTruth(ids=np.arange(n + len(d)), p_W=np.vstack([p, d.p_W]),
                           v_W=np.vstack([v, np.zeros((len(d), 3))]), kind=(*kinds, *("decoy",) * len(d)),
                           yaw=np.concatenate([yaw, d.yaw]),
                           cone_axis_W=np.vstack([np.tile([0.0, 0.0, 1.0], (n, 1)), d.cone_axis_W]),
                           cone_half_angle=np.concatenate([np.full(n, np.pi), d.cone_half_angle]),
                           seg_ids=np.concatenate([segs, d.body_ids]))

    def own_state(self, i: int, t: float) -> OwnState:
        """UAV ``i``'s navigation state at ``t`` (s): its true position, velocity and yaw."""
        st = self.quads.state
        return OwnState(t=t, p_W=st.p_W[i], v_W=st.v_W[i], yaw=yaw_of(st.q_WB[i]))


def yaw_of(q: np.ndarray) -> float:
    """Yaw (rad) of the quaternion ``q`` (x, y, z, w)."""
    x, y, z, w = q
    return float(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
