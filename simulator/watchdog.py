"""The divergence watchdog: a run whose physics has blown up stops, naming the body, the tick and the quantity.

Checked after every physics step, on the state the fleets have just read (before sensors and agents see it):

- every UAV's and ground vehicle's position and velocity, and every UAV's attitude and body rates, are finite;
- no UAV is more than :data:`BELOW_GROUND_M` under the ground plane (contact keeps a body above it: one under it
  went through);
- no UAV is faster than its airframe can fly. PyBullet clamps each velocity component at 100 m/s, so a blown-up
  body shows a plausible-looking ``100·√3`` m/s instead of an infinity; the limit is
  :data:`SPEED_MARGIN` times the airframe's top speed — its quadratic and linear drag, on its least draggy axis,
  balancing full thrust plus its weight (a powered dive, an upper bound of every manoeuvre) — plus the strongest
  wind of the world (drag acts on the speed through the air).

The check is one compiled pass over the UAVs per tick (:meth:`Watchdog.check`; about a microsecond, plus reading
the fleet's state); it changes nothing in a run that stays sane.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from worlds.schema import World

__all__ = ["BELOW_GROUND_M", "Divergence", "SPEED_MARGIN", "Watchdog", "airframe_top_speed", "world_watchdog"]

BELOW_GROUND_M = 1.0
"""How far under the ground plane (m) a UAV's centre may be before the run has diverged: PyBullet's contact lets a
body sink millimetres, a crash a few centimetres; a metre is a body that went through."""

SPEED_MARGIN = 1.25
"""Factor over the airframe's top speed (-) before a UAV is too fast to be physical."""

GUST_SIGMAS = 6.0
"""Standard deviations of turbulence added to the mean wind for the strongest gust (-)."""


@dataclass(eq=False)
class Divergence(Exception):
    """The physics diverged: ``body`` (a UAV's or vehicle's id) at ``tick`` has ``quantity`` = ``value``.

    Attributes
    ----------
    body, tick, quantity : str, int, str
        What diverged, when, and which quantity (``p_W``, ``v_W``, ``q_WB``, ``omega_B``, ``z``, ``speed``).
    value : str
        The offending value, as text.
    limit : str
        What it should have been.
    """

    body: str
    tick: int
    quantity: str
    value: str
    limit: str

    def __str__(self) -> str:
        return f"{self.body} diverged at tick {self.tick}: {self.quantity} = {self.value} ({self.limit})"

    def fields(self) -> dict[str, object]:
        """The event fields of the record (``run_end``'s ``diverged``)."""
        return {"body": self.body, "tick": self.tick, "quantity": self.quantity, "value": self.value,
                "limit": self.limit}


def airframe_top_speed(*, mass: float, max_thrust: float, drag_linear: Sequence[float],
                       drag_quadratic: Sequence[float], gravity: float) -> float:
    """Fastest an airframe can move through the air (m/s): ``c2 v² + c1 v = T_max + m g`` on its least draggy axis
    (``inf`` for an airframe without drag)."""
    c1, c2, f = min(drag_linear), min(drag_quadratic), max_thrust + mass * gravity
    if c2 > 0:
        return (-c1 + math.sqrt(c1 * c1 + 4.0 * c2 * f)) / (2.0 * c2)
    return f / c1 if c1 > 0 else math.inf


@njit(cache=True)
def _first_insane(p_W: np.ndarray, v_W: np.ndarray, q_WB: np.ndarray, omega_B: np.ndarray, speed2_max: np.ndarray,
                  z_min: float) -> int:
    """Index of the first UAV with a non-finite state, under ``z_min`` or faster than ``sqrt(speed2_max)``; -1 if
    none (one compiled pass: about a microsecond, a tenth of the numpy expressions it replaces)."""
    for i in range(p_W.shape[0]):
        s = q_WB[i, 0] + q_WB[i, 1] + q_WB[i, 2] + q_WB[i, 3]  # a sum is finite only if every term is
        s += p_W[i, 0] + p_W[i, 1] + p_W[i, 2] + omega_B[i, 0] + omega_B[i, 1] + omega_B[i, 2]
        v2 = v_W[i, 0] * v_W[i, 0] + v_W[i, 1] * v_W[i, 1] + v_W[i, 2] * v_W[i, 2]
        if not (math.isfinite(s) and p_W[i, 2] >= z_min and v2 <= speed2_max[i]):  # NaN fails both comparisons
            return i
    return -1


