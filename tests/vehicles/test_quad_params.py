"""Airframe parameter files, their validation and the inertia model."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import trimesh

from vehicles.quadrotor.airframes import list_airframes, load_airframe
from vehicles.quadrotor.inertia import x_frame_inertia
from vehicles.quadrotor.params import GRAVITY, ControllerGains, QuadrotorParams


def test_list_and_load_airframes() -> None:
    assert list_airframes() == ["survey_quad", "crazyflie"]
    for name in list_airframes():
        params = load_airframe(name)
        assert isinstance(params, QuadrotorParams)
        assert params.name == name
    with pytest.raises(KeyError, match="survey_quad"):
        load_airframe("hexacopter")


def test_survey_quad_envelope() -> None:
    a = load_airframe("survey_quad")
    assert 1.5 <= a.mass <= 2.5
    assert a.max_speed >= 15.0
    assert a.thrust_to_weight > 2.0
    # Trim at max speed in still air: the drag must be balanced inside the tilt limit (level flight, body ~ world).
    v = a.max_speed
    drag = a.drag_linear[0] * v + a.drag_quadratic[0] * v * v
    assert math.atan2(drag, a.weight) < a.tilt_max - a.gains.tilt_margin
    # ... and the thrust needed there is within the rotor range.
    assert math.hypot(drag, a.weight) < a.max_total_thrust


def test_crazyflie_matches_cf2x() -> None:
    a = load_airframe("crazyflie")
    rpm = 2.0 * math.pi / 60.0
    assert a.mass == 0.027
    assert a.arm_length == 0.0397
    assert a.k_f * rpm**2 == pytest.approx(3.16e-10, rel=1e-12)
    assert a.k_m * rpm**2 == pytest.approx(7.94e-12, rel=1e-12)
    assert a.thrust_to_weight == pytest.approx(2.25, rel=1e-9)
    # Hover 14 476 rpm in gym-pybullet-drones' units.
    assert a.hover_rotor_speed / rpm == pytest.approx(math.sqrt(0.027 * GRAVITY / (4 * 3.16e-10)), rel=1e-9)
    # Geometry-derived inertia within 20 % of the cf2x.urdf values.
    np.testing.assert_allclose(a.inertia, (1.4e-5, 1.4e-5, 2.17e-5), rtol=0.2)


def test_inertia_closed_form_matches_trimesh() -> None:
    """The closed form of x_frame_inertia against trimesh's integration of the same solids (thin arms as boxes)."""
    L, m_hub, m_rot, m_arm = 0.25, 1.25, 0.10, 0.05
    size = (0.20, 0.20, 0.10)
    hub = trimesh.creation.box(extents=size)
    hub.density = m_hub / hub.volume
    total = hub.moment_inertia.copy()
    for k in range(4):
        theta = math.pi / 4 + k * math.pi / 2
        c, s = math.cos(theta), math.sin(theta)
        r = np.array([L * c, L * s, 0.0])
        total += m_rot * (np.dot(r, r) * np.eye(3) - np.outer(r, r))  # point mass at the hub
        arm = trimesh.creation.box(extents=(L, 1e-3, 1e-3))
        arm.apply_translation((L / 2, 0.0, 0.0))
        arm.apply_transform(trimesh.transformations.rotation_matrix(theta, (0, 0, 1)))
        arm.density = m_arm / arm.volume
        c_arm = arm.center_mass  # trimesh gives the inertia about the part's own centre of mass: shift it
        total += arm.moment_inertia + m_arm * (np.dot(c_arm, c_arm) * np.eye(3) - np.outer(c_arm, c_arm))
    closed = x_frame_inertia(hub_mass=m_hub, hub_size=size, rotor_mass=m_rot, arm_length=L, arm_mass=m_arm)
    np.testing.assert_allclose(np.diag(total), closed, rtol=1e-3)
    np.testing.assert_allclose(total - np.diag(np.diag(total)), 0.0, atol=1e-9)


def _with(params: QuadrotorParams, **changes) -> QuadrotorParams:
    return dataclasses.replace(params, **changes)


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("mass", 0.0, "mass"),
        ("mass", -1.0, "mass"),
        ("mass", float("nan"), "mass"),
        ("arm_length", 0.0, "arm_length"),
        ("k_f", -1e-6, "k_f"),
        ("motor_time_constant", 0.0, "motor_time_constant"),
        ("inertia", (0.01, 0.01, 0.05), "triangle"),
        ("inertia", (0.01, -0.01, 0.01), "inertia"),
        ("drag_linear", (0.1, -0.1, 0.1), "drag_linear"),
        ("rotor_speed_max", 700.0, "thrust-to-weight"),
        ("mass", 5.0, "thrust-to-weight"),
        ("rotor_speed_min", 2000.0, "rotor_speed_min"),
        ("tilt_max", math.pi / 2, "tilt_max"),
        ("rotor_radius", 0.2, "rotor_radius"),
        ("name", "", "name"),
    ],
)
def test_invalid_params_rejected_naming_field(field: str, value: object, match: str) -> None:
    base = load_airframe("survey_quad")
    with pytest.raises(ValueError, match=match):
        _with(base, **{field: value})


def test_thrust_to_weight_threshold() -> None:
    base = load_airframe("survey_quad")
    w_at = lambda ratio: math.sqrt(ratio * base.weight / (4 * base.k_f))  # noqa: E731
    assert _with(base, rotor_speed_max=w_at(1.21)).thrust_to_weight == pytest.approx(1.21)
    with pytest.raises(ValueError, match=r"rotor_speed_max.*thrust-to-weight 1\.190"):
        _with(base, rotor_speed_max=w_at(1.19))


@pytest.mark.parametrize(
    ("field", "value"),
    [("vel_p_xy", 0.0), ("att_p_rp", -1.0), ("rate_p_yaw", float("inf")), ("vel_i_xy", -0.1), ("att_p_rp", 25.0)],
)
def test_invalid_gains_rejected_naming_field(field: str, value: float) -> None:
    gains = load_airframe("survey_quad").gains
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(gains, **{field: value})


def test_tilt_margin_must_leave_a_tilt() -> None:
    base = load_airframe("survey_quad")
    gains = dataclasses.replace(base.gains, tilt_margin=base.tilt_max)
    with pytest.raises(ValueError, match="tilt_margin"):
        _with(base, gains=gains)
    assert isinstance(base.gains, ControllerGains)
