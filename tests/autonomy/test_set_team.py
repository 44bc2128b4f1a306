"""The set-membership estimator in the run loop: scans (observed region + box detections) applied in time order, and
the team's set fusion over the links that are up."""

import numpy as np
import pytest
import shapely

from autonomy.estimation.setmem import polygons as pg
from autonomy.estimation.setmem.estimator import SetMembershipConfig, SetMembershipEstimator
from autonomy.estimation.setmem.tracker import ObservedRegion, SetMembershipTracker
from autonomy.fusion.set_team import fuse_team_sets
from autonomy.sensing.measurement import Detection

AREA = shapely.box(0.0, 0.0, 400.0, 400.0)
V = 5.0 / 3.6


def det(z, t, b=5.0):
    return Detection(z=np.asarray(z, float), R=np.eye(2) * b**2 / 3, t_meas=t, t_arrival=t, sensor_id="box",
                     p_sensor_W=np.zeros(3), kind="box", bound=np.array([b, b]))


def scan(region, t, arrival=None):
    return ObservedRegion(t_meas=t, t_arrival=t if arrival is None else arrival, region=region)


def test_a_scan_without_detections_clears_its_region_and_the_sets_reach_the_step_time():
    tr = SetMembershipTracker(SetMembershipConfig(), AREA, owner=0)
    F = shapely.box(100, 100, 180, 180)
    tr.observe(scan(F, 1.0))
    assert tr.step(1.0, []) is None  # sets, not a point estimate
    est = tr.estimator.estimate
    assert est.t == 1.0 and est.X.is_empty
    assert est.area_Xbar == pytest.approx(AREA.area - F.area, rel=1e-9)
    tr.step(3.0, [])  # no scan: the sets are predicted (the cleared square shrinks by 2 s of target motion)
    assert tr.estimator.estimate.t == 3.0 and tr.scans == 1
    r = 2 * V / np.cos(np.pi / 8)  # the outer dilation's enlarged radius (quad_segs 2)
    assert not tr.estimator.estimate.Xbar.intersects(shapely.box(100 + r, 100 + r, 180 - r, 180 - r).buffer(-0.01))
    assert tr.estimator.estimate.Xbar.covers(shapely.box(100, 100, 180, 180).exterior.buffer(2 * V - 0.01))


def test_scans_apply_in_the_order_they_were_taken_with_their_own_detections():
    """Two scans arrive at one step (the second first): each corrects with its region and its detections, so the box
    seen at t = 1 is dilated for 1 s before the second scan, which sees it empty, erases it."""
    tr = SetMembershipTracker(SetMembershipConfig(), AREA, owner=0)
    F1, F2 = shapely.box(100, 100, 180, 180), shapely.box(120, 120, 200, 200)
    tr.observe(scan(F2, 2.0))
    tr.observe(scan(F1, 1.0))
    tr.step(2.0, [det([110.0, 110.0], 1.0)])
    X = tr.estimator.estimate.X
    assert tr.scans == 2 and not X.is_empty
    # the detected box [105, 115]² grown by V, less F2
    expected = shapely.difference(shapely.box(105 - V, 105 - V, 115 + V, 115 + V), F2)
    assert X.area == pytest.approx(expected.area, rel=0.02)
    assert pg.contains_points(X, np.array([[106.0, 106.0]]), 1e-9).all()


def test_detections_without_their_scan_region_are_an_error():
    tr = SetMembershipTracker(SetMembershipConfig(), AREA, owner=0)
    with pytest.raises(ValueError, match="without the region"):
        tr.step(1.0, [det([10.0, 10.0], 1.0)])


def test_a_scan_older_than_the_sets_is_dropped_and_counted():
    tr = SetMembershipTracker(SetMembershipConfig(), AREA, owner=0)
    tr.observe(scan(shapely.box(0, 0, 50, 50), 2.0))
    tr.step(2.0, [])
    before = tr.estimator.estimate
    tr.observe(scan(shapely.box(200, 200, 250, 250), 1.0, arrival=2.5))  # taken before the sets' time
    tr.step(3.0, [])
    assert tr.late_scans == 1 and tr.scans == 1
    assert tr.estimator.estimate.area_Xbar >= before.area_Xbar  # nothing cleared, only predicted


def _team(n):
    ests = [SetMembershipEstimator(SetMembershipConfig(), AREA, owner=i) for i in range(n)]
    for i, e in enumerate(ests):
        e.predict(1.0)
        e.update(shapely.box(80 * i, 0, 80 * i + 80, 80), [])
    return ests


def test_team_fusion_equals_each_uav_fusing_its_linked_neighbours():
    ests, ref = _team(4), _team(4)
    A = np.array([[0, 1, 1, 0], [1, 0, 1, 0], [1, 1, 0, 0], [0, 0, 0, 0]], dtype=bool)
    used = fuse_team_sets(ests, A)
    assert used.tolist() == [2, 2, 2, 0]
    shared = [e.shared for e in ref]
    for i, e in enumerate(ref):
        nbrs = [shared[j] for j in np.flatnonzero(A[i])]
        fused = e.fuse(nbrs)
        got = ests[i].estimate
        assert shapely.equals_exact(got.Xbar, fused.Xbar, 0.0) and shapely.equals_exact(got.X, fused.X, 0.0)
    # the linked three cleared each other's squares; UAV 3 only its own
    cleared = [AREA.area - e.estimate.area_Xbar for e in ests]
    assert cleared[:3] == pytest.approx([3 * 6400.0] * 3, rel=1e-9) and cleared[3] == pytest.approx(6400.0)


def test_a_uav_without_a_current_scan_sits_the_fusion_out():
    ests = _team(3)
    stale = SetMembershipEstimator(SetMembershipConfig(), AREA, owner=3)  # never corrected: its sets are of t = 0
    stale.predict(1.0)
    used = fuse_team_sets([*ests, stale], ~np.eye(4, dtype=bool))
    assert used.tolist() == [2, 2, 2, 0]
    assert stale.estimate.area_Xbar == pytest.approx(AREA.area)  # it lent nothing and took nothing


def test_team_fusion_checks_the_adjacency_shape():
    with pytest.raises(ValueError, match="adjacency"):
        fuse_team_sets(_team(2), np.ones((3, 3), bool))
