"""The car control's scalar and cached forms give the array formulas' results to the last bit (recorded runs depend
on it): lane-path reads, the speed envelope, the speed caps and the wheel speeds."""

import math

import numpy as np

from car_fixtures import s_curve_network
from vehicles.car.body import _wheel_speed_list, wheel_speeds
from vehicles.car.driver import Driver
from vehicles.car.driver_config import DriverConfig
from vehicles.car.lane_path import LanePath, _closest_segment
from vehicles.car.longitudinal import _BRAKE_CURVE_MARGIN, curve_speed, envelope_accel, path_envelope_accel
from vehicles.car.params import load_car
from vehicles.car.route import Route

SEDAN = load_car("sedan")


def _bits(x: float) -> bytes:
    return np.float64(x).tobytes()


def _path() -> LanePath:
    net = s_curve_network()
    return LanePath([net.roads[r] for r in "abcde"], [0] * 5, s_start=3.7, ds=1.0, corner_length=7.0)


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def test_projection_heading_and_arc_length_equal_the_array_formula():
    path = _path()
    rng = np.random.default_rng(3)
    n = len(path.xy)
    seg = np.linalg.norm(np.diff(path.xy, axis=0), axis=1)
    t = np.diff(path.xy, axis=0) / np.maximum(seg, 1e-12)[:, None]
    for _ in range(2000):
        q = path.xy[int(rng.integers(n))] + rng.normal(0, 2.0, 2)
        hint = int(rng.integers(n))
        lo, hi = max(0, hint - 80), min(n - 1, hint + 80)
        k, u, lateral = _closest_segment(path.xy, t, seg, lo, hi, float(q[0]), float(q[1]))
        frac = u / max(seg[k], 1e-12)
        heading = float(path.heading[k] + frac * _wrap(path.heading[k + 1] - path.heading[k]))
        for proj in (path.project(q, hint, 80), path.project_xy(float(q[0]), float(q[1]), hint, 80)):
            assert (proj.index, _bits(proj.s), _bits(proj.lateral), _bits(proj.heading)) == \
                (k, _bits(float(path.s[k] + u)), _bits(lateral), _bits(heading))


def test_heading_wrap_in_floats_equals_the_numpy_scalar_wrap():
    rng = np.random.default_rng(5)
    for a in np.r_[rng.normal(0, 4, 20000), rng.normal(0, 1e5, 2000), 0.0, -0.0, np.pi, -np.pi, 2 * np.pi, 1e-300]:
        f = float(a)
        assert _bits((f + math.pi) % (2 * math.pi) - math.pi) == _bits(_wrap(np.float64(a)))


def test_locate_and_search_equal_the_searchsorted_formula():
    path = _path()
    rng = np.random.default_rng(11)
    seg = np.linalg.norm(np.diff(path.xy, axis=0), axis=1)
    queries = np.r_[rng.uniform(-5.0, path.length + 5.0, 3000), path.s, 0.0, path.length]
    for q in queries:
        assert path.search(float(q)) == int(np.searchsorted(path.s, q, side="right"))
        s = min(max(float(q), 0.0), float(path.s[-1]))
        k = min(max(int(np.searchsorted(path.s, s, side="right")) - 1, 0), len(path.s) - 2)
        frac = (s - path.s[k]) / max(seg[k], 1e-12)
        if path.road_index[k] != path.road_index[k + 1]:
            ref = int(path.road_index[k]), float(path.road_s[k])
        else:
            ref = int(path.road_index[k]), float(path.road_s[k] + frac * (path.road_s[k + 1] - path.road_s[k]))
        got = path.locate(float(q))
        assert got[0] == ref[0] and _bits(got[1]) == _bits(ref[1])


def _envelope_reference(v, d, v_cap, *, gain, decel_plan, min_distance):
    """envelope_accel as first written (numpy reductions, the cap squared twice)."""
    d = np.maximum(np.asarray(d, dtype=float), 0.0)
    v_cap = np.asarray(v_cap, dtype=float)
    v_curve = np.sqrt(v_cap ** 2 + 2.0 * decel_plan * d)
    v_target = float(np.min(v_curve))
    a = gain * (v_target - v)
    far = (d >= min_distance) & (v_cap < v) & (v >= v_curve - _BRAKE_CURVE_MARGIN)
    if np.any(far):
        a = min(a, float(np.min((v_cap[far] ** 2 - v * v) / (2.0 * d[far]))))
    return a, v_target


