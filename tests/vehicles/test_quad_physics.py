"""Per-rotor physics: force/torque application in PyBullet, motor lag, drag, ground effect, downwash."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from interfaces.setpoints import PositionSetpoint, VelocitySetpoint
from vehicles.quadrotor.aero import DownwashConfig, body_drag_B, downwash_force_W, ground_effect_factor
from vehicles.quadrotor.airframes import load_airframe
from vehicles.quadrotor.fleet import FleetOptions, QuadrotorFleet
from vehicles.quadrotor.params import GRAVITY
from vehicles.quadrotor.rotors import RotorBank
from vehicles.quadrotor.stack import AirframeStack
from vehicles.quadrotor.wind import WindConfig

DT = 1.0 / 240.0


def make_fleet(cid: int, names: list[str], p0: list[list[float]], rng: np.random.Generator,
               options: FleetOptions | None = None, yaw0: list[float] | None = None) -> QuadrotorFleet:
    return QuadrotorFleet(cid, [load_airframe(n) for n in names], np.array(p0, dtype=float),
                          np.zeros(len(names)) if yaw0 is None else np.array(yaw0), 240,
                          options or FleetOptions(), rng)


def test_bodies_have_airframe_mass_inertia_and_no_damping(bullet_client, rng) -> None:
    fleet = make_fleet(bullet_client, ["survey_quad", "crazyflie"], [[0, 0, 10], [5, 0, 10]], rng)
    for b, name in zip(fleet.body_ids.tolist(), ["survey_quad", "crazyflie"], strict=True):
        a = load_airframe(name)
        info = p.getDynamicsInfo(b, -1, physicsClientId=bullet_client)
        assert info[0] == pytest.approx(a.mass)
        np.testing.assert_allclose(info[2], a.inertia, rtol=1e-6)
        np.testing.assert_allclose(info[3], 0.0, atol=1e-12)  # inertial frame at the body origin
    # Zero damping: a free body with no applied force keeps its spin exactly.
    b = int(fleet.body_ids[1])
    p.resetBaseVelocity(b, [0, 0, 0], [0.0, 0.0, 3.0], physicsClientId=bullet_client)
    p.setGravity(0, 0, 0, physicsClientId=bullet_client)
    for _ in range(24):
        p.stepSimulation(physicsClientId=bullet_client)
    assert p.getBaseVelocity(b, physicsClientId=bullet_client)[1][2] == pytest.approx(3.0, rel=1e-9)


def test_body_frame_torque_gives_expected_angular_acceleration(bullet_client, rng, run_fleet) -> None:
    """Newton-Euler check of what the fleet applies: a = F/m + g and J w_dot + w x J w = tau, in one physics step."""
    a = load_airframe("survey_quad")
    fleet = make_fleet(bullet_client, ["survey_quad"], [[0, 0, 50]], rng, yaw0=[0.7])
    fleet.set_command(0, VelocitySetpoint(v_W=[6.0, -4.0, 1.0], yaw=-1.0))
    tick = run_fleet(fleet, 150)  # mid-manoeuvre: tilted, rotating, rotors unequal
    s0 = fleet.state
    assert np.degrees(np.arccos(s0.R_WB[0, 2, 2])) > 5.0 and np.linalg.norm(s0.omega_B) > 0.05
    fleet.apply_actuation()
    F_W, tau_W = fleet.force_W[0].copy(), fleet.torque_W[0].copy()
    p.stepSimulation(physicsClientId=bullet_client)
    fleet.after_step(tick)
    s1 = fleet.state
    np.testing.assert_allclose((s1.v_W[0] - s0.v_W[0]) / DT, F_W / a.mass + [0, 0, -GRAVITY], rtol=0, atol=1e-9)
    R0 = s0.R_WB[0]
    J = np.diag(a.inertia)
    w0_W, w1_W = R0 @ s0.omega_B[0], s1.R_WB[0] @ s1.omega_B[0]
    I_W = R0 @ J @ R0.T
    expected = np.linalg.solve(I_W, tau_W - np.cross(w0_W, I_W @ w0_W))
    tau_B = R0.T @ tau_W
    assert np.linalg.norm(tau_B[:2]) > 1e-3  # a real roll/pitch torque was applied
    np.testing.assert_allclose((w1_W - w0_W) / DT, expected, rtol=0, atol=2e-3 * np.linalg.norm(expected) + 1e-9)


def test_pure_body_torque_from_rest_on_a_tilted_body(bullet_client) -> None:
    """Applying R_WB tau_B in WORLD_FRAME spins the body about its own axis: d(omega_B)/dt = J^-1 tau_B."""
    a = load_airframe("crazyflie")
    cid = bullet_client
    p.setGravity(0, 0, 0, physicsClientId=cid)
    col = p.createCollisionShape(p.GEOM_BOX, halfExtents=list(a.body_half_extents), physicsClientId=cid)
    q = p.getQuaternionFromEuler([0.5, -0.4, 2.0])
    b = p.createMultiBody(baseMass=a.mass, baseCollisionShapeIndex=col, basePosition=[0, 0, 1], baseOrientation=q,
                          baseInertialFramePosition=[0, 0, 0], physicsClientId=cid)
    p.changeDynamics(b, -1, localInertiaDiagonal=list(a.inertia), linearDamping=0, angularDamping=0,
                     physicsClientId=cid)
    R = np.array(p.getMatrixFromQuaternion(q)).reshape(3, 3)
    for tau_B in ([1e-5, 0, 0], [0, 2e-5, 0], [0, 0, 1e-5]):
        p.resetBasePositionAndOrientation(b, [0, 0, 1], q, physicsClientId=cid)
        p.resetBaseVelocity(b, [0, 0, 0], [0, 0, 0], physicsClientId=cid)
        p.applyExternalTorque(b, -1, (R @ tau_B).tolist(), p.WORLD_FRAME, physicsClientId=cid)
        p.stepSimulation(physicsClientId=cid)
        w_B = R.T @ np.array(p.getBaseVelocity(b, physicsClientId=cid)[1])
        np.testing.assert_allclose(w_B / DT, np.array(tau_B) / np.array(a.inertia), rtol=1e-9, atol=1e-9)


def test_motor_lag_is_exact_first_order_and_saturates() -> None:
    a = load_airframe("survey_quad")
    stack = AirframeStack.from_params([a])
    bank = RotorBank(stack, DT, np.full((1, 4), 500.0))
    bank.omega_cmd = np.array([[800.0, 300.0, 500.0, 5000.0]])
    k = np.arange(1, 49)
    out = np.array([bank.step()[0].copy() for _ in k])
    omega = np.sqrt(out / a.k_f)
    decay = np.exp(-k * DT / a.motor_time_constant)
    np.testing.assert_allclose(omega[:, 0], 800 + (500 - 800) * decay, rtol=1e-12)
    np.testing.assert_allclose(omega[:, 1], 300 + (500 - 300) * decay, rtol=1e-12)
    np.testing.assert_allclose(omega[:, 2], 500.0, rtol=1e-12)
    assert omega[:, 3].max() == pytest.approx(a.rotor_speed_max)  # saturated at w_max
    np.testing.assert_allclose(out, a.k_f * omega**2, rtol=1e-12)  # thrust = k_f w^2


def test_body_drag_closed_form() -> None:
    v = np.array([[3.0, -2.0, 0.5]])
    c1, c2 = np.array([[0.1, 0.2, 0.3]]), np.array([[0.02, 0.03, 0.05]])
    np.testing.assert_allclose(body_drag_B(v, c1, c2),
                               [[-(0.3 + 0.18), 0.4 + 0.12, -(0.15 + 0.0125)]], rtol=1e-12)


def test_hover_in_constant_wind_tilts_into_it(bullet_client, rng, run_fleet) -> None:
    """Holding position in a steady 5 m/s wind, the drag of the air-relative velocity is balanced by the tilted
    thrust."""
    a = load_airframe("survey_quad")
    opts = FleetOptions(wind=WindConfig(mean_W=(0.0, 5.0, 0.0), sigma=(0.0, 0.0, 0.0)))
    fleet = make_fleet(bullet_client, ["survey_quad"], [[0, 0, 30]], rng, opts)
    run_fleet(fleet, 240 * 12)
    st = fleet.state
    assert np.linalg.norm(st.p_W[0] - [0, 0, 30]) < 0.05  # integral action still converging
    # Equilibrium: thrust b3 T + R drag_B(R^T (0 - w)) = m g e3; solve for the tilt about x (wind along +y).
    w_W = np.array([0.0, 5.0, 0.0])
    R = st.R_WB[0]
    drag_W = R @ body_drag_B((R.T @ -w_W)[None], np.array([a.drag_linear]), np.array([a.drag_quadratic]))[0]
    b3_expected = (np.array([0, 0, a.weight]) - drag_W) / np.linalg.norm(np.array([0, 0, a.weight]) - drag_W)
    np.testing.assert_allclose(R[:, 2], b3_expected, atol=2e-4)
    assert R[1, 2] < -0.04  # leans into the wind, which blows towards +y: about 3 degrees


def test_ground_effect_factor_values() -> None:
    R = np.array([[0.1]])
    assert ground_effect_factor(np.array([[0.2]]), R, 0.5)[0, 0] == pytest.approx(1.0 / (1.0 - (0.1 / 0.8) ** 2))
    assert ground_effect_factor(np.array([[100.0]]), R, 0.5)[0, 0] == pytest.approx(1.0, abs=1e-6)
    capped = 1.0 / (1.0 - 1.0 / 16.0 / 0.25)
    assert ground_effect_factor(np.array([[0.0]]), R, 0.5)[0, 0] == pytest.approx(capped)
    assert ground_effect_factor(np.array([[-1.0]]), R, 0.5)[0, 0] == pytest.approx(capped)


def test_ground_effect_lowers_hover_rotor_speed(bullet_client, rng, run_fleet) -> None:
    """Near the ground the same total thrust (m g) needs rotor speed w_hover / sqrt(factor)."""
    a = load_airframe("survey_quad")
    h = 0.30
    opts = FleetOptions(ground_effect=True, ground_z=0.0)
    fleet = make_fleet(bullet_client, ["survey_quad"], [[0, 0, h]], rng, opts)
    run_fleet(fleet, 240 * 8)
    st = fleet.state
    assert st.p_W[0, 2] == pytest.approx(h, abs=0.005)
    factor = 1.0 / (1.0 - (a.rotor_radius / (4.0 * st.p_W[0, 2])) ** 2)
    assert factor > 1.015
    assert st.thrust[0].sum() == pytest.approx(a.weight, rel=2e-3)
    assert st.rotor_speed[0].mean() == pytest.approx(a.hover_rotor_speed / math.sqrt(factor), rel=1e-3)


def test_downwash_bounded_as_gap_vanishes() -> None:
    cfg = DownwashConfig()
    T_up = 20.0
    gaps = np.concatenate([[0.0], np.logspace(-12, 1, 60)])
    forces = []
    for dz in gaps:
        p_W = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, dz]])
        F = downwash_force_W(p_W, np.array([18.0, T_up]), np.array([0.4, 0.4]), np.array([0.29, 0.29]), cfg)
        assert np.all(np.isfinite(F))
        assert F[1, 2] == 0.0  # the upper UAV feels nothing from the lower one
        forces.append(-F[0, 2])
    forces = np.array(forces)
    assert np.all(forces >= 0.0) and forces.max() <= cfg.coefficient * T_up + 1e-12
    assert forces[0] == 0.0 and forces[1] < 1e-9  # continuous at dz = 0
    k = np.argmin(np.abs(gaps - cfg.ramp_height))
    assert forces[k] == pytest.approx(cfg.coefficient * T_up * (0.4 / (0.4 + cfg.spread * gaps[k])) ** 2, rel=0.05)
    assert np.all(np.diff(forces[gaps > cfg.ramp_height]) < 0)  # decays with the gap beyond the ramp
    # Horizontal offset: Gaussian in the distance, width = wake radius at that gap.
    p_W = np.array([[0.6, 0.0, 0.0], [0.0, 0.0, 1.0]])
    F = downwash_force_W(p_W, np.array([18.0, T_up]), np.array([0.4, 0.4]), np.array([0.29, 0.29]), cfg)
    r = 0.4 + cfg.spread
    assert -F[0, 2] == pytest.approx(cfg.coefficient * T_up * (0.4 / r) ** 2 * math.exp(-0.5 * 0.36 / r**2))


def test_stacked_uavs_gap_to_zero_forces_stay_finite(bullet_client, rng, run_fleet) -> None:
    """The lower UAV climbs into the upper one's wake until the gap closes; forces stay finite and bounded."""
    cid = bullet_client
    opts = FleetOptions(downwash=True)
    fleet = make_fleet(cid, ["survey_quad", "survey_quad"], [[0, 0, 20], [0.05, 0, 14]], rng, opts)
    a = load_airframe("survey_quad")
    fleet.set_command(1, PositionSetpoint(p_W=[0.05, 0.0, 20.5]))
    gaps, dw, upper_thrust = [], [], []

    def record(_tick: int) -> None:
        st = fleet.state
        assert np.all(np.isfinite(fleet.force_W)) and np.all(np.isfinite(fleet.torque_W))
        assert np.all(np.isfinite(st.p_W)) and np.all(np.isfinite(st.q_WB))
        gaps.append(st.p_W[0, 2] - st.p_W[1, 2])
        dw.append(fleet.downwash_W[:, 2].copy())
        upper_thrust.append(st.thrust[0].sum())

    run_fleet(fleet, 240 * 10, on_tick=record)
    gaps, dw, upper_thrust = np.array(gaps), np.array(dw), np.array(upper_thrust)
    assert gaps.min() < 0.15  # the bodies met (box half heights 0.05 m each)
    bound = DownwashConfig().coefficient * a.max_total_thrust
    assert np.all(np.abs(dw) <= bound)
    assert np.all(dw[gaps > 0.0, 0] == 0.0)  # nothing acts on the upper UAV while it is above
    in_wake = (gaps > 1.0) & (gaps < 3.0)
    assert in_wake.any() and np.all(-dw[in_wake, 1] > 0.05 * a.weight)  # a real, sizeable wake force
    assert np.all(np.abs(dw[:, 1]) <= DownwashConfig().coefficient * np.roll(upper_thrust, 1) + 1e-9)