def _text(a: np.ndarray) -> str:
    return np.array2string(np.asarray(a, dtype=float), precision=4, separator=", ")


class Watchdog:
    """Checks the fleets' state after each physics step; raises :class:`Divergence`.

    Parameters
    ----------
    uav_ids, car_ids : sequence of str
        Ids of the UAVs and ground vehicles, in fleet order (the bodies a divergence names).
    speed_max : np.ndarray
        (N,) fastest physical speed of each UAV (m/s).
    ground_z : float
        Height of the ground plane (m).
    """

    def __init__(self, uav_ids: Sequence[str], car_ids: Sequence[str], speed_max: np.ndarray,
                 ground_z: float = 0.0) -> None:
        self.uav_ids, self.car_ids = list(uav_ids), list(car_ids)
        self.speed_max = np.asarray(speed_max, dtype=float).reshape(len(self.uav_ids))
        self._speed2_max = self.speed_max**2
        self.z_min = float(ground_z) - BELOW_GROUND_M

    def check(self, tick: int, uavs: object | None, cars: object | None) -> None:
        """Raise :class:`Divergence` for the first UAV (then vehicle) whose state is not sane; ``uavs`` and ``cars``
        are the fleets' states (:class:`~vehicles.quadrotor.state.FleetState`, :class:`~vehicles.car.fleet.CarState`)
        or None."""
        if uavs is not None and _first_insane(uavs.p_W, uavs.v_W, uavs.q_WB, uavs.omega_B, self._speed2_max,
                                              self.z_min) >= 0:
            self._name_uav(tick, uavs)
        if cars is not None and not math.isfinite(float(cars.p_W.sum() + cars.v_W.sum())):
            for i, cid in enumerate(self.car_ids):
                for q in ("p_W", "v_W"):
                    x = getattr(cars, q)[i]
                    if not np.isfinite(x).all():
                        raise Divergence(cid, tick, q, _text(x), "not finite")

    def _name_uav(self, tick: int, st: object) -> None:
        for i, uid in enumerate(self.uav_ids):
            for q in ("p_W", "v_W", "q_WB", "omega_B"):
                x = getattr(st, q)[i]
                if not np.isfinite(x).all():
                    raise Divergence(uid, tick, q, _text(x), "not finite")
            z = float(st.p_W[i, 2])
            if z < self.z_min:
                raise Divergence(uid, tick, "z", f"{z:.4g} m", f"under the ground: below {self.z_min:g} m")
            speed = float(np.linalg.norm(st.v_W[i]))
            if speed > self.speed_max[i]:
                raise Divergence(uid, tick, "speed", f"{speed:.4g} m/s",
                                 f"faster than the airframe can fly: above {self.speed_max[i]:.4g} m/s")


def world_watchdog(world: World, ground_z: float = 0.0) -> Watchdog:
    """The watchdog of a world: each UAV's airframe top speed in the world's gravity, times :data:`SPEED_MARGIN`,
    plus the world's strongest wind (its mean speed and :data:`GUST_SIGMAS` of turbulence)."""
    from vehicles.quadrotor.airframes import load_airframe

    env = world.environment
    wind = 0.0
    if env.wind is not None:
        turb = env.wind.turbulence
        wind = math.hypot(*env.wind.mean_W) + (0.0 if turb is None else GUST_SIGMAS * turb.sigma)
    limits = []
    for u in world.uavs:
        a = load_airframe(u.airframe)
        top = airframe_top_speed(mass=a.mass, max_thrust=4.0 * a.k_f * a.rotor_speed_max**2,
                                 drag_linear=a.drag_linear, drag_quadratic=a.drag_quadratic, gravity=env.gravity)
        limits.append(SPEED_MARGIN * top + wind)
    return Watchdog([u.id for u in world.uavs], [g.id for g in world.ground_vehicles], np.array(limits), ground_z)
