"""Standoff-tracking geometry over time (paper 002's Table III metrics): each UAV's standoff-distance error and the
team's phase-keeping error, from UAV and target positions.

With ``N`` trackers at horizontal positions :math:`p_i` around the target :math:`p_T`, the standoff error of UAV
``i`` is :math:`| \\|p_i - p_T\\| - r_d |` and the phase error is the mean deviation of the angular gaps between
neighbouring trackers (sorted by bearing from the target) from the commanded :math:`2\\pi / N`:

.. math::

    e_\\phi = \\frac{1}{N} \\sum_{k} \\left| g_k - \\frac{2\\pi}{N} \\right|, \\qquad
    g_k = \\theta_{(k+1)} - \\theta_{(k)}\\ (\\text{cyclic}),

so for two UAVs :math:`e_\\phi = |g - \\pi|`, zero at 180° separation.
"""

from __future__ import annotations

import numpy as np

__all__ = ["standoff_errors", "phase_errors"]


def standoff_errors(uav_xy: np.ndarray, target_xy: np.ndarray, standoff_m: np.ndarray | float) -> np.ndarray:
    """(T, N) standoff-distance errors, m, of UAVs at ``uav_xy`` (T, N, 2) m around targets at ``target_xy`` (T, 2) m
    for standoff radii ``standoff_m`` (scalar or (N,)) m."""
    uav_xy = np.asarray(uav_xy, dtype=float)
    rel = uav_xy - np.asarray(target_xy, dtype=float)[:, None, :]
    return np.abs(np.hypot(rel[..., 0], rel[..., 1]) - np.asarray(standoff_m, dtype=float))


def phase_errors(uav_xy: np.ndarray, target_xy: np.ndarray) -> np.ndarray:
    """(T,) phase-keeping errors, rad, of N >= 2 UAVs at ``uav_xy`` (T, N, 2) m around ``target_xy`` (T, 2) m."""
    uav_xy = np.asarray(uav_xy, dtype=float)
    n = uav_xy.shape[1]
    if n < 2:
        raise ValueError(f"phase error needs at least two UAVs, got {n}")
    rel = uav_xy - np.asarray(target_xy, dtype=float)[:, None, :]
    ang = np.sort(np.arctan2(rel[..., 1], rel[..., 0]), axis=1)
    gaps = np.diff(np.concatenate([ang, ang[:, :1] + 2.0 * np.pi], axis=1), axis=1)
    return np.mean(np.abs(gaps - 2.0 * np.pi / n), axis=1)