def test_envelope_equals_the_reference_formula():
    rng = np.random.default_rng(2)
    for _ in range(3000):
        m = int(rng.integers(2, 90))
        d = np.sort(rng.uniform(-1.0, 80.0, m))
        cap = rng.uniform(0.0, 20.0, m)
        if rng.random() < 0.5:
            d, cap = np.append(d, rng.uniform(-2.0, 60.0)), np.append(cap, 0.0)
        v = float(rng.uniform(0.0, 18.0))
        kw = dict(gain=float(rng.uniform(0.5, 2.0)), decel_plan=float(rng.uniform(1.0, 3.0)),
                  min_distance=max(2.0, 2 * v / 40))
        got, ref = envelope_accel(v, d, cap, **kw), _envelope_reference(v, d, cap, **kw)
        assert (_bits(got[0]), _bits(got[1])) == (_bits(ref[0]), _bits(ref[1]))


def test_driver_speed_caps_equal_the_per_call_formula_and_follow_the_cruise_fraction():
    net = s_curve_network()
    cfg = DriverConfig(stop_probability=0.0)
    drv = Driver(config=cfg, params=SEDAN, route=Route(roads=("a", "b", "c", "d", "e")), network=net,
                 rng=np.random.default_rng(0))
    for fraction in (drv.cruise_fraction, 0.7, 0.95, 0.7):
        drv.cruise_fraction = fraction
        path = drv.path
        for i0, i1 in ((0, 2), (10, 70), (len(path.s) - 2, len(path.s))):
            ahead = slice(i0, i1)
            ref = np.minimum(curve_speed(path.kappa[ahead], cfg.lateral_accel_max),
                             np.minimum(fraction * path.speed_limit[ahead], SEDAN.max_speed))
            assert drv._caps()[ahead].tobytes() == ref.tobytes()


def test_wheel_speed_list_equals_the_array_formula():
    rng = np.random.default_rng(4)
    for _ in range(2000):
        v, delta = float(rng.uniform(-2.0, 30.0)), float(rng.uniform(-0.6, 0.6))
        tau = math.tan(delta)
        v_r = v * math.cos(math.atan(0.5 * tau))
        q = 0.5 * SEDAN.track * tau / SEDAN.wheelbase
        rl, rr = 1.0 - q, 1.0 + q
        ref = v_r / SEDAN.wheel_radius * np.array([math.hypot(rl, tau), math.hypot(rr, tau), rl, rr])
        assert np.array(_wheel_speed_list(v, delta, SEDAN)).tobytes() == ref.tobytes()
        assert wheel_speeds(v, delta, SEDAN).tobytes() == ref.tobytes()


def test_path_envelope_equals_envelope_accel_on_a_path_with_and_without_a_stop_line():
    """The compiled envelope a driver's step uses reads the caps of the path points from the car's segment on (the
    first at distance 0) and a stop line: the same bits as envelope_accel of those distances and caps."""
    rng = np.random.default_rng(5)
    for _ in range(3000):
        n = int(rng.integers(3, 120))
        s = np.cumsum(np.r_[0.0, rng.uniform(0.2, 1.2, n - 1)])
        cap = rng.uniform(0.0, 20.0, n)
        i0 = int(rng.integers(0, n - 2))
        i1 = int(rng.integers(i0 + 2, n + 1))
        s_car = float(s[i0] + rng.uniform(0.0, s[i0 + 1] - s[i0]))
        with_stop = bool(rng.random() < 0.5)
        stop_d = float(rng.uniform(-2.0, 60.0))
        v = float(rng.uniform(0.0, 18.0))
        kw = dict(gain=float(rng.uniform(0.5, 2.0)), decel_plan=float(rng.uniform(1.0, 3.0)),
                  min_distance=max(2.0, 2 * v / 40))
        d = np.r_[0.0, s[i0 + 1:i1] - s_car]
        c = cap[i0:i1]
        if with_stop:
            d, c = np.r_[d, stop_d], np.r_[c, 0.0]
        ref, _ = envelope_accel(v, d, c, **kw)
        got = path_envelope_accel(v, s, cap, i0, i1, s_car, stop_d, with_stop, kw["gain"], kw["decel_plan"],
                                  kw["min_distance"])
        assert _bits(got) == _bits(ref)
