"""FIM-optimal formation (Yang & Wang 2019): Algorithm 1 on Example 1, the free rotation, Jacobi coordinates, and the
PD formation controller in closed loop on single integrators (velocity set-points followed exactly)."""

import numpy as np
import pytest

from autonomy.guidance.formation.geometry import optimal_formation
from autonomy.guidance.formation.guidance import FormationConfig, FormationGuidance, formation_step
from autonomy.guidance.formation.jacobi import JacobiGains, jacobi_matrix, jacobi_pd_acceleration
from autonomy.metrics.fim import bearing_fim, max_det_bearing_fim
from interfaces.state import OwnState, TargetEstimate, TeammateState

EX1_SENSORS = np.array([[-10.0, 0.0], [0.0, 0.0], [0.0, 10.0]])
EX1_TARGET = np.array([5.0, 5.0])


def test_example_1_optimum():
    r = np.linalg.norm(EX1_SENSORS - EX1_TARGET, axis=1)
    assert np.linalg.det(bearing_fim(EX1_TARGET, EX1_SENSORS, 0.1)) == pytest.approx(4.800, abs=1e-9)
    geo = optimal_formation(EX1_TARGET, np.zeros(2), EX1_SENSORS, r, 0.1)
    assert geo.det_fim == pytest.approx(4.84, abs=1e-9)
    assert geo.det_bound == pytest.approx(4.84, abs=1e-9)
    np.testing.assert_allclose(np.linalg.norm(geo.p_W - EX1_TARGET, axis=1), r, rtol=1e-12)
    assert np.linalg.det(bearing_fim(EX1_TARGET, geo.p_W, 0.1)) == pytest.approx(4.84, abs=1e-9)
    # the paper's printed "optimal" positions only reach the start's value
    printed = np.array([[-10.8114, 5.0], [10.0, 0.0], [0.0, 0.0]])
    assert np.linalg.det(bearing_fim(EX1_TARGET, printed, 0.1)) == pytest.approx(4.800, abs=1e-4)
    # the paper's 1° grid search (sensor 2 fixed at (0, 0)) finds 4.8399 at θ1 = 273°, θ3 = 321°
    th = np.deg2rad(np.arange(360.0))
    t1, t3 = np.meshgrid(th, th, indexing="ij")
    theta2 = np.arctan2(-5.0, -5.0)
    c2 = 1.0 / (0.1 * r) ** 2
    # det F = (½ Σ c²)² − ¼ ‖Σ c_i² [cos 2θ_i, sin 2θ_i]‖²  (θ: direction target → sensor)
    det = (0.5 * c2.sum()) ** 2 - 0.25 * (
        (c2[0] * np.cos(2 * t1) + c2[1] * np.cos(2 * theta2) + c2[2] * np.cos(2 * t3)) ** 2
        + (c2[0] * np.sin(2 * t1) + c2[1] * np.sin(2 * theta2) + c2[2] * np.sin(2 * t3)) ** 2)
    assert det.max() == pytest.approx(4.8399, abs=1e-4)
    assert det.max() <= geo.det_fim + 1e-12


def test_optimal_for_random_ranges():
    rng = np.random.default_rng(11)
    for _ in range(50):
        n = int(rng.integers(3, 7))
        r = rng.uniform(20.0, 60.0, size=n)
        p = rng.uniform(-100.0, 100.0, size=(n, 2))
        geo = optimal_formation(np.zeros(2), rng.normal(size=2), p, r, 0.02)
        c2 = 1.0 / (0.02 * r) ** 2
        assert geo.det_bound == pytest.approx(max_det_bearing_fim(c2), rel=1e-12)
        assert geo.det_fim == pytest.approx(geo.det_bound, rel=1e-9)


def test_rotation_avoids_backward_moves():
    """Agents abeam of a target moving +x: some reflection puts every agent ahead, and the selection finds it."""
    p = np.array([[0.0, 30.0], [0.0, -40.0], [0.0, 60.0]])
    v_t = np.array([10.0, 0.0])
    r = np.array([30.0, 40.0, 50.0])
    free = optimal_formation(np.zeros(2), v_t, p, r, 0.01, backward_weight=0.0)
    soft = optimal_formation(np.zeros(2), v_t, p, r, 0.01, backward_weight=10.0)
    hard = optimal_formation(np.zeros(2), v_t, p, r, 0.01, backward_weight=1e4)
    back = [np.maximum(0.0, -(g.p_W - p)[:, 0]).max() for g in (free, soft, hard)]
    assert back[0] > 5.0  # shortest moves alone would send an agent back
    assert back[0] > back[1] > back[2] and back[2] < 1e-9
    for g in (free, soft, hard):
        assert g.det_fim == pytest.approx(g.det_bound, rel=1e-9)


