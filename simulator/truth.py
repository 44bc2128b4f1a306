"""The engine side of a run as the tick sees it: the vehicle fleets (typed protocols, so a scripted fleet can stand
in for PyBullet's) and the ground truth read from them."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np

from interfaces.state import OwnState
from autonomy.sensing.scene import TargetTruth
from simulator.decoys import StaticDecoys
from vehicles.car.fleet import CarState
from interfaces.setpoints import FlightSetpoint
from vehicles.quadrotor.state import FleetState
from worlds.catalog import CAR_ATTRIBUTES, car_classes

__all__ = ["Fleet", "GroundFleet", "Truth", "UavFleet", "car_attributes", "yaw_of"]


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

    @property
    def live_state(self) -> FleetState:
        """The same state without copies, only to be read before the next step."""
        ...

    def set_command(self, i: int, cmd: FlightSetpoint) -> None: ...


class GroundFleet(Fleet, Protocol):
    """The cars: their state, and their scene bodies placed on demand."""

    @property
    def state(self) -> CarState: ...

    def sync_scene(self) -> None:
        """Place every car's scene body where the state says (bodies moved lazily are placed before a sensor
        looks)."""
        ...


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
    car_attributes : Mapping[str, np.ndarray] | None
        Each car's class index per attribute (``worlds.catalog.CAR_ATTRIBUTES``; :func:`car_attributes`), (N,) per
        name; the targets' :attr:`~autonomy.sensing.scene.TargetTruth.attributes`, with -1 for the static decoys.
        None: the targets carry no attributes.
    """

    def __init__(self, quads: UavFleet | None, cars: GroundFleet | None, car_kinds: tuple[str, ...],
                 decoys: StaticDecoys | None, car_attributes: Mapping[str, np.ndarray] | None = None) -> None:
        self.quads = quads
        self.cars = cars
        self.car_kinds = car_kinds
        self.decoys = decoys
        self.car_attributes = None
        if car_attributes is not None:
            attrs = {str(k): np.array(v, dtype=int).reshape(-1) for k, v in car_attributes.items()}
            bad = {k: v.size for k, v in attrs.items() if v.size != len(car_kinds)}
            if bad:
                raise ValueError(f"Truth.car_attributes must have one entry per car ({len(car_kinds)}), got {bad}")
            self.car_attributes = attrs

    def _attributes(self, n_decoys: int) -> dict[str, np.ndarray] | None:
        if self.car_attributes is None:
            return None
        return {k: np.concatenate([v, np.full(n_decoys, -1, dtype=int)]) for k, v in self.car_attributes.items()}

    def targets(self) -> TargetTruth:
        """The ground vehicles on the road, then the static decoys (ids ``len(cars) + k``; cars' cone rows are
        unused). A traffic source's slot holding no vehicle now is left out (its id skipped)."""
        if self.cars is None and self.decoys is None:
            return TargetTruth.empty()
        n_dec = 0 if self.decoys is None else len(self.decoys)
        if self.cars is None:
            p, v, yaw, kinds, segs = np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), (), np.zeros(0, int)
            on = np.zeros(0, dtype=int)
        else:
            st = self.cars.state
            on = np.arange(len(self.car_kinds)) if st.active is None else np.flatnonzero(st.active)
            p, v, yaw, segs = st.p_W[on], st.v_W[on], np.asarray(st.yaw)[on], np.asarray(self.cars.body_ids)[on]
            kinds = tuple(self.car_kinds[i] for i in on)
        attrs = self._attributes(n_dec)
        if attrs is not None and len(on) != len(self.car_kinds):
            keep = np.r_[on, len(self.car_kinds) + np.arange(n_dec)]
            attrs = {k: a[keep] for k, a in attrs.items()}
        if self.decoys is None:
            return TargetTruth(ids=on, p_W=p, v_W=v, kind=kinds, yaw=yaw, seg_ids=segs, attributes=attrs)
        d, n = self.decoys, len(kinds)
        return TargetTruth(ids=np.r_[on, len(self.car_kinds) + np.arange(n_dec)], p_W=np.vstack([p, d.p_W]),
                           v_W=np.vstack([v, np.zeros((n_dec, 3))]), kind=(*kinds, *("decoy",) * n_dec),
                           yaw=np.concatenate([yaw, d.yaw]),
                           cone_axis_W=np.vstack([np.tile([0.0, 0.0, 1.0], (n, 1)), d.cone_axis_W]),
                           cone_half_angle=np.concatenate([np.full(n, np.pi), d.cone_half_angle]),
                           seg_ids=np.concatenate([segs, d.body_ids]), attributes=attrs)

    def own_state(self, i: int, t: float) -> OwnState:
        """UAV ``i``'s navigation state at ``t`` (s): its true position, velocity and yaw."""
        st = self.quads.state
        return OwnState(t=t, p_W=st.p_W[i], v_W=st.v_W[i], yaw=yaw_of(st.q_WB[i]))


def car_attributes(types: Sequence[str], colours: Sequence[str]) -> dict[str, np.ndarray]:
    """(N,) class index of each car per attribute of ``worlds.catalog.CAR_ATTRIBUTES``, from each car's type and
    colour (:func:`worlds.catalog.car_classes`)."""
    if len(types) != len(colours):
        raise ValueError(f"car_attributes needs one colour per car type, got {len(types)} types, {len(colours)} "
                         "colours")
    rows = [car_classes(t, c) for t, c in zip(types, colours, strict=True)]
    return {name: np.array([r[name] for r in rows], dtype=int) for name in CAR_ATTRIBUTES}


def yaw_of(q: np.ndarray) -> float:
    """Yaw (rad) of the quaternion ``q`` (x, y, z, w)."""
    x, y, z, w = q
    return float(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
