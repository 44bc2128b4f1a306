"""Who follows whom: the nearest car ahead in each car's lane, found on each driver's own lane path."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from vehicles.car.driver import Driver
from vehicles.car.driver_config import LeaderInfo

__all__ = ["find_leaders"]


def find_leaders(drivers: Sequence[Driver], p_xy: np.ndarray, yaw: np.ndarray, speed: np.ndarray,
                 lengths: Sequence[float]) -> list[LeaderInfo | None]:
    """Leader of every car: the nearest other car ahead whose centre lies within half a lane of the car's lane path.

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

    Returns
    -------
    list of LeaderInfo or None
        Gap = s_j - s_i - (l_i + l_j) / 2 along car i's path; leader speed = v_j cos(psi_j - path heading), >= 0.
    """
    p_xy = np.asarray(p_xy, dtype=float)
    n = len(drivers)
    out: list[LeaderInfo | None] = [None] * n
    if n < 2:
        return out
    dist = np.linalg.norm(p_xy[:, None, :] - p_xy[None, :, :], axis=2)
    for i, drv in enumerate(drivers):
        path = drv.path
        cfg = drv.config
        own = path.project(p_xy[i], None if drv._proj is None else drv._proj.index)
        half_window = int(cfg.follow_range / (2 * cfg.path_ds)) + 2
        hint = own.index + half_window
        best: LeaderInfo | None = None
        for j in np.flatnonzero(dist[i] < cfg.follow_range + lengths[i]):
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
