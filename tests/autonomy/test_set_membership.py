"""Set-membership estimator on unions of polygons: outer approximations, the three stages, the guarantee."""

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from autonomy.estimation.setmem import polygons as pg
from autonomy.estimation.setmem.estimator import (
    SetEstimate,
    SetMembershipConfig,
    SetMembershipEstimator,
    free_search_area,
)
from autonomy.guidance.search.planner import SearchConfig
from autonomy.sensing.measurement import Detection
from simulator.kinematic.search_mission import MissionConfig, SearchMission
from worlds.geometry import Building

AREA = shapely.box(0.0, 0.0, 400.0, 400.0)


def box_det(z, b=5.0):
    return Detection(z=np.asarray(z, float), R=np.eye(2) * b**2 / 3, t_meas=0.0, t_arrival=0.0, sensor_id="box",
                     p_sensor_W=np.zeros(3), kind="box", bound=np.array([b, b]))


# ---------------------------------------------------------------- outer approximations


@pytest.mark.parametrize("quad_segs", [1, 2, 4])
def test_dilation_contains_the_exact_minkowski_sum(quad_segs):
    sq = shapely.box(0, 0, 10, 10)
    r = 2.0
    D = pg.dilate(sq, r, quad_segs)
    exact = 100 + 4 * 10 * r + np.pi * r**2
    assert D.area >= exact - 1e-9
    r_out = r / np.cos(np.pi / (4 * quad_segs))  # the enlarged radius bounds the result from above
    assert D.area <= 100 + 4 * 10 * r_out + np.pi * r_out**2
    # every point at distance r from a corner (the arcs the buffer approximates) is inside
    th = np.linspace(0, 2 * np.pi, 721)
    for c in [(0, 0), (10, 0), (10, 10), (0, 10)]:
        ring = np.column_stack([c[0] + r * np.cos(th), c[1] + r * np.sin(th)])
        assert np.all(pg.contains_points(D, ring, tol=1e-9))


def test_plain_buffer_would_not_be_outer():
    """The enlargement is needed: shapely's own buffer leaves points of the true dilation outside."""
    r = 2.0
    B = shapely.buffer(shapely.Point(0, 0), r, quad_segs=2)
    th = np.linspace(0, 2 * np.pi, 721)
    circle = np.column_stack([r * np.cos(th), r * np.sin(th)])
    assert not np.all(pg.contains_points(B, circle, tol=1e-9))
    assert np.all(pg.contains_points(pg.dilate(shapely.Point(0, 0).buffer(1e-9), r, 2), circle, tol=1e-9))


def test_outer_simplify_contains_and_reduces():
    rng = np.random.default_rng(3)
    th = np.sort(rng.uniform(0, 2 * np.pi, 3000))
    rad = 100 + rng.uniform(-3, 3, th.size)
    star = shapely.Polygon(np.column_stack([rad * np.cos(th), rad * np.sin(th)])).buffer(0)
    tol = 0.5
    S = pg.outer_simplify(star, tol)
    assert shapely.difference(star, S).area < 1e-9
    assert pg.n_vertices(S) < pg.n_vertices(star) / 3
    # the added area is at most the boundary grown by the buffer width 2 tol
    assert S.area - star.area <= 2 * tol * star.length


def test_boxes_union_and_components():
    U = pg.boxes_union(np.array([[0, 0], [3, 0], [50, 50]]), np.array([2.0, 2.0]))
    assert U.area == pytest.approx(16 + 16 - 4 + 16)
    comps = pg.components(U)
    assert [round(c.area) for c in comps] == [28, 16]


# ---------------------------------------------------------------- estimator stages


def make_est(**kw):
    return SetMembershipEstimator(SetMembershipConfig(**kw), AREA)


def test_config_validation_names_field():
    with pytest.raises(ValueError, match="max_target_speed"):
        SetMembershipConfig(max_target_speed=0.0)
    with pytest.raises(ValueError, match="quad_segs"):
        SetMembershipConfig(quad_segs=0)


def test_initial_sets_and_free_area():
    b = Building.cuboid((100, 100), (40, 20, 100))
    free = free_search_area(AREA, [b])
    assert free.area == pytest.approx(400 * 400 - 800)
    est = SetMembershipEstimator(SetMembershipConfig(), free)
    assert est.estimate.X.is_empty
    assert est.normalized_areas() == (0.0, pytest.approx(1.0))


