"""What the run loop asks of background traffic: cars stepped at their own rate, their scene bodies placed lazily.

A traffic source owns N slots (one scene body each, fixed for the run). The built-in compiled fleet
(:mod:`vehicles.car.traffic_fleet`) keeps one car per slot for the whole run; SUMO co-simulation
(:mod:`vehicles.sumo`) maps its vehicles onto slots as they depart and arrive, so a slot may be inactive (its body
parked out of sight, invisible to sensors). The source steps on its own ticks (a divisor of the physics rate) and can
say where every slot is at any physics tick since its last step (:meth:`TrafficSource.poses`); the scene bodies are
moved there only when something is about to look at the scene (:meth:`TrafficSource.sync_scene`: before a sensor scan,
a camera or video frame, a contact check), and every tick for the slots near a dynamic body (a UAV or a physics car,
:meth:`TrafficSource.sync_near`) so that contacts see them where they are.

The physics cars of the world (the targets by default) are not part of a source; the source hears where they are at
its own steps (:class:`OtherCars`) so its cars follow them, and it reports its slots to the physics cars' drivers
through :meth:`TrafficSource.poses` so they follow the traffic: car following sees both ways.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

__all__ = ["OtherCars", "TrafficPoses", "TrafficSource"]


@dataclass(frozen=True)
class TrafficPoses:
    """Where the slots of a traffic source are at one physics tick.

    Attributes
    ----------
    tick : int
        Physics tick.
    xy : np.ndarray
        (N, 2) centre-of-mass positions, world ENU (m).
    yaw : np.ndarray
        (N,) headings (rad).
    speed : np.ndarray
        (N,) speeds of the centre of mass (m/s).
    v_xy : np.ndarray
        (N, 2) velocities (m/s).
    yaw_rate : np.ndarray
        (N,) yaw rates (rad/s).
    active : np.ndarray
        (N,) bool: the slot holds a vehicle on the road now (always True for the built-in fleet).
    a_xy : np.ndarray or None
        (N, 2) accelerations (m/s²): the time derivative of ``v_xy`` as the source moves it (None: not given; the
        built-in fleet's come from its per-tick readings).
    """

    tick: int
    xy: np.ndarray
    yaw: np.ndarray
    speed: np.ndarray
    v_xy: np.ndarray
    yaw_rate: np.ndarray
    active: np.ndarray
    a_xy: np.ndarray | None = None


@dataclass(frozen=True)
class OtherCars:
    """The cars outside a traffic source (the physics cars) at one physics tick, for car following both ways.

    Attributes
    ----------
    xy : np.ndarray
        (M, 2) positions (m).
    yaw : np.ndarray
        (M,) headings (rad).
    speed : np.ndarray
        (M,) forward speeds (m/s).
    length : np.ndarray
        (M,) body lengths (m).
    """

    xy: np.ndarray
    yaw: np.ndarray
    speed: np.ndarray
    length: np.ndarray

    @staticmethod
    def none() -> OtherCars:
        """No other cars."""
        z = np.zeros(0)
        return OtherCars(xy=np.zeros((0, 2)), yaw=z, speed=z, length=z)


class TrafficSource(Protocol):
    """Background traffic as the car fleet steps it (see the module docstring)."""

    ids: list[str]
    """One id per slot."""
    body_ids: np.ndarray
    """(N,) PyBullet body of each slot."""
    lengths: np.ndarray
    """(N,) body length of each slot (m)."""
    ground_z: np.ndarray
    """(N,) height of each slot's centre of mass above the world origin when active (m)."""

    def advance(self, tick: int, others: OtherCars) -> None:
        """After the physics step of ``tick``: step the traffic if ``tick`` is one of its own ticks (else nothing).

        ``others`` are the physics cars at ``tick``."""

    def poses(self, tick: int) -> TrafficPoses:
        """Every slot's pose at physics tick ``tick``, between the last step and the next one (exact for the built-in
        fleet, which integrates every physics tick of its period at once; interpolated for SUMO)."""

    def sync_scene(self, tick: int) -> None:
        """Place every slot's body at its pose at ``tick`` (inactive slots parked out of sight); cheap when done."""

    def sync_near(self, tick: int, points_xy: np.ndarray, radius: float) -> None:
        """Place the bodies of the slots within ``radius`` (m) of any of ``points_xy`` (K, 2) at their pose at
        ``tick``."""

    def road_positions(self, tick: int) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
        """(road id, arc length on it (m), lateral offset from its centre-line (m), stopped) per slot at ``tick``;
        road id "" for an inactive slot."""

    def pop_events(self) -> list[dict]:
        """Events since the last call, as :meth:`vehicles.car.fleet.CarFleet.pop_events` (``car`` = slot index)."""

    def close(self) -> None:
        """Release what the source holds outside the process's memory (a SUMO instance); idempotent."""