def test_rotation_functions_against_scipy() -> None:
    from scipy.spatial.transform import Rotation

    from vehicles.quadrotor.outer_loop import attitude_from_thrust
    from vehicles.quadrotor.rotation import cross3, quat_to_rotmat, rotate_T, tilt_of, yaw_of, yaw_to_quat

    rot = Rotation.random(20, random_state=4)
    R = quat_to_rotmat(rot.as_quat())  # scipy uses (x, y, z, w) too
    np.testing.assert_allclose(R, rot.as_matrix(), atol=1e-12)
    np.testing.assert_allclose(yaw_of(quat_to_rotmat(yaw_to_quat(np.array([0.3, -2.0])))), [0.3, -2.0], atol=1e-12)
    np.testing.assert_allclose(tilt_of(R), np.arccos(rot.as_matrix()[:, 2, 2]), atol=1e-9)
    v = np.random.default_rng(0).normal(size=(20, 3))
    np.testing.assert_allclose(rotate_T(R, v), np.einsum("nji,nj->ni", R, v), atol=1e-12)
    np.testing.assert_allclose(cross3(v, v[::-1]), np.cross(v, v[::-1]), atol=1e-12)
    # Full attitude from a thrust axis and a heading: orthonormal, z along F, body-x heading exactly psi.
    F = v.copy()
    F[:, 2] = np.abs(F[:, 2]) + 0.5
    yaw = np.linspace(-3.0, 3.0, 20)
    Rd = attitude_from_thrust(F, yaw)
    np.testing.assert_allclose(np.matmul(Rd.transpose(0, 2, 1), Rd), np.broadcast_to(np.eye(3), Rd.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(Rd), 1.0, atol=1e-12)
    np.testing.assert_allclose(Rd[:, :, 2], F / np.linalg.norm(F, axis=1, keepdims=True), atol=1e-12)
    np.testing.assert_allclose(np.angle(np.exp(1j * (yaw_of(Rd) - yaw))), 0.0, atol=1e-12)
