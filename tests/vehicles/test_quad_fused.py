"""The fleet's fused per-tick loops give the same numbers, to the last bit, as the stages they call one by one."""

from __future__ import annotations

import numpy as np

from interfaces.setpoints import UnicycleSetpoint, VelocitySetpoint
from vehicles.quadrotor.airframes import load_airframe
from vehicles.quadrotor.fleet import FleetOptions, QuadrotorFleet, _actuate, _inner_loops
from vehicles.quadrotor.rotation import quat_to_rotmat, rotate_T, rotation_and_body_rates
from vehicles.quadrotor.setpoints import AttitudeSetpoint
from vehicles.quadrotor.wrench import total_wrench_W


def _manoeuvring_fleet(cid: int, rng: np.random.Generator, run_fleet) -> QuadrotorFleet:
    """A mixed fleet mid-manoeuvre: tilted, turning, rotors unequal and some at their limits."""
    airframes = [load_airframe(name) for name in ("survey_quad", "crazyflie", "survey_quad")]
    fleet = QuadrotorFleet(cid, airframes, np.array([[0.0, 0.0, 50.0], [8.0, 0.0, 40.0], [0.0, 9.0, 60.0]]),
                           np.array([0.0, 1.0, -2.0]), 240, FleetOptions(), rng)
    fleet.set_command(0, VelocitySetpoint(v_W=[15.0, -6.0, 3.0], yaw=2.5))
    fleet.set_command(1, UnicycleSetpoint(speed=3.0, heading_rate=0.8, altitude=42.0))
    fleet.set_command(2, VelocitySetpoint(v_W=[-12.0, 12.0, -4.0]))
    run_fleet(fleet, 70)
    return fleet


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def test_inner_loops_match_the_stages_bit_for_bit(bullet_client, rng, run_fleet) -> None:
    fleet = _manoeuvring_fleet(bullet_client, rng, run_fleet)
    st = fleet._state
    assert np.abs(st.omega_B).max() > 0.1
    for F_W, yaw in ((fleet._att_sp.F_W, fleet._att_sp.yaw),                           # the fleet's set-point
                     (np.array([[30.0, -40.0, 5.0], [0.0, 0.0, 0.01], [-2.0, 1.0, 30.0]]), np.array([3.0, -3.0, 0.1]))):
        sp = AttitudeSetpoint(F_W=F_W.copy(), yaw=yaw.copy(), yaw_rate=np.array([0.3, -0.8, 0.0]))
        wrench = fleet._rate_ctrl.update(fleet._att_ctrl.update(sp, st), st)
        f_ref = fleet._mixer.allocate(wrench).copy()
        omega_ref = fleet._mixer.update(wrench, st).omega.copy()
        rates_ref = fleet._att_ctrl.update(sp, st)
        w, omega_cmd = np.full_like(fleet._w, np.nan), np.full((3, 4), np.nan)
        _inner_loops(st.R_WB, st.omega_B, sp.F_W, sp.yaw, sp.yaw_rate, fleet._k, fleet._s.alloc_inv, w, omega_cmd)
        assert _same(w[:, 0:3], rates_ref.omega_B) and _same(w[:, 3], rates_ref.thrust)
        assert _same(w[:, 4:7], wrench.torque_B)
        assert _same(w[:, 7:11], f_ref) and _same(omega_cmd, omega_ref)


def test_actuation_matches_the_stages_bit_for_bit(bullet_client, rng, run_fleet) -> None:
    fleet = _manoeuvring_fleet(bullet_client, rng, run_fleet)
    st, s, r = fleet._state, fleet._s, fleet._rotors
    omega0, cmd = r.omega.copy(), r.omega_cmd.copy()
    assert np.ptp(cmd - omega0) > 1.0
    v_rel = st.v_W - np.array([[3.0, -1.0, 0.5]])
    # reference: the rotor bank's step, then the wrench of its thrusts
    f_nom = r.step().copy()
    omega_ref = r.omega.copy()
    F_ref, tau_ref, T_ref = np.empty((3, 3)), np.empty((3, 3)), np.empty(3)
    total_wrench_W(st.R_WB, f_nom, f_nom, s.alloc, v_rel, s.drag_linear, s.drag_quadratic, F_ref, tau_ref, T_ref)
    # fused, from the same rotor speeds
    omega, f_nom2, f = omega0.copy(), np.full((3, 4), np.nan), np.full((3, 4), np.nan)
    F, tau, T = np.full((3, 3), np.nan), np.full((3, 3), np.nan), np.full(3, np.nan)
    _actuate(omega, cmd, fleet._k, f_nom2, f, st.R_WB, s.alloc, v_rel, F, tau, T)
    assert _same(omega, omega_ref) and _same(f_nom2, f_nom) and _same(f, f_nom)
    assert _same(F, F_ref) and _same(tau, tau_ref) and _same(T, T_ref)


def test_rotation_and_body_rates_in_place_matches_the_allocating_forms(rng) -> None:
    q = rng.standard_normal((5, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    x = np.hstack([rng.standard_normal((5, 3)), q, rng.standard_normal((5, 6))])
    R, omega_B = np.full((5, 3, 3), np.nan), np.full((5, 3), np.nan)
    rotation_and_body_rates(x, R, omega_B)
    R_ref = quat_to_rotmat(np.ascontiguousarray(x[:, 3:7]))
    assert _same(R, R_ref) and _same(omega_B, rotate_T(R_ref, np.ascontiguousarray(x[:, 10:13])))


def test_one_uav_and_many_hand_the_kernels_arrays_of_one_layout(new_bullet_session, rng, run_fleet) -> None:
    """The live state's arrays (given to the compiled kernels: the command shaper, the velocity loop, the actuation,
    the watchdog) have the same numba type with one UAV as with three, so a one-UAV world does not compile them again
    (a column view of the packed state is contiguous for one row only); they hold what PyBullet reports."""
    import numba
    import pybullet as p

    types = []
    for n in (1, 3):
        with new_bullet_session() as cid:
            fleet = QuadrotorFleet(cid, [load_airframe("survey_quad")] * n, np.column_stack(
                [np.arange(n) * 10.0, np.zeros(n), np.full(n, 30.0)]), np.zeros(n), 240, FleetOptions(), rng)
            fleet.set_command(0, VelocitySetpoint(v_W=[3.0, -2.0, 1.0], yaw=0.5))
            run_fleet(fleet, 20)
            st = fleet.live_state
            types.append([numba.typeof(a) for a in (st.p_W, st.q_WB, st.v_W, st.R_WB, st.omega_B)])
            for i, body in enumerate(fleet.body_ids):
                pos, quat = p.getBasePositionAndOrientation(int(body), physicsClientId=cid)
                vel, _ = p.getBaseVelocity(int(body), physicsClientId=cid)
                assert st.p_W[i].tolist() == list(pos) and st.q_WB[i].tolist() == list(quat)
                assert st.v_W[i].tolist() == list(vel)
    assert types[0] == types[1]