def test_observed_square_then_prediction_closed_form():
    """Xbar = A \\ F; one prediction erodes the hole F by r: area A - (a - 2r)^2 (outer: never below it)."""
    est = make_est(quad_segs=3)
    a, r = 80.0, 5.0 / 3.6
    F = shapely.box(100, 100, 100 + a, 100 + a)
    est.predict(1.0)  # inside the area nothing changes
    assert est.estimate.area_Xbar == pytest.approx(AREA.area, rel=1e-9)
    est.update(F, [])
    assert est.estimate.area_Xbar == pytest.approx(AREA.area - a * a, rel=1e-9)
    est.predict(2.0)
    exact = AREA.area - (a - 2 * r) ** 2
    got = est.estimate.area_Xbar
    assert got >= exact - 1e-6
    assert got - exact < 4 * a * r * (1 / np.cos(np.pi / 12) - 1) + 1.0


def test_detection_moves_box_to_X_and_unseen_view_erases_it():
    est = make_est()
    F = shapely.box(100, 100, 180, 180)
    est.predict(1.0)
    est.update(F, [box_det([140.0, 150.0])])
    e = est.estimate
    assert e.area_X == pytest.approx(100.0)
    assert e.in_X(np.array([[140.0 + 4.9, 150.0 - 4.9]]))[0]
    # next step the same region is in view and nothing is detected (a decoy seen outside its cone): X is erased
    est.predict(2.0)
    est.update(F, [])
    assert est.estimate.X.is_empty
    # a box detected outside X U Xbar (an already cleared region) adds nothing
    est.predict(3.0)
    est.update(F, [box_det([140.0, 150.0])])
    assert est.estimate.area_X == pytest.approx(0.0, abs=1e-9)


def test_unobserved_X_grows_by_dilation():
    est = make_est(quad_segs=4)
    est.predict(1.0)
    est.update(shapely.box(100, 100, 180, 180), [box_det([140.0, 150.0])])
    est.predict(11.0)  # 10 s unobserved: the 10 m box grows by 13.9 m on every side
    r = 10 * 5.0 / 3.6
    exact = 100 + 4 * 10 * r + np.pi * r**2
    assert est.estimate.area_X >= exact - 1e-6
    assert est.estimate.area_X <= exact * 1.03


def test_fusion_intersects_xbar_and_removes_proven_empty_from_X():
    e1, e2 = make_est(), make_est()
    F1 = shapely.box(100, 100, 180, 180)
    F2 = shapely.box(150, 100, 230, 180)
    for e in (e1, e2):
        e.predict(1.0)
    e1.update(F1, [box_det([160.0, 140.0])])  # UAV 1 takes something for a target
    e2.update(F2, [])  # UAV 2 sees the same spot and detects nothing (decoy outside its cone)
    s1, s2 = e1.shared, e2.shared
    f1 = e1.fuse([s2])
    assert f1.area_Xbar == pytest.approx(AREA.area - shapely.union(F1, F2).area, rel=1e-9)
    assert f1.X.is_empty  # proven empty by UAV 2
    # without UAV 2's view of the box, the fused X keeps it
    e3 = make_est()
    e3.predict(1.0)
    e3.update(shapely.box(300, 300, 380, 380), [])
    f1b = SetMembershipEstimator(SetMembershipConfig(), AREA)
    f1b.reset(s1)
    assert f1b.fuse([e3.shared]).area_X == pytest.approx(100.0)


def test_fusion_rejects_mismatched_times():
    e1 = make_est()
    e1.predict(1.0)
    e1.update(shapely.box(0, 0, 10, 10), [])
    with pytest.raises(ValueError, match="fusing"):
        e1.fuse([SetEstimate(t=0.0, X=pg.EMPTY, Xbar=AREA)])


def test_prediction_with_simplification_stays_outer():
    """A jagged set over the vertex budget is simplified, and still contains the exact dilation."""
    rng = np.random.default_rng(5)
    th = np.sort(rng.uniform(0, 2 * np.pi, 1500))
    rad = 120 + rng.uniform(-4, 4, th.size)
    jagged = shapely.Polygon(np.column_stack([200 + rad * np.cos(th), 200 + rad * np.sin(th)])).buffer(0)
    est = SetMembershipEstimator(SetMembershipConfig(max_vertices=100, simplify_tol=0.5), AREA)
    est.reset(SetEstimate(t=0.0, X=pg.EMPTY, Xbar=jagged))
    est.predict(1.0)
    assert est.stats.simplifications >= 1
    assert pg.n_vertices(est.estimate.Xbar) < pg.n_vertices(jagged)
    inner = jagged.buffer(5.0 / 3.6, quad_segs=32)  # inscribed arcs: inside the exact dilation
    assert shapely.difference(inner, est.estimate.Xbar).area < 1e-6


