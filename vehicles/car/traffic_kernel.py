"""Compiled arithmetic of the built-in traffic fleet (:mod:`vehicles.car.traffic_fleet`): every car's driver step and
kinematic-bicycle ticks in one call each.

The functions repeat, operation for operation, the Python driver's common step
(:meth:`vehicles.car.driver.Driver.update` when the car neither rebuilds its lane path, changes road, redraws its
cruise speed, nor stops or starts at a stop line: :func:`drive_all` flags those cars and the fleet hands them to the
Python driver), the leader search of :func:`vehicles.car.traffic.find_leaders`, and
:meth:`vehicles.car.bicycle.KinematicBicycle.step`, so a car driven here follows the same trajectory to the last bit
(tested). Two details keep it so: powers of two are taken with an exponent passed in at run time (``two``), since the
compiler replaces a constant ``x ** 2.0`` with ``x * x``, which rounds differently from the C library's ``pow`` that
NumPy scalars use; and the heading read back from the body's quaternion (the fleet's readings of a car go through it)
is recomputed the way the quaternion-to-yaw formula does it.

Layout. Per car i, its lane path is row i of the path arrays (``P_*``, padded to a common capacity, ``P_n[i]`` points),
its junction stops row i of ``J_*``; the drivers' settings are columns of ``cfg`` (:data:`CFG`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from vehicles.car.lane_path import _closest_segment
from vehicles.car.longitudinal import path_envelope_accel

__all__ = ["CFG", "MODE_DONE", "MODE_DRIVE", "MODE_STOPPED", "ROWS", "drive_all", "integrate", "locate_all"]

CFG = ("stanley_gain", "stanley_softening", "yaw_damping", "speed_gain", "decel_plan", "decel_max", "accel_max",
       "idm_s0", "idm_time_headway", "lookahead_margin", "stop_window", "stopped_speed", "follow_range", "rate_hz",
       "path_horizon", "corner_length", "cruise_change_period", "path_ds", "length", "wheelbase", "max_steer",
       "max_steer_rate", "max_decel", "max_accel", "max_speed")
"""Columns of the per-car settings matrix: the driver's (effective accel / decel limits) and the car's."""
_C = {name: k for k, name in enumerate(CFG)}
(C_GAIN, C_SOFT, C_DAMP, C_KV, C_BPLAN, C_BMAX, C_AMAX, C_S0, C_T, C_MARGIN, C_SWIN, C_VSTOP, C_FOLLOW, C_RATE,
 C_HORIZON, C_CORNER, C_CRUISE, C_DS, C_LEN, C_WB, C_STEER, C_STEER_RATE, C_PDECEL, C_PACCEL, C_VMAX) = range(len(CFG))

ROWS = ("x", "y", "yaw", "speed", "steer", "beta", "yaw_rate", "yaw_read", "speed_fwd", "vx", "vy", "omega")
"""Columns of a buffered tick of a car: the bicycle's state after the tick (x, y, yaw, speed, steer, beta, the yaw rate
applied over the tick), then what the fleet reads of it: the heading read back from the body's quaternion, the forward
speed along it, the centre-of-mass velocity and the yaw rate of the present state."""
(R_X, R_Y, R_YAW, R_V, R_STEER, R_BETA, R_YAWRATE, R_YAWREAD, R_VFWD, R_VX, R_VY, R_OMEGA) = range(len(ROWS))

MODE_DRIVE, MODE_STOPPED, MODE_DONE = 0, 1, 2


@njit(cache=True)
def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


@njit(cache=True)
def _bisect(a, lo, hi, x, right):
    """``np.searchsorted(a[lo:hi], x, side) + lo`` for sorted ``a``: the first index in [lo, hi) with a[j] > x
    (``right``) or a[j] >= x; a plain loop, several times cheaper than the library call on short arrays."""
    while lo < hi:
        mid = (lo + hi) // 2
        if a[mid] < x or (right and a[mid] == x):
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True)
def _segment_r2(xy, t, seg, k, px, py):
    """(u, lateral, squared distance) of the point to segment k, in the operations of ``_closest_segment``."""
    dx, dy = px - xy[k, 0], py - xy[k, 1]
    tx, ty = t[k, 0], t[k, 1]
    u = min(max(dx * tx + dy * ty, 0.0), seg[k])
    rx, ry = dx - u * tx, dy - u * ty
    return u, tx * dy - ty * dx, rx * rx + ry * ry


_BOUND_STRIDE = 8  # segments between the samples of the bound
_SKIP_MARGIN = 1e-6  # m; a segment is skipped only when it is provably this much farther than the bound


@njit(cache=True)
def _closest(xy, t, seg, s, lo, hi, hint, px, py):
    """``_closest_segment`` over segments [lo, hi) (the first of equally close ones), skipping runs of segments that
    cannot be the closest: a segment k' after k lies within arc length s[k' + 1] - s[k] of point k, so it is farther
    from the query than |p - xy[k]| - (s[k' + 1] - s[k]); runs farther than a bound (the distance to the segments
    near ``hint`` and to every :data:`_BOUND_STRIDE`-th one, plus :data:`_SKIP_MARGIN`) are jumped in one search.
    Segments as close as the bound are all examined in order, so the result is exactly the full scan's."""
    best_b = np.inf
    h = min(max(hint, lo), hi - 1)
    for k in range(max(lo, h - 2), min(hi, h + 3)):
        best_b = min(best_b, _segment_r2(xy, t, seg, k, px, py)[2])
    for k in range(lo, hi, _BOUND_STRIDE):  # and every few segments over the window, for points far from the hint
        best_b = min(best_b, _segment_r2(xy, t, seg, k, px, py)[2])
    bound = math.sqrt(best_b) + _SKIP_MARGIN
    best, k_best, u_best, lat_best = np.inf, lo, 0.0, 0.0
    k = lo
    while k < hi:
        dx, dy = px - xy[k, 0], py - xy[k, 1]
        slack = math.sqrt(dx * dx + dy * dy) - bound
        if slack > seg[k]:
            nxt = _bisect(s, k, len(s), s[k] + slack, False) - 1
            if nxt > k:
                k = min(nxt, hi)
                continue
        u, lat, r2 = _segment_r2(xy, t, seg, k, px, py)
        if r2 < best:
            best, k_best, u_best, lat_best = r2, k, u, lat
        k += 1
    return k_best, u_best, lat_best


@njit(cache=True)
def _project(xy, t, seg, s, head, npts, hint, window, px, py):
    """:meth:`LanePath.project_xy` on one packed path: (s, lateral, heading, segment index); ``hint`` < 0 searches
    the whole path."""
    n = npts - 1
    if hint < 0:
        lo, hi, h = 0, n, 0
    else:
        lo, hi, h = max(0, hint - window), min(n, hint + window), hint
    if hi <= lo:  # an empty window: the scan's answer is its start
        k, u, lat = _closest_segment(xy, t, seg, lo, hi, px, py)
    else:
        k, u, lat = _closest(xy, t, seg, s[:npts], lo, hi, h, px, py)
    frac = u / max(seg[k], 1e-12)
    return s[k] + u, lat, head[k] + frac * _wrap(head[k + 1] - head[k]), k


_LEADER_SKIP_MARGIN = 1e-6  # m; a car is passed over only when provably this much wider of the lane than allowed


@njit(cache=True)
def _leader_window(xy, tt, lanew, ridx, npts, hint, window):
    """What bounds the lateral offset of any point from the path segments ``_project(..., hint, window, ...)``
    searches, [lo, hi): (x0, x1, y0, y1) the bounding box of their points, ``cmin`` the least cosine of the turn
    between consecutive segments (0 when none is searched: nothing may be passed over), ``hmax`` the largest half lane
    width of their points, and ``hi``. A point whose nearest point on them lies inside a segment is offset by its
    distance to it; one nearest a vertex between two segments (on the outside of their turn) by at least that distance
    times the turn's cosine; nearest the first point, it is not ahead of a car on those segments; nearest the last
    point, it may lie on the extension of the last segment (any offset). So a point not beyond the last point along
    the last segment whose distance to the box times ``cmin`` exceeds ``hmax`` is no car's leader on this path."""
    n = npts - 1
    lo, hi = max(0, hint - window), min(n, hint + window)
    if hi <= lo:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, hi
    x0 = x1 = xy[lo, 0]
    y0 = y1 = xy[lo, 1]
    for k in range(lo + 1, hi + 1):
        x0, x1 = min(x0, xy[k, 0]), max(x1, xy[k, 0])
        y0, y1 = min(y0, xy[k, 1]), max(y1, xy[k, 1])
    hmax, cmin = 0.0, 1.0
    for k in range(lo, hi):
        hmax = max(hmax, 0.5 * lanew[ridx[k]])
    for k in range(lo, hi - 1):
        cmin = min(cmin, tt[k, 0] * tt[k + 1, 0] + tt[k, 1] * tt[k + 1, 1])
    return x0, x1, y0, y1, cmin, hmax, hi


@njit(cache=True)
def _cells(xy, cell):
    """Sorted uniform-grid keys of points (and the order that sorts them) for neighbour searches."""
    n = xy.shape[0]
    cx = np.empty(n, np.int64)
    cy = np.empty(n, np.int64)
    for j in range(n):
        cx[j] = int(math.floor(xy[j, 0] / cell))
        cy[j] = int(math.floor(xy[j, 1] / cell))
    keys = cx * 2097152 + cy  # |cell index| < 2^20 (the world is far smaller than 2^20 cells)
    order = np.argsort(keys, kind="mergesort")
    return keys[order], order, cx, cy


@njit(cache=True)
def drive_all(tick, X, OX, OLEN, P_xy, P_t, P_seg, P_s, P_head, P_kappa, P_cap, P_ridx, P_corner, P_lanew,
              P_laneoff, P_n, R_code, R_width, J_s, J_flag, J_n, ends_route, proj, last_code, mode, release_tick,
              next_cruise, cfg, two, out_cmd, out_flag, out_leader, out_off):
    """One driver step of every car at ``tick``; see the module docstring.

    ``X`` (N, ROWS) holds the cars' readings at ``tick``; ``OX`` (M, 4) the other (physics) cars' x, y, heading and
    forward speed, ``OLEN`` (M,) their lengths. ``proj`` (N, 4) holds each car's last projection (s, lateral,
    heading, index; index -1 before the first) and is updated for the cars stepped here. Writes per car ``out_cmd``
    (accel, steer, hold), ``out_flag`` (True: the Python driver must take this step), ``out_leader`` (gap, speed,
    index; index -1 for none, >= N for another car) and ``out_off`` (the car's centre beyond its road's lanes).
    """
    n = X.shape[0]
    m = OX.shape[0]
    allxy = np.empty((n + m, 2))
    ayaw = np.empty(n + m)
    aspd = np.empty(n + m)
    alen = np.empty(n + m)
    for j in range(n):
        allxy[j, 0], allxy[j, 1] = X[j, R_X], X[j, R_Y]
        ayaw[j], aspd[j], alen[j] = X[j, R_YAWREAD], X[j, R_VFWD], cfg[j, C_LEN]
    for j in range(m):
        allxy[n + j, 0], allxy[n + j, 1] = OX[j, 0], OX[j, 1]
        ayaw[n + j], aspd[n + j], alen[n + j] = OX[j, 2], OX[j, 3], OLEN[j]
    cell = 1.0
    for i in range(n):
        cell = max(cell, cfg[i, C_FOLLOW] + cfg[i, C_LEN])
    keys, order, cx, cy = _cells(allxy, cell)
    for i in range(n):
        npts = P_n[i]
        xy, tt, seg, ss, head = P_xy[i], P_t[i], P_seg[i], P_s[i], P_head[i]
        px, py = X[i, R_X], X[i, R_Y]
        own_s, own_lat, own_head, own_k = _project(xy, tt, seg, ss, head, npts, int(proj[i, 3]), 60, px, py)
        # leader: the nearest car ahead within half a lane of the path (vehicles.car.traffic.find_leaders)
        half_window = int(cfg[i, C_FOLLOW] / (2 * cfg[i, C_DS])) + 2
        hint = own_k + half_window
        reach2 = cfg[i, C_FOLLOW] + cfg[i, C_LEN]
        best_gap, best_v, best_j = 0.0, 0.0, -1
        wx0, wx1, wy0, wy1, cmin, hmax, whi = _leader_window(xy, tt, P_lanew[i], P_ridx[i], npts, hint,
                                                             half_window + 2)
        can_skip = cmin > 0.0
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                key = (cx[i] + dx) * 2097152 + (cy[i] + dy)
                lo = _bisect(keys, 0, len(keys), key, False)
                hi = _bisect(keys, lo, len(keys), key, True)
                for q in range(lo, hi):
                    j = order[q]
                    if j == i:
                        continue
                    ddx, ddy = allxy[j, 0] - px, allxy[j, 1] - py
                    if not math.sqrt(ddx * ddx + ddy * ddy) < reach2:
                        continue
                    if can_skip:  # provably beside this path (_leader_window): no projection needed
                        qx, qy = allxy[j, 0], allxy[j, 1]
                        ex, ey = max(wx0 - qx, 0.0, qx - wx1), max(wy0 - qy, 0.0, qy - wy1)
                        beyond = (qx - xy[whi, 0]) * tt[whi - 1, 0] + (qy - xy[whi, 1]) * tt[whi - 1, 1]
                        if (beyond < -_LEADER_SKIP_MARGIN
                                and math.sqrt(ex * ex + ey * ey) * cmin > hmax + _LEADER_SKIP_MARGIN):
                            continue
                    sj, latj, headj, kj = _project(xy, tt, seg, ss, head, npts, hint, half_window + 2,
                                                   allxy[j, 0], allxy[j, 1])
                    if sj <= own_s:
                        continue
                    if abs(latj) > 0.5 * P_lanew[i, P_ridx[i, kj]]:
                        continue
                    gap = sj - own_s - 0.5 * (alen[i] + alen[j])
                    if best_j < 0 or gap < best_gap or (gap == best_gap and j < best_j):
                        best_gap, best_j = gap, j
                        best_v = max(0.0, aspd[j] * math.cos(ayaw[j] - headj))
        out_leader[i, 0], out_leader[i, 1], out_leader[i, 2] = best_gap, best_v, best_j
        proj[i, 0], proj[i, 1], proj[i, 2], proj[i, 3] = own_s, own_lat, own_head, own_k
        # the steps the Python driver takes: a path rebuild, a new road, a cruise draw, a stop or a start
        k = own_k
        flag = False
        if not (P_corner[i, k] or P_corner[i, min(k + 1, npts - 1)]):
            kr = P_ridx[i, k]
            short = ss[npts - 1] - own_s < cfg[i, C_HORIZON] - 4 * cfg[i, C_CORNER]
            if not (kr == 0 and (not short or ends_route[i])):
                flag = True
        if R_code[i, P_ridx[i, k]] != last_code[i]:
            flag = True
        if cfg[i, C_CRUISE] > 0 and (next_cruise[i] < 0 or tick >= next_cruise[i]):
            flag = True
        v = max(X[i, R_VFWD], 0.0)
        has_stop = False
        stop_s = 0.0
        for q in range(J_n[i]):
            if J_flag[i, q] and J_s[i, q] > own_s - 3 * cfg[i, C_SWIN]:
                has_stop, stop_s = True, J_s[i, q]
                break
        if not has_stop and ends_route[i]:
            has_stop, stop_s = True, max(ss[npts - 1] - 0.5 * cfg[i, C_LEN] - 1.0, 0.0)
        if (mode[i] == MODE_DRIVE and has_stop and stop_s - own_s < cfg[i, C_SWIN] and v < cfg[i, C_VSTOP]):
            flag = True
        if mode[i] == MODE_STOPPED and tick >= release_tick[i]:
            flag = True
        out_flag[i] = flag
        if flag:
            continue
        # off the road: the centre beyond the lanes of the road the projection lies on (FleetCars._check_road)
        q = _bisect(ss, 0, npts, min(max(own_s, 0.0), ss[npts - 1]), True) - 1
        q = min(max(q, 0), npts - 2)
        out_off[i] = abs(own_lat + P_laneoff[i, k]) > R_width[i, P_ridx[i, q]]
        # steering (Driver._steer): Stanley at the front axle with yaw-rate damping
        yaw = X[i, R_YAWREAD]
        half_l = 0.5 * cfg[i, C_WB]
        fs, flat, fhead, fk = _project(xy, tt, seg, ss, head, npts, k, 80, px + half_l * math.cos(yaw),
                                       py + half_l * math.sin(yaw))
        delta = _wrap(fhead - yaw) - math.atan2(cfg[i, C_GAIN] * flat, v + cfg[i, C_SOFT])
        if cfg[i, C_DAMP] > 0:
            delta -= cfg[i, C_DAMP] * (X[i, R_OMEGA] - v * P_kappa[i, fk])
        steer = min(max(delta, -cfg[i, C_STEER]), cfg[i, C_STEER])
        out_cmd[i, 1] = steer
        if mode[i] != MODE_DRIVE:
            out_cmd[i, 0], out_cmd[i, 2] = -cfg[i, C_BMAX], 1.0
            continue
        out_cmd[i, 2] = 0.0
        # acceleration (Driver._accel, longitudinal.envelope_accel and idm_plus_accel)
        b = cfg[i, C_BPLAN]
        reach = v * v / (2 * b) + cfg[i, C_MARGIN]
        i0 = k
        i1 = min(max(_bisect(ss, 0, npts, own_s + reach, True), i0 + 2), npts)
        with_stop = has_stop and stop_s - own_s <= reach
        min_d = max(2.0, 2 * v / cfg[i, C_RATE])
        # caps of the path points from the car's segment on (the car's own point at distance 0), then the stop line
        a = path_envelope_accel(v, ss, P_cap[i], i0, i1, own_s, stop_s - own_s, with_stop, cfg[i, C_KV], b, min_d)
        if best_j >= 0:
            am = cfg[i, C_AMAX]
            s_star = cfg[i, C_S0] + max(0.0, v * cfg[i, C_T] + v * (v - best_v) / (2.0 * math.sqrt(am * b)))
            gap_s = max(best_gap, 1e-3)
            a = min(a, am * (1.0 - (s_star / gap_s) ** two))
        out_cmd[i, 0] = min(max(a, -cfg[i, C_BMAX]), cfg[i, C_AMAX])


@njit(cache=True)
def integrate(S, cmd, cfg, dt, buf):
    """``buf.shape[1] - 1`` kinematic-bicycle ticks of every car from its state ``S`` (N, 7: x, y, yaw, speed, steer,
    beta, yaw rate) under its command ``cmd`` (N, 3: accel, steer, hold), as :meth:`KinematicBicycle.step` with
    ``dt``; ``buf[:, 0]`` must hold the readings of the start, ``buf[:, k]`` receives those after tick k (columns
    :data:`ROWS`), and ``S`` the final state."""
    n, ticks = buf.shape[0], buf.shape[1] - 1
    for i in range(n):
        x, y, yaw, spd, st = S[i, 0], S[i, 1], S[i, 2], S[i, 3], S[i, 4]
        beta, yr = S[i, 5], S[i, 6]
        target = min(max(cmd[i, 1], -cfg[i, C_STEER]), cfg[i, C_STEER])
        rate = cfg[i, C_STEER_RATE] * dt
        if cmd[i, 2] > 0.5:
            a = -cfg[i, C_PDECEL]
        else:
            a = min(max(cmd[i, 0], -cfg[i, C_PDECEL]), cfg[i, C_PACCEL])
        wb = cfg[i, C_WB]
        st_at, tan_d, cos_b = np.nan, 0.0, 1.0  # the steering angle tan_d, beta and cos_b were last computed for
        for k in range(1, ticks + 1):
            st += min(max(target - st, -rate), rate)
            if st != st_at:  # the same angle gives the same values: most ticks hold the steering
                tan_d = math.tan(st)
                beta = math.atan(0.5 * tan_d)
                cos_b, st_at = math.cos(beta), st
            yr = spd * cos_b * tan_d / wb
            ds = dt * spd
            x += ds * math.cos(yaw + beta)
            y += ds * math.sin(yaw + beta)
            yaw = (yaw + dt * yr + math.pi) % (2 * math.pi) - math.pi
            spd = min(max(0.0, spd + a * dt), cfg[i, C_VMAX])
            _reading(buf, i, k, x, y, yaw, spd, st, beta, yr, wb, tan_d, cos_b)
        S[i, 0], S[i, 1], S[i, 2], S[i, 3], S[i, 4], S[i, 5], S[i, 6] = x, y, yaw, spd, st, beta, yr


@njit(cache=True)
def _reading(buf, i, k, x, y, yaw, spd, st, beta, yr, wb, tan_st, cos_beta):
    """One buffered tick: the state, and what the fleet reads (KinematicDynamics.state_row then CarFleet._arrays);
    ``tan_st`` and ``cos_beta`` are tan(st) and cos(beta)."""
    h = yaw + beta
    vx, vy = spd * math.cos(h), spd * math.sin(h)
    omega = spd * cos_beta * tan_st / wb
    qz, qw = math.sin(0.5 * yaw), math.cos(0.5 * yaw)
    yaw_read = math.atan2(2 * (qw * qz + 0.0 * 0.0), 1 - 2 * (0.0 * 0.0 + qz * qz))
    r = buf[i, k]
    r[R_X], r[R_Y], r[R_YAW], r[R_V], r[R_STEER], r[R_BETA], r[R_YAWRATE] = x, y, yaw, spd, st, beta, yr
    r[R_YAWREAD] = yaw_read
    r[R_VFWD] = vx * math.cos(yaw_read) + vy * math.sin(yaw_read)
    r[R_VX], r[R_VY], r[R_OMEGA] = vx, vy, omega


@njit(cache=True)
def start_reading(buf, S, cfg):
    """``buf[:, 0]`` from the state ``S`` (the readings of a car at rest or after a Python-side change)."""
    for i in range(S.shape[0]):
        _reading(buf, i, 0, S[i, 0], S[i, 1], S[i, 2], S[i, 3], S[i, 4], S[i, 5], S[i, 6], cfg[i, C_WB],
                 math.tan(S[i, 4]), math.cos(S[i, 5]))


@njit(cache=True)
def locate_all(xy, P_xy, P_t, P_seg, P_s, P_head, P_ridx, P_laneoff, P_n, proj, road_s_of, out):
    """(path road index, arc length on that road, lateral offset from its centre-line) of every car's point ``xy``
    (N, 2), as :meth:`Driver.locate` (window 20 around the last projection); ``road_s_of`` (N, M) is each path
    point's arc length on its road."""
    for i in range(xy.shape[0]):
        npts = P_n[i]
        s, lat, _, k = _project(P_xy[i], P_t[i], P_seg[i], P_s[i], P_head[i], npts, int(proj[i, 3]), 20,
                                xy[i, 0], xy[i, 1])
        ss = P_s[i]
        s = min(max(s, 0.0), ss[npts - 1])
        q = _bisect(ss, 0, npts, s, True) - 1
        q = min(max(q, 0), npts - 2)
        frac = (s - ss[q]) / max(P_seg[i, q], 1e-12)
        r0, r1 = P_ridx[i, q], P_ridx[i, q + 1]
        out[i, 0] = r0
        out[i, 1] = road_s_of[i, q] if r0 != r1 else road_s_of[i, q] + frac * (road_s_of[i, q + 1] - road_s_of[i, q])
        out[i, 2] = lat + P_laneoff[i, k]
