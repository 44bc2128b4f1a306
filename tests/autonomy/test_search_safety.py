"""Safe-loiter constraint of the search MPC: loiter geometry, clearance by construction, its failure without it."""

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from autonomy.estimation.setmem import polygons as pg
from autonomy.estimation.setmem.estimator import SetEstimate
from autonomy.guidance.search.planner import SearchConfig, SearchPlanner
from autonomy.guidance.search.regions import PrismViewRegion
from autonomy.guidance.search.safety import TOL, LoiterSafety
from autonomy.sensing.box_sensor import BoxSensorConfig
from simulator.kinematic.search_mission import MissionConfig, SearchMission
from worlds.geometry import Building

AREA = shapely.box(0.0, 0.0, 500.0, 500.0)
FOOT = np.sqrt(2) * 100 * np.tan(np.pi / 8)
CFG = SearchConfig()


def planner(buildings, cfg=CFG, keep_in=None):
    obst = shapely.union_all([shapely.Polygon(b.footprint) for b in buildings])
    return SearchPlanner(cfg, PrismViewRegion(BoxSensorConfig(), buildings), shapely.difference(AREA, obst),
                         buildings, footprint_radius=FOOT, keep_in=keep_in)


BOX = shapely.box(200, 200, 260, 260)


def safety(cfg=CFG, obstacles=BOX, keep_in=None):
    return LoiterSafety(speed=cfg.speed, dt=cfg.dt, max_turn=cfg.max_turn, required=cfg.d_col + cfg.clearance_margin,
                        obstacles=obstacles, keep_in=keep_in)


def fly(pl, p, psi, est, steps):
    """Closed loop of the discrete model with a fixed estimate; returns the flown chords' obstacle distances (m)
    and the number of decisions taken without a safe candidate."""
    d, unsafe = [], 0
    for _ in range(steps):
        dec = pl.decide(p, psi, est)
        unsafe += not dec.safe
        psi = psi + dec.u
        q = p + pl.config.speed * pl.config.dt * np.array([np.cos(psi), np.sin(psi)])
        d.append(float(shapely.distance(pl._obstacles, shapely.LineString([p, q]))))
        p = q
    return np.array(d), unsafe


@pytest.mark.parametrize("max_turn", [np.pi / 4, np.pi / 6, np.pi])
def test_closed_loiter_is_the_regular_polygon(max_turn):
    """Holding +-u_max closes an n-gon on the circle of radius R about the centre; its last chord is the one flown
    into the state."""
    s = safety(SearchConfig(max_turn=max_turn))
    p, psi = np.array([[50.0, 40.0]]), np.array([0.7])
    v = s.loiter(p, psi)
    n = round(2 * np.pi / max_turn)
    assert s.n_chords == n and v.shape == (1, 2, n + 1, 2)
    c = s.centres(p, psi)
    for side in range(2):
        np.testing.assert_allclose(v[0, side, -1], p[0], atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(v[0, side] - c[0, side], axis=1), s.radius, rtol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(np.diff(v[0, side], axis=0), axis=1), CFG.speed * CFG.dt,
                                   rtol=1e-12)
        prev = p[0] - CFG.speed * CFG.dt * np.array([np.cos(psi[0]), np.sin(psi[0])])
        np.testing.assert_allclose(v[0, side, -2], prev, atol=1e-9)
    a, b = v[0, 0, 1] - p[0], c[0, 0] - p[0]
    assert a[0] * b[1] - a[1] * b[0] > 0  # left loiter turns counter-clockwise