# ---------------------------------------------------------------- the guarantee in closed loop


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), n_obstacles=st.integers(1, 3), n_uavs=st.integers(1, 3),
       control=st.sampled_from(["random", "mpc"]))
def test_true_targets_always_inside_X_or_Xbar(seed, n_obstacles, n_uavs, control):
    """Random or MPC turns, random target motion within the bound, box sensor among buildings, decoys, fusion."""
    cfg = MissionConfig(area_size=(180.0, 180.0), n_uavs=n_uavs, n_targets=2, n_decoys=2, n_obstacles=n_obstacles,
                        obstacle_sides=(15.0, 35.0), steps=30, control=control,
                        search=SearchConfig(speed=10.0, altitude=60.0),
                        estimator=SetMembershipConfig(max_vertices=200, simplify_tol=0.3))
    mission = SearchMission(cfg, np.random.default_rng(seed))
    res = mission.run()
    assert res.guarantee.all(), f"targets left the sets at steps {np.argwhere(~res.guarantee)[:5]}"
    for est in mission.estimators:
        e = est.estimate
        # the sets stay inside the free area
        assert shapely.difference(e.support, mission.free_area.buffer(1e-6)).area < 1e-6
    # the test is not vacuous: the sensors cleared part of the area
    assert res.area_Xbar.min() < 0.95


def test_dilate_recomputes_an_invalid_buffer_with_more_segments(monkeypatch):
    """A self-intersecting buffer from GEOS is not passed on: the next quad_segs is tried, still an outer bound."""
    real = shapely.buffer
    calls = []

    def flaky(geom, distance, quad_segs=8, **kw):
        calls.append(quad_segs)
        if len(calls) == 1:  # a bow-tie, as GEOS once returned
            return shapely.Polygon([(0, 0), (1, 1), (1, 0), (0, 1)])
        return real(geom, distance, quad_segs=quad_segs, **kw)

    monkeypatch.setattr(pg.shapely, "buffer", flaky)
    sq = shapely.box(0, 0, 10, 10)
    D = pg.dilate(sq, 2.0, 2)
    assert calls == [2, 3] and D.is_valid
    a = np.linspace(0.0, np.pi / 2, 50)
    corner = np.column_stack([10 + 1.999 * np.cos(a), 10 + 1.999 * np.sin(a)])  # inside the exact dilation
    assert D.contains(shapely.box(-2, 0, 12, 10)) and D.contains(shapely.box(0, -2, 10, 12))
    assert np.all(pg.contains_points(D, corner, tol=0.0))


def test_uavs_fusing_the_same_sets_get_the_same_result_and_adopt_keeps_the_shared_set():
    """Fusion combines the sets in the order of their owners: any member of a linked group computes the group's
    result to the last bit, so the mission computes it once and the others adopt it."""
    ests = [SetMembershipEstimator(SetMembershipConfig(), AREA, owner=k) for k in range(3)]
    views = [shapely.box(100, 100, 180, 180), shapely.box(150, 120, 190, 200), shapely.Point(170, 150).buffer(45)]
    for e, F, dets in zip(ests, views, ([box_det([160.0, 140.0])], [], [box_det([205.0, 150.0])]), strict=True):
        e.predict(1.0)
        e.update(F, dets)
    shared = [e.shared for e in ests]
    f0 = ests[0].fuse([shared[1], shared[2]])
    f1 = ests[1].fuse([shared[2], shared[0]])
    assert shapely.equals_exact(f0.X, f1.X, 0.0) and shapely.equals_exact(f0.Xbar, f1.Xbar, 0.0)
    assert f0.area_X > 0 and f0.area_Xbar < AREA.area - views[0].area  # a real fusion happened
    adopted = ests[2].adopt(f0)
    assert adopted.owner == 2 and shapely.equals_exact(adopted.X, f0.X, 0.0)
    assert ests[2].shared is shared[2]  # what UAV 2 sends next is still its own corrected set
    with pytest.raises(ValueError, match="adopting"):
        ests[2].adopt(SetEstimate(t=5.0, X=f0.X, Xbar=f0.Xbar))
