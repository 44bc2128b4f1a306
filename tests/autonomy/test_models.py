"""Motion models: closed-form matrices, exact discretisation, semigroup property, turn geometry, Jacobians."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from autonomy.estimation.models import (
    CA_2D,
    CT_OMEGA_2D,
    CV_2D,
    SINGER,
    ConstantAcceleration,
    ConstantVelocity,
    CoordinatedTurn,
    CoordinatedTurnEstimated,
    Singer,
    van_loan,
)

LINEAR_MODELS = [
    ConstantVelocity(q=0.7),
    ConstantVelocity(q=0.7, dim=3),
    ConstantAcceleration(q=0.2),
    Singer(alpha=0.6, sigma_a=0.66),
    Singer(alpha=0.6, sigma_a=0.66, dim=3),
    Singer(alpha=0.6, sigma_a=0.67, discretisation="euler"),
    CoordinatedTurn(omega=0.3, q=0.5),
    CoordinatedTurn(omega=-0.35, q=0.5),
]
LINEAR_IDS = ["cv2", "cv3", "ca", "singer", "singer3", "singer_euler", "ct+", "ct-"]


def test_layouts_follow_paper_ordering():
    assert Singer(alpha=0.6, sigma_a=0.66).layout == ("x", "vx", "ax", "y", "vy", "ay") == SINGER
    assert ConstantVelocity(q=1.0).layout == CV_2D == ("x", "vx", "y", "vy")
    assert ConstantVelocity(q=1.0, dim=3).layout == ("x", "vx", "y", "vy", "z", "vz")
    assert ConstantAcceleration(q=1.0).layout == CA_2D
    assert CoordinatedTurnEstimated(q=1.0, q_omega=0.01).layout == CT_OMEGA_2D


def test_singer_exact_matches_paper_002_numbers():
    F, Q = Singer(alpha=0.6, sigma_a=0.66).matrices(0.5)
    np.testing.assert_allclose(np.diag(Q)[:3], [6.9407e-4, 1.74981e-2, 1.965377e-1], rtol=2e-5)
    a, T = 0.6, 0.5
    np.testing.assert_allclose(F[:3, :3], [[1, T, (np.exp(-a * T) + a * T - 1) / a**2],
                                           [0, 1, (1 - np.exp(-a * T)) / a], [0, 0, np.exp(-a * T)]])
    # the two axes are uncoupled
    assert np.all(F[:3, 3:] == 0) and np.all(Q[:3, 3:] == 0)


@pytest.mark.parametrize("alpha,T", [(0.6, 0.5), (0.05, 0.1), (2.0, 1.7), (1e-4, 0.5), (0.3, 1e-3)])
def test_singer_closed_form_equals_van_loan(alpha, T):
    sigma = 0.8
    F, Q = Singer(alpha=alpha, sigma_a=sigma).matrices(T)
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -alpha]])
    F_ref, Q_ref = van_loan(A, np.diag([0.0, 0.0, 2 * alpha * sigma**2]), T)
    np.testing.assert_allclose(F[:3, :3], expm(A * T), rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(Q[:3, :3], Q_ref, rtol=1e-7, atol=1e-16)


def test_singer_euler_is_paper_000_form():
    T, a, s = 0.5, 0.6, 0.67
    F, Q = Singer(alpha=a, sigma_a=s, discretisation="euler").matrices(T)
    np.testing.assert_allclose(F[:3, :3], np.eye(3) + T * np.array([[0, 1, 0], [0, 0, 1], [0, 0, -a]]))
    np.testing.assert_allclose(np.diag(Q), [0, 0, T**2 * s**2, 0, 0, T**2 * s**2])
    assert np.linalg.matrix_rank(Q) == 2


def test_cv_and_ca_closed_forms_equal_van_loan():
    T = 0.37
    F, Q = ConstantVelocity(q=2.0).matrices(T)
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    F1, Q1 = van_loan(A, np.diag([0.0, 2.0]), T)
    np.testing.assert_allclose(F[:2, :2], F1, atol=1e-14)
    np.testing.assert_allclose(Q[:2, :2], Q1, rtol=1e-10)
    F, Q = ConstantAcceleration(q=3.0).matrices(T)
    A = np.diag([1.0, 1.0], k=1)
    F1, Q1 = van_loan(A, np.diag([0.0, 0.0, 3.0]), T)
    np.testing.assert_allclose(F[:3, :3], F1, atol=1e-14)
    np.testing.assert_allclose(Q[:3, :3], Q1, rtol=1e-9)


@pytest.mark.parametrize("model", LINEAR_MODELS, ids=LINEAR_IDS)
def test_semigroup_property_for_asynchronous_steps(model):
    """Predicting over a then b equals predicting over a + b (exact discretisations only)."""
    a, b = 0.23, 0.61
    Fa, Qa = model.matrices(a)
    Fb, Qb = model.matrices(b)
    Fab, Qab = model.matrices(a + b)
    if getattr(model, "discretisation", "exact") == "exact":
        np.testing.assert_allclose(Fb @ Fa, Fab, atol=1e-12)
        np.testing.assert_allclose(Fb @ Qa @ Fb.T + Qb, Qab, rtol=1e-9, atol=1e-14)
    else:  # the Euler form is only first-order accurate: F(a+b) = F(b)F(a) + O(ab)
        assert not np.allclose(Fb @ Fa, Fab)
    np.testing.assert_allclose(Qab, Qab.T)
    assert np.linalg.eigvalsh(Qab).min() > -1e-12


def test_matrices_are_cached_and_read_only():
    m = ConstantVelocity(q=1.0)
    F1, _ = m.matrices(0.5)
    F2, _ = m.matrices(0.5)
    assert F1 is F2
    with pytest.raises(ValueError):
        F1[0, 0] = 3.0


def test_coordinated_turn_geometry():
    w, v = 0.25, 12.0
    m = CoordinatedTurn(omega=w, q=0.1)
    x0 = np.array([0.0, v, 0.0, 0.0])
    # quarter turn: heading rotates by π/2 counter-clockwise; position ends at (R, R) with R = v/ω
    x = m.propagate(x0, (np.pi / 2) / w)
    R = v / w
    np.testing.assert_allclose(x, [R, 0.0, R, v], atol=1e-9)
    # full circle returns to the start
    np.testing.assert_allclose(m.propagate(x0, 2 * np.pi / w), x0, atol=1e-9)
    # tiny ω reduces to constant velocity
    F0, _ = CoordinatedTurn(omega=1e-9, q=0.1).matrices(0.5)
    np.testing.assert_allclose(F0, ConstantVelocity(q=0.1).matrices(0.5)[0], atol=1e-9)


@pytest.mark.parametrize("omega", [0.3, -0.2, 0.0, 1e-8])
def test_ct_estimated_matches_known_turn_and_its_jacobian(omega):
    m = CoordinatedTurnEstimated(q=0.5, q_omega=0.01)
    x = np.array([3.0, 10.0, -2.0, 4.0, omega])
    T = 0.4
    F_known, _ = CoordinatedTurn(omega=omega, q=0.5).matrices(T)
    np.testing.assert_allclose(m.propagate(x, T)[:4], F_known @ x[:4], atol=1e-12)
    J = m.jacobian(x, T)
    eps = 1e-6
    J_num = np.column_stack([(m.propagate(x + eps * e, T) - m.propagate(x - eps * e, T)) / (2 * eps)
                             for e in np.eye(5)])
    np.testing.assert_allclose(J, J_num, atol=1e-6)
    # vectorised over columns
    X = np.column_stack([x, x + 0.1])
    np.testing.assert_allclose(m.propagate(X, T)[:, 1], m.propagate(x + 0.1, T), atol=1e-12)


@pytest.mark.parametrize(
    "ctor,field",
    [
        (lambda: ConstantVelocity(q=-1.0), "q"),
        (lambda: ConstantVelocity(q=1.0, dim=4), "dim"),
        (lambda: Singer(alpha=0.0, sigma_a=1.0), "alpha"),
        (lambda: Singer(alpha=1.0, sigma_a=1.0, discretisation="rk4"), "discretisation"),
        (lambda: CoordinatedTurn(omega=float("nan"), q=1.0), "omega"),
        (lambda: CoordinatedTurnEstimated(q=1.0, q_omega=-1.0), "q_omega"),
    ],
)
def test_validation_names_field(ctor, field):
    with pytest.raises(ValueError, match=field):
        ctor()
