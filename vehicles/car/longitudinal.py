"""Longitudinal driving laws: the curvature / speed-limit / stop speed envelope and the IDM+ car-following term.

Speed envelope over the points i ahead (distance d_i >= 0, speed cap v_i):
    v_i = min(cruise_i, sqrt(a_lat,max / |kappa_i|)),  v_i = 0 at a stop line,
    v_target = min_i sqrt(v_i^2 + 2 b_plan d_i),
    a_track = k_v (v_target - v),
    a_brake = min_{i: d_i >= d_min, v > v_i} (v_i^2 - v^2) / (2 d_i)   (constant deceleration reaching v_i at d_i),
    a_free  = min(a_track, a_brake).
Car following, IDM+ (Schakel, Knoop, van Arem, TRR 2188, 2010), interaction term only:
    s* = s0 + max(0, v T + v (v - v_lead) / (2 sqrt(a b))),   a_int = a (1 - (s*/s)^2),
so that at equal speeds the equilibrium gap is exactly s0 + v T (plain IDM's free-road term would widen it by
1 / sqrt(1 - (v/v0)^delta)). The command is min(a_free, a_int) clipped to [-b_max, a_max].
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["curve_speed", "envelope_accel", "idm_plus_accel", "path_envelope_accel"]


def curve_speed(kappa: np.ndarray, lateral_accel_max: float) -> np.ndarray:
    """Largest speed with lateral acceleration v^2 |kappa| <= ``lateral_accel_max`` (m/s); inf on straights."""
    k = np.abs(np.asarray(kappa, dtype=float))
    with np.errstate(divide="ignore"):
        return np.where(k > 1e-9, np.sqrt(lateral_accel_max / np.maximum(k, 1e-300)), np.inf)


_BRAKE_CURVE_MARGIN = 0.5  # m/s below a braking curve at which its exact braking term starts to apply


def envelope_accel(v: float, d: np.ndarray, v_cap: np.ndarray, *, gain: float, decel_plan: float,
                   min_distance: float) -> tuple[float, float]:
    """Acceleration command (m/s^2) keeping the speed under the envelope of the caps ahead, and v_target (m/s).

    Parameters
    ----------
    v : float
        Current speed (m/s).
    d : np.ndarray
        (M,) distances ahead along the path of the capped points (m); d[0] = 0 is the car's own position.
    v_cap : np.ndarray
        (M,) speed caps at those points (m/s), finite.
    gain : float
        Speed-tracking gain k_v (1/s).
    decel_plan : float
        Deceleration b_plan of the planning envelope (m/s^2).
    min_distance : float
        Caps nearer than this (m) use only the tracking term.
    """
    d = np.maximum(np.asarray(d, dtype=float), 0.0)
    v_cap = np.asarray(v_cap, dtype=float)
    v_cap2 = v_cap ** 2
    v_curve = np.sqrt(v_cap2 + 2.0 * decel_plan * d)  # braking curve of each cap, evaluated here
    v_target = float(v_curve.min())
    a = gain * (v_target - v)
    # exact braking only for caps whose braking curve the car has (nearly) reached: a car creeping far below the
    # curve must be allowed to speed up, not held at a standstill by a tiny braking demand
    far = (d >= min_distance) & (v_cap < v) & (v >= v_curve - _BRAKE_CURVE_MARGIN)
    if far.any():
        a = min(a, float(((v_cap2[far] - v * v) / (2.0 * d[far])).min()))
    return a, v_target


@njit(cache=True)
def path_envelope_accel(v, s, cap, i0, i1, s_car, stop_d, with_stop, gain, decel_plan, min_distance):
    """:func:`envelope_accel` (its first value) of the caps ``cap[i0:i1]`` of a lane path's points at arc lengths
    ``s[i0:i1]`` seen from arc length ``s_car`` (the first point at distance 0: the car's own segment), and, if
    ``with_stop``, of a stop line (cap 0) ``stop_d`` m ahead; the same operations on each point, in compiled scalar
    code (a driver's step calls it with a few dozen points: numpy's per-call overhead would be most of the cost)."""
    v_target, brake = np.inf, np.inf
    vals = i1 - i0 + (1 if with_stop else 0)
    for q in range(vals):
        if q == i1 - i0:
            dq, cq = max(stop_d, 0.0), 0.0
        else:
            dq, cq = (0.0 if q == 0 else max(s[i0 + q] - s_car, 0.0)), cap[i0 + q]
        vc = math.sqrt(cq * cq + 2.0 * decel_plan * dq)
        v_target = min(v_target, vc)
        if dq >= min_distance and cq < v and v >= vc - _BRAKE_CURVE_MARGIN:
            brake = min(brake, (cq * cq - v * v) / (2.0 * dq))
    a = gain * (v_target - v)
    if brake < np.inf:
        a = min(a, brake)
    return a


def idm_plus_accel(v: float, v_lead: float, gap: float, *, s0: float, time_headway: float, accel: float,
                   decel: float) -> float:
    """IDM+ interaction acceleration a (1 - (s*/s)^2) behind a leader ``gap`` metres ahead (bumper to bumper)."""
    s_star = s0 + max(0.0, v * time_headway + v * (v - v_lead) / (2.0 * np.sqrt(accel * decel)))
    s = max(gap, 1e-3)
    return float(accel * (1.0 - (s_star / s) ** 2))