def test_jacobi_matrix_matches_paper_and_is_orthonormal():
    phi = jacobi_matrix(3)
    np.testing.assert_allclose(phi[0], [0.0, 1 / np.sqrt(2), -1 / np.sqrt(2)], atol=1e-15)
    np.testing.assert_allclose(phi[1], [2 / np.sqrt(6), -1 / np.sqrt(6), -1 / np.sqrt(6)], atol=1e-15)
    np.testing.assert_allclose(phi[2], [1 / 3] * 3, atol=1e-15)
    for n in (2, 3, 5, 8):
        shape = jacobi_matrix(n)[:-1]
        np.testing.assert_allclose(shape @ shape.T, np.eye(n - 1), atol=1e-12)
        np.testing.assert_allclose(shape @ np.ones(n), 0.0, atol=1e-12)


def test_pd_decouples_shape_and_centre():
    """A translated copy of the desired formation gets equal accelerations (no shape action), and vice versa."""
    rng = np.random.default_rng(2)
    p_d = rng.normal(size=(4, 2)) * 20
    gains = JacobiGains(kp_shape=0.5, kd_shape=1.2, kp_center=0.3, kd_center=0.8)
    shift = np.array([3.0, -2.0])
    a = jacobi_pd_acceleration(p_d + shift, np.zeros((4, 2)), p_d, np.zeros((4, 2)), gains)
    np.testing.assert_allclose(a, np.broadcast_to(-0.3 * shift, (4, 2)), atol=1e-12)
    dp = rng.normal(size=(4, 2))
    dp -= dp.mean(axis=0)  # pure shape error
    a = jacobi_pd_acceleration(p_d + dp, np.zeros((4, 2)), p_d, np.zeros((4, 2)), gains)
    np.testing.assert_allclose(a, -0.5 * dp, atol=1e-12)


def _states(p, v, t):
    return [OwnState(t=t, p_W=[*p[i], 60.0], v_W=[*v[i], 0.0], yaw=0.0) for i in range(len(p))]


def test_closed_loop_converges_to_optimal_geometry():
    """Paper case 1 scaled to a car: three agents from p = (0, 5), (5, −2), (0, 0) (m) with the target's velocity,
    target at (5, 5) moving at 12 m/s along π/4; desired ranges 40, 50, 60 m; 60 s at Δt = 0.1 s.
    Converged: every agent within 0.2 m of its optimal slot, det F within 0.1 % of the bound."""
    cfg = FormationConfig(team_size=3, sigma_bearing=0.01, ranges=(40.0, 50.0, 60.0), dt=0.1, max_speed=40.0,
                          gains=JacobiGains(kp_shape=0.4, kd_shape=1.2, kp_center=0.4, kd_center=1.2))
    laws = [FormationGuidance(cfg, i) for i in range(3)]
    v_t = 12.0 * np.array([np.cos(np.pi / 4), np.sin(np.pi / 4)])
    p = np.array([[0.0, 5.0], [5.0, -2.0], [0.0, 0.0]])
    v = np.tile(v_t, (3, 1))
    err0 = None
    for k in range(600):
        t = k * cfg.dt
        target = TargetEstimate(t=t, p_W=np.array([5.0, 5.0]) + v_t * t, v_W=v_t)
        own = _states(p, v, t)
        mates = [TeammateState(id=i, t=t, p_W=own[i].p_W, v_W=own[i].v_W) for i in range(3)]
        cmds = [laws[i].command(own[i], target, [m for m in mates if m.id != i], t) for i in range(3)]
        if err0 is None:
            err0 = np.linalg.norm(p - laws[0].last_step.geometry.p_W, axis=1).max()
        v = np.array([c.v_W[:2] for c in cmds])
        p = p + v * cfg.dt
    t = 600 * cfg.dt
    target = TargetEstimate(t=t, p_W=np.array([5.0, 5.0]) + v_t * t, v_W=v_t)
    step = formation_step(p, v, target, cfg)
    err = np.linalg.norm(p - step.geometry.p_W, axis=1)
    assert err0 > 30.0
    assert err.max() < 0.2
    np.testing.assert_allclose(np.linalg.norm(p - target.p_W, axis=1), [40.0, 50.0, 60.0], atol=0.2)
    det = np.linalg.det(bearing_fim(target.p_W, p, 0.01))
    assert det == pytest.approx(step.geometry.det_bound, rel=1e-3)
    np.testing.assert_allclose(v, np.tile(v_t, (3, 1)), atol=0.05)


def test_guidance_validates_and_holds_without_target():
    with pytest.raises(ValueError, match="ranges"):
        FormationConfig(team_size=3, ranges=(10.0, -1.0, 5.0))
    g = FormationGuidance(FormationConfig(team_size=2, altitude=50.0, altitude_gain=0.5), 0)
    sp = g.command(OwnState(t=0.0, p_W=[0, 0, 40.0], v_W=[1, 0, 0], yaw=0.0), None, [], 0.0)
    np.testing.assert_allclose(sp.v_W, [0.0, 0.0, 5.0])