def test_clearance_closed_form():
    """A state heading east with the obstacle due north: the right loiter (clockwise, away) is clear by its
    distance; the left one runs into the obstacle."""
    s = safety(obstacles=shapely.box(-100, 30, 100, 50))
    c = s.clearance(np.array([[0.0, 0.0]]), np.array([0.0]))[0]
    v = s.loiter(np.array([[0.0, 0.0]]), np.array([0.0]))[0]
    assert v[0, :, 1].max() > 30.0  # the left octagon reaches 2 apothems north, into the obstacle
    assert v[1, :, 1].max() == pytest.approx(0.0, abs=1e-9)  # the right one's northmost points are on y = 0
    assert c == pytest.approx(30.0)
    assert s.is_safe(np.array([[0.0, 0.0]]), np.array([0.0]))[0]
    # heading at it from 15 m: either loiter first swings 11.8 m further north, 3.2 m from the obstacle
    assert s.clearance(np.array([[0.0, 15.0]]), np.array([np.pi / 2]))[0] == pytest.approx(15 - 11.785, abs=1e-3)
    assert not s.is_safe(np.array([[0.0, 15.0]]), np.array([np.pi / 2]))[0]
    # far from everything: lower bound, still safe
    assert s.clearance(np.array([[0.0, -400.0]]), np.array([1.0]))[0] >= 400 - 80 - 2 * s.radius


def test_non_closing_turn_uses_the_disc():
    s = safety(SearchConfig(max_turn=0.7), obstacles=shapely.box(-100, 40, 100, 80))
    assert s.n_chords is None
    c = s.centres(np.array([[0.0, 0.0]]), np.array([0.0]))
    got = s.clearance(np.array([[0.0, 0.0]]), np.array([0.0]))[0]
    assert c[0, 0, 1] > 0 > c[0, 1, 1]
    assert got == pytest.approx(40.0 - c[0, 1, 1] - s.radius)  # the right disc, away from the obstacle


def test_keep_in_area_is_enforced():
    s = safety(obstacles=shapely.GeometryCollection(), keep_in=AREA)
    assert s.active
    assert s.is_safe(np.array([[250.0, 250.0]]), np.array([0.0]))[0]
    # 10 m inside the west border heading west: both loiters leave the area
    assert not s.is_safe(np.array([[10.0, 250.0]]), np.array([np.pi]))[0]


def head_on(cfg):
    """A UAV 70 m south of a 200 m wide obstacle, heading north at it, with the only undetected set right behind
    it: the distance term rewards flying into the obstacle."""
    b = Building.cuboid((250, 300), (200, 40, 100))
    pl = planner([b], cfg)
    est = SetEstimate(t=0.0, X=pg.EMPTY, Xbar=shapely.box(230, 322, 270, 360))
    return pl, np.array([250.0, 210.0]), np.pi / 2, est


@pytest.mark.parametrize("alpha_s", [0.0, CFG.alpha_s], ids=["no_risk_term", "paper_risk_term"])
def test_head_on_keeps_clearance(alpha_s):
    pl, p, psi, est = head_on(SearchConfig(alpha_s=alpha_s))
    assert pl.safety.is_safe(p, psi)[0]
    d, unsafe = fly(pl, p, psi, est, 60)
    assert unsafe == 0
    assert d.min() >= CFG.d_col + CFG.clearance_margin - TOL
    if alpha_s == 0.0:  # it does go to the obstacle: the constraint, not the cost, keeps it off
        assert d.min() < 2 * (CFG.d_col + CFG.clearance_margin)


def test_head_on_without_the_constraint_collides():
    """The same set-up with the paper's planner (no safe loiter, no risk term) flies into the obstacle."""
    pl, p, psi, est = head_on(SearchConfig(alpha_s=0.0, loiter_safety=False))
    assert pl.safety is None
    d, _ = fly(pl, p, psi, est, 60)
    assert d.min() < CFG.d_col


