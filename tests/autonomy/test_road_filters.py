"""MAEKF and ECUKF on one road: closed-form updates on straight roads, road-following prediction, SPD covariances."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autonomy.estimation.measurements import Measurement, PositionModel
from autonomy.estimation.models import SINGER, Singer
from autonomy.estimation.road.constraint import RoadConstraintParams, SegmentCursor
from autonomy.estimation.road.filters import ECUKF, MAEKF, make_road_filter
from autonomy.estimation.road.segments import RoadApproximation

MODEL = Singer(alpha=0.6, sigma_a=0.66, dim=2)
THETA = 0.5  # rad; heading of the straight test road
OFFSET, SIGMA_L = -1.75, 1.0  # m


def straight_cursor() -> SegmentCursor:
    t = np.array([np.cos(THETA), np.sin(THETA)])
    approx = RoadApproximation.from_vertices(np.array([[0.0, 0.0], 500.0 * t, 1000.0 * t]), road_id="r")
    return SegmentCursor(approx.segments, 0)


def rotation() -> np.ndarray:
    """Road frame (along, left) from world x-y."""
    c, s = np.cos(THETA), np.sin(THETA)
    return np.array([[c, s], [-s, c]])


def box(z: np.ndarray, t: float, sigma: float = 5.0) -> Measurement:
    return Measurement(z=z, R=np.eye(2) * sigma**2, t_meas=t, kind="box")


def start(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    x0 = np.array([100.0, 8.0, 0.0, 60.0, 4.0, 0.0]) + rng.normal(size=6)
    P0 = np.diag([100.0, 9.0, 1.0, 100.0, 9.0, 1.0])
    return x0, P0


def test_maekf_equals_the_kalman_filter_with_the_stacked_linear_constraint():
    """On a line the lateral row is linear: ℓ = −sinθ x + cosθ y, so MAEKF is the exact Kalman filter on
    z_a = [z, ℓ0] with H_a = [H; (−sinθ, cosθ) on (x, y)], R_a = diag(R, σ_ℓ²)."""
    rng = np.random.default_rng(3)
    x, P = start(rng)
    params = RoadConstraintParams(sigma_lateral=SIGMA_L, lateral_offset=OFFSET, velocity_update="off",
                                  follow_road_heading=False)
    f = MAEKF(MODEL, x, P, 0.0, cursor=straight_cursor(), lanes={"r": (OFFSET, SIGMA_L)}, params=params)
    H = np.vstack([PositionModel(SINGER).H, np.zeros(6)])
    H[2, 0], H[2, 3] = -np.sin(THETA), np.cos(THETA)
    Ra = np.diag([25.0, 25.0, SIGMA_L**2])
    for k in range(1, 15):
        z = rng.normal(size=2) * 5.0 + [100.0 + 9 * k, 60.0 + 4 * k]
        F, Q = MODEL.matrices(0.5)
        x, P = F @ x, F @ P @ F.T + Q
        S = H @ P @ H.T + Ra
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ (np.append(z, OFFSET) - H @ x)
        P = (np.eye(6) - K @ H) @ P
        inn = f.update(box(z, 0.5 * k))
        np.testing.assert_allclose(inn.S, S[:2, :2], rtol=1e-9)  # the sensor rows of the augmented innovation
    np.testing.assert_allclose(f.x, x, rtol=1e-9, atol=1e-8)
    np.testing.assert_allclose(f.P, P, rtol=1e-8, atol=1e-9)


def test_ecukf_projection_puts_the_mean_on_the_lane_with_the_stated_lateral_variance():
    rng = np.random.default_rng(4)
    x, P = start(rng)
    params = RoadConstraintParams(sigma_lateral=SIGMA_L, lateral_offset=OFFSET, velocity_update="joint",
                                  sigma_normal_speed=0.5)
    f = ECUKF(MODEL, x, P, 0.0, cursor=straight_cursor(), lanes={"r": (OFFSET, SIGMA_L)}, params=params,
              stage2="project")
    Rw = rotation()
    for k in range(1, 8):
        f.update(box(rng.normal(size=2) * 5.0 + [100.0 + 9 * k, 60.0 + 4 * k], 0.5 * k))
        along_left = Rw @ f.x[[0, 3]]
        assert along_left[1] == pytest.approx(OFFSET, abs=1e-9)  # every sigma point projected: the mean too
        v_left = (Rw @ f.x[[1, 4]])[1]
        assert v_left == pytest.approx(0.0, abs=1e-9)
        P_pos = Rw @ f.P[np.ix_([0, 3], [0, 3])] @ Rw.T
        assert P_pos[1, 1] == pytest.approx(SIGMA_L**2, rel=1e-9)
        assert P_pos[0, 1] == pytest.approx(0.0, abs=1e-9)
        P_vel = Rw @ f.P[np.ix_([1, 4], [1, 4])] @ Rw.T
        assert P_vel[1, 1] == pytest.approx(0.25, rel=1e-9)


@pytest.mark.parametrize("variant,stage2", [("maekf", "project"), ("ecukf", "pseudo")], ids=["maekf", "ecukf-pseudo"])
def test_pseudo_measurement_filters_pull_to_the_lane_by_the_kalman_fraction(variant, stage2):
    """One constraint on a line from P = diag: the lateral mean moves by P_ll / (P_ll + σ_ℓ²) of the gap."""
    Rw = rotation()
    p = Rw.T @ np.array([200.0, 6.0])  # 6 m left of the centre-line
    x = np.array([p[0], 0.0, 0.0, p[1], 0.0, 0.0])
    P = np.diag([16.0, 1.0, 1.0, 16.0, 1.0, 1.0])
    params = RoadConstraintParams(sigma_lateral=2.0, lateral_offset=OFFSET, velocity_update="off")
    f = make_road_filter(variant, MODEL, x, P, 0.0, cursor=straight_cursor(), lanes={"r": (OFFSET, 2.0)},
                         params=params, stage2=stage2)
    f.constrain()
    lat = (Rw @ f.x[[0, 3]])[1]
    assert lat == pytest.approx(6.0 - 16.0 / 20.0 * (6.0 - OFFSET), rel=1e-6)
    assert (Rw @ f.x[[0, 3]])[0] == pytest.approx(200.0, abs=1e-6)  # nothing along the road (no correlation)


def test_follow_road_heading_turns_velocity_with_a_circular_road():
    radius, v = 200.0, 12.0
    ang = np.linspace(-0.5, 2.0, 12)
    approx = RoadApproximation.from_vertices(radius * np.c_[np.cos(ang), np.sin(ang)], road_id="c")
    p0, th0 = radius * np.array([1.0, 0.0]), np.pi / 2
    x = np.array([p0[0], v * np.cos(th0), 0.0, p0[1], v * np.sin(th0), 0.0])
    for follow, expect_turn in ((True, True), (False, False)):
        f = MAEKF(MODEL, x, np.diag([1.0, 0.1, 0.01] * 2), 0.0, cursor=SegmentCursor(approx.segments),
                  lanes={"c": (0.0, 1.0)}, params=RoadConstraintParams(follow_road_heading=follow))
        f.predict(1.0)
        th = np.arctan2(f.x[4], f.x[1])
        foot = np.arctan2(f.x[3], f.x[0]) + np.pi / 2  # circle tangent at the new foot point
        if expect_turn:
            assert th == pytest.approx(foot, abs=1e-9)
            assert th - th0 == pytest.approx(v / radius, rel=0.01)  # Δθ = v T κ
        else:
            assert th == pytest.approx(th0, abs=1e-12)
        assert np.hypot(f.x[1], f.x[4]) == pytest.approx(v, rel=1e-12)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), variant=st.sampled_from(["maekf", "ecukf"]),
       stage2=st.sampled_from(["pseudo", "project"]), mode=st.sampled_from(["auto", "joint", "partial", "off"]))
def test_covariance_stays_symmetric_positive_definite(seed, variant, stage2, mode):
    rng = np.random.default_rng(seed)
    ang = np.linspace(0.0, 3.0, 9)
    approx = RoadApproximation.from_vertices(150.0 * np.c_[np.cos(ang), np.sin(ang)] + rng.normal(size=(9, 2)),
                                             road_id="c")
    x = np.array([150.0, 0.0, 0.0, 0.0, 10.0, 0.0]) + rng.normal(size=6) * 3
    f = make_road_filter(variant, MODEL, x, np.diag([50.0, 4.0, 1.0] * 2), 0.0, cursor=SegmentCursor(approx.segments),
                         lanes={"c": (-1.75, 1.1)}, params=RoadConstraintParams(velocity_update=mode), stage2=stage2)
    for k in range(1, 30):
        p = f.x[[0, 3]] + rng.normal(size=2) * 10.0
        d = np.array([p[0] - 400.0, p[1] - 100.0, -100.0])
        z = np.array([np.linalg.norm(d), np.arctan2(d[1], d[0])])
        f.update(Measurement(z=z, R=np.diag([20.0**2, 0.1**2]), t_meas=0.5 * k,
                             p_sensor_W=np.array([400.0, 100.0, 100.0])))
        np.testing.assert_allclose(f.P, f.P.T, atol=1e-9)
        assert np.linalg.eigvalsh(f.P).min() > 0.0


def test_a_road_filter_keeps_the_lanes_of_its_path_and_refuses_a_path_without_them():
    rng = np.random.default_rng(4)
    x, P = start(rng)
    lanes = {"r": (OFFSET, SIGMA_L), "elsewhere": (0.0, 2.0)}
    f = ECUKF(MODEL, x, P, 0.0, cursor=straight_cursor(), lanes=lanes)
    assert f.lanes == {"r": (OFFSET, SIGMA_L)}
    with pytest.raises(ValueError, match=r"lanes must give \(offset, sigma\) for every road on the path, "
                                         r"missing \['r'\]"):
        MAEKF(MODEL, x, P, 0.0, cursor=straight_cursor(), lanes={"elsewhere": (0.0, 2.0)})
