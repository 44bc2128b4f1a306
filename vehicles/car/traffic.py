"""Who follows whom: the nearest car ahead in each car's lane, found on each driver's own lane path."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from vehicles.car.driver import Driver
from vehicles.car.driver_config import LeaderInfo

__all__ = ["find_leaders"]


def find_leaders(drivers: Sequence[Driver], p_xy: np.ndarray, yaw: np.ndarray, speed: np.ndarray,
                 lengths: Sequence[float], followers: Sequence[int] | None = None) -> list[LeaderInfo | None]:
    """Leader of every car (or of the ``followers``): the nearest other car ahead whose centre lies within half a
    lane of the car's lane path. Cost: one distance per follower and car, a path projection per car near it (the
    compiled fleet of :mod:`vehicles.car.traffic_kernel` does the same for many followers on a grid).

    Parameters
    ----------
    drivers : Sequence[Driver]
        One driver per car (their lane paths and last projections are used).
    p_xy : np.ndarray
        (N, 2) car positions (m).
    yaw : np.ndarray
        (N,) headings (rad).
    speed : np.ndarray
        (N,) forward speeds (m/s).
    lengths : Sequence[float]
        Car body lengths (m), for bumper-to-bumper gaps.
    followers : Sequence[int] | None
        The cars whose leaders are wanted (None: all); ``drivers`` need only be real for these.

    Returns
    -------
    list of LeaderInfo or None
        Gap = s_j - s_i - (l_i + l_j) / 2 along car i's path; leader speed = v_j cos(psi_j - path heading), >= 0;
        None for a car without a leader or not among the followers.
    """
    p_xy = np.asarray(p_xy, dtype=float)
    n = len(drivers)
    out: list[LeaderInfo | None] = [None] * n
    if n < 2:
        return out
    for i in range(n) if followers is None else followers:
        drv = drivers[i]
        dist_i = np.linalg.norm(p_xy - p_xy[i], axis=1)
        path = drv.path
        cfg = drv.config
        own = path.project(p_xy[i], None if drv._proj is None else drv._proj.index)
        half_window = int(cfg.follow_range / (2 * cfg.path_ds)) + 2
        hint = own.index + half_window
        best: LeaderInfo | None = None
        for j in np.flatnonzero(dist_i < cfg.follow_range + lengths[i]):
            if j == i:
                continue
            pj = path.project(p_xy[j], hint, window=half_window + 2)
            if pj.s <= own.s:
                continue
            half_lane = 0.5 * path.roads[int(path.road_index[pj.index])].lane_width
            if abs(pj.lateral) > half_lane:
                continue
            gap = pj.s - own.s - 0.5 * (lengths[i] + lengths[j])
            if best is None or gap < best.gap:
                v_along = max(0.0, float(speed[j]) * math.cos(float(yaw[j]) - pj.heading))
                best = LeaderInfo(gap=float(gap), speed=v_along, index=int(j))
        out[i] = best
    return out