def test_unsafe_start_takes_the_clearest_candidate_and_says_so():
    b = Building.cuboid((250, 300), (200, 40, 100))
    pl = planner([b])
    est = SetEstimate(t=0.0, X=pg.EMPTY, Xbar=AREA)
    dec = pl.decide(np.array([250.0, 270.0]), np.pi / 2, est)  # 10 m from the wall, heading at it
    assert not dec.safe and not dec.admissible.any()
    clear = pl.safety.clearance(
        np.array([250.0, 270.0]) + CFG.speed * np.column_stack([np.cos(np.pi / 2 + dec.controls),
                                                                np.sin(np.pi / 2 + dec.controls)]),
        np.pi / 2 + dec.controls)
    assert dec.clearance == pytest.approx(clear.max())


layouts = st.lists(
    st.tuples(st.floats(120, 380), st.floats(120, 380), st.floats(8, 90), st.floats(8, 90), st.floats(0, np.pi / 2)),
    min_size=1, max_size=4)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(boxes=layouts, seed=st.integers(0, 2**32 - 1))
def test_property_planner_flies_clear_of_random_layouts(boxes, seed):
    """Random obstacles, a random safe start and a random undetected patch to chase: every flown chord keeps
    d_col + margin from every obstacle."""
    bs = [Building.cuboid((x, y), (sx, sy, 100), yaw=yaw) for x, y, sx, sy, yaw in boxes]
    pl = planner(bs)
    rng = np.random.default_rng(seed)
    for _ in range(1000):
        p, psi = rng.uniform(50, 450, 2), rng.uniform(-np.pi, np.pi)
        if pl.safety.is_safe(p, psi)[0] and not shapely.contains_xy(pl._obstacles, *p):
            break
    else:
        pytest.skip("no safe start drawn")
    c = rng.uniform(60, 440, 2)
    est = SetEstimate(t=0.0, X=pg.EMPTY, Xbar=shapely.box(*(c - 15), *(c + 15)))
    d, unsafe = fly(pl, p, psi, est, 40)
    assert unsafe == 0
    assert d.min() >= CFG.d_col + CFG.clearance_margin - TOL


@settings(max_examples=60, deadline=None)
@given(boxes=layouts, seed=st.integers(0, 2**32 - 1), max_turn=st.sampled_from([np.pi / 4, 0.7, np.pi / 3]))
def test_property_any_admissible_choice_stays_clear(boxes, seed, max_turn):
    """Adversarial version of the induction: at every step pick a random candidate among those whose next state
    is safe; there always is one, and every chord keeps the clearance (closed polygons and the disc)."""
    cfg = SearchConfig(max_turn=max_turn)
    obst = shapely.union_all([shapely.Polygon(Building.cuboid((x, y), (sx, sy, 100), yaw=yaw).footprint)
                              for x, y, sx, sy, yaw in boxes])
    s = safety(cfg, obstacles=obst)
    rng = np.random.default_rng(seed)
    for _ in range(1000):
        p, psi = rng.uniform(50, 450, 2), rng.uniform(-np.pi, np.pi)
        if s.is_safe(p, psi)[0]:
            break
    else:
        pytest.skip("no safe start drawn")
    u = cfg.controls()
    for _ in range(100):
        nxt = p + cfg.speed * cfg.dt * np.column_stack([np.cos(psi + u), np.sin(psi + u)])
        ok = s.is_safe(nxt, psi + u)
        assert ok.any()
        j = rng.choice(np.flatnonzero(ok))
        assert shapely.distance(obst, shapely.LineString([p, nxt[j]])) >= s.required - TOL
        p, psi = nxt[j], psi + u[j]


def test_mission_starts_are_safe_and_no_chord_comes_within_d_col():
    cfg = MissionConfig(area_size=(250.0, 250.0), n_uavs=3, n_targets=1, n_decoys=0, n_obstacles=3,
                        obstacle_sides=(20.0, 50.0), steps=40)
    m = SearchMission(cfg, np.random.default_rng(3))
    assert m.planner.safety.is_safe(m.uav_xy, m.uav_heading).all()
    r = m.run()
    assert not r.unsafe_decisions.any()
    assert r.min_obstacle_distance.min() >= CFG.d_col + CFG.clearance_margin - TOL
