"""Slots of a co-simulated traffic source: which vehicle each holds, its state at two steps, poses in between.

The source's simulator steps at ticks ``t_prev`` and ``t_next = t_prev + period``; a slot holds the state of its
vehicle at both. At a physics tick ``t`` in ``[t_prev, t_next)`` with ``alpha = (t - t_prev) / period``:

- a vehicle on the road at both steps is interpolated linearly, position and speed, and its heading along the
  shorter arc: ``x(t) = (1 - alpha) x_prev + alpha x_next``, ``yaw(t) = yaw_prev + alpha wrap(yaw_next - yaw_prev)``,
  yaw rate ``wrap(yaw_next - yaw_prev) / (period dt)``;
- a vehicle that arrives (or leaves the road) during the step stays where it was at ``t_prev`` until ``t_next``;
- a vehicle that departs during the step is inactive until ``t_next``;

and at ``t = t_next`` every slot is its state at ``t_next``. So a slot changes vehicle only at a step, never blends
two vehicles, and the poses at ``t_next`` are the same before and after the step from ``t_next`` is taken.
"""

from __future__ import annotations

import heapq

import numpy as np

from vehicles.car.traffic_source import TrafficPoses

__all__ = ["SlotStates"]


class SlotStates:
    """N slots: the vehicle each holds and its state at the last two steps (see the module docstring).

    Parameters
    ----------
    n : int
        Number of slots.
    """

    def __init__(self, n: int) -> None:
        if n < 1:
            raise ValueError(f"SlotStates: n must be >= 1, got {n}")
        self.n = n
        self.vehicle: list[str | None] = [None] * n
        self._slot_of: dict[str, int] = {}
        self._free = list(range(n))  # a heap: the lowest free slot is taken first, so slot order is reproducible
        self._prev_vehicle: list[str | None] = [None] * n
        self.xy = np.zeros((2, n, 2))  # [prev, next]
        self.yaw = np.zeros((2, n))
        self.speed = np.zeros((2, n))
        self.on = np.zeros((2, n), dtype=bool)
        self.road = [[""] * n, [""] * n]
        self._same = np.zeros(n, dtype=bool)
        self._lerp: tuple | None = None  # positions()' gathered states of its last slots in this step

    # ------------------------------------------------------------------ vehicles in and out
    def slot_of(self, vehicle_id: str) -> int | None:
        """Slot holding ``vehicle_id``, or None."""
        return self._slot_of.get(vehicle_id)

    def take(self, vehicle_id: str) -> int:
        """Give ``vehicle_id`` the lowest free slot; RuntimeError when all are taken."""
        if not self._free:
            raise RuntimeError(f"all {self.n} traffic slots are taken: vehicle {vehicle_id!r} has none; give the "
                               f"source more slots than vehicles on the road")
        k = heapq.heappop(self._free)
        self.vehicle[k] = vehicle_id
        self._slot_of[vehicle_id] = k
        return k

    def release(self, vehicle_id: str) -> int | None:
        """Free the slot of ``vehicle_id`` (its state at the next step becomes off the road); its index or None."""
        k = self._slot_of.pop(vehicle_id, None)
        if k is not None:
            self.vehicle[k] = None
            self.on[1, k] = False
            self.road[1][k] = ""
            heapq.heappush(self._free, k)
        return k

    # ------------------------------------------------------------------ steps
    def begin_step(self) -> None:
        """The state at the next step becomes the previous one (call before the simulator steps)."""
        self._prev_vehicle = list(self.vehicle)
        self._lerp = None
        self.xy[0], self.yaw[0], self.speed[0], self.on[0] = self.xy[1], self.yaw[1], self.speed[1], self.on[1]
        self.road[0] = list(self.road[1])

    def end_step(self, slots: np.ndarray, xy: np.ndarray, yaw: np.ndarray, speed: np.ndarray, on: np.ndarray,
                 road: list[str]) -> None:
        """States at the new step of the vehicles in ``slots`` (every occupied slot; the others are off the road)."""
        self.on[1] = False
        self.on[1, slots] = on
        self.xy[1, slots], self.yaw[1, slots], self.speed[1, slots] = xy, yaw, speed
        nxt = [""] * self.n
        for k, r in zip(slots.tolist(), road, strict=True):
            nxt[k] = r
        self.road[1] = nxt
        pairs = zip(self._prev_vehicle, self.vehicle, strict=True)
        same = np.array([a is not None and a == b for a, b in pairs], dtype=bool)
        self._same = same & self.on[0] & self.on[1]
        self._lerp = None

    # ------------------------------------------------------------------ poses
    def poses(self, tick: int, alpha: float, step_dt: float, idx: np.ndarray | None = None) -> TrafficPoses:
        """Poses at ``tick``, a fraction ``alpha`` in [0, 1] of the way from the previous step to the next one
        (``step_dt``: the step length, s); of the slots ``idx`` only, in that order, if given (the same numbers as
        their rows of every slot's poses)."""
        sel = slice(None) if idx is None else idx
        same = self._same[sel]
        xy, yaw, dyaw, a = self._xy_yaw(alpha, sel)
        if alpha >= 1.0:
            speed, on = self.speed[1, sel].copy(), self.on[1, sel].copy()
        else:
            sp0 = self.speed[0, sel]
            speed = sp0 + a * (self.speed[1, sel] - sp0)
            on = self.on[0, sel].copy()
        yaw_rate = np.where(same, dyaw, 0.0) / step_dt
        speed = np.where(on, speed, 0.0)
        yaw_rate = np.where(on, yaw_rate, 0.0)
        c, s = np.cos(yaw), np.sin(yaw)
        v_xy = speed[:, None] * np.stack([c, s], axis=1)
        # d/dt of speed (cos yaw, sin yaw) with speed and yaw linear over the step: along the heading the step's
        # change of speed, across it speed times the yaw rate (at a step's end, the step just ended)
        accel = np.where(on & same, (self.speed[1, sel] - self.speed[0, sel]) / step_dt, 0.0)
        a_xy = np.stack([accel * c - speed * yaw_rate * s, accel * s + speed * yaw_rate * c], axis=1)
        return TrafficPoses(tick=tick, xy=xy, yaw=yaw, speed=speed, v_xy=v_xy, yaw_rate=yaw_rate, active=on,
                            a_xy=a_xy)

    def positions(self, alpha: float, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(xy (k, 2), yaw (k,)) of the slots ``idx`` at ``alpha``: the :meth:`poses` ``xy`` and ``yaw`` of those
        rows (the same numbers), without the rest of a pose. Asked again for the same ``idx`` (the same array, not
        changed since) within a step, the slots' states and the step's changes are those gathered the first time."""
        if alpha >= 1.0:
            xy, yaw, _, _ = self._xy_yaw(alpha, idx)
            return xy, yaw
        if self._lerp is None or self._lerp[0] is not idx:
            self._lerp = (idx, self._terms(idx))
        xy, yaw, _ = self._lerp_at(self._lerp[1], alpha)
        return xy, yaw

    def _terms(self, sel: slice | np.ndarray) -> tuple[np.ndarray, ...]:
        """Of the slots ``sel``: positions and headings at the previous step, their changes over the step (the heading's
        wrapped) and whether each holds one vehicle on the road at both steps."""
        xy0, yaw0 = self.xy[0, sel], self.yaw[0, sel]
        d = self.yaw[1, sel] - yaw0
        return xy0, self.xy[1, sel] - xy0, yaw0, np.arctan2(np.sin(d), np.cos(d)), self._same[sel]

    @staticmethod
    def _lerp_at(terms: tuple[np.ndarray, ...], alpha: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, wrapped headings and per-slot fractions at ``alpha`` < 1 from :meth:`_terms`."""
        xy0, dxy, yaw0, dyaw, same = terms
        a = np.where(same, alpha, 0.0)
        yaw = yaw0 + a * dyaw
        return xy0 + a[:, None] * dxy, np.arctan2(np.sin(yaw), np.cos(yaw)), a

    def _xy_yaw(self, alpha: float, sel: slice | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                        np.ndarray | None]:
        """Positions and wrapped headings of the slots ``sel`` at ``alpha``, the step's wrapped change of heading and
        the per-slot fraction (``None`` at ``alpha`` >= 1) of the interpolation."""
        terms = self._terms(sel)
        if alpha >= 1.0:
            yaw1 = self.yaw[1, sel]
            return self.xy[1, sel].copy(), np.arctan2(np.sin(yaw1), np.cos(yaw1)), terms[3], None
        xy, yaw, a = self._lerp_at(terms, alpha)
        return xy, yaw, terms[3], a

    def active_at(self, alpha: float) -> np.ndarray:
        """Which slots hold a vehicle on the road at ``alpha`` (the ``active`` of :meth:`poses`), without poses."""
        return self.on[1] if alpha >= 1.0 else self.on[0]

    def reach(self) -> tuple[np.ndarray, np.ndarray]:
        """(centre (n, 2), radius (n,)) m of a disc that holds each slot's position at every ``alpha`` of the
        current step: the midpoint and half of the segment a slot interpolated along covers (1 mm more, for the
        interpolation's rounding), the previous position for the others (which stay there, or jump to the next at
        ``alpha`` 1: radius the whole jump)."""
        xy0, xy1 = self.xy[0], self.xy[1]
        half = 0.5 * np.hypot(*(xy1 - xy0).T)
        centre = np.where(self._same[:, None], 0.5 * (xy0 + xy1), xy0)
        return centre, np.where(self._same, half, 2.0 * half) + 1e-3

    def roads_at(self, alpha: float) -> list[str]:
        """SUMO edge of each slot at the step nearer to ``alpha`` (``""`` off the road)."""
        return list(self.road[1] if alpha >= 0.5 else self.road[0])
