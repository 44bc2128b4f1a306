"""A fleet of quadrotors in one PyBullet client: per-rotor physics and the flight-control cascade, vectorised.

Run loop contract, per physics tick ``k = 1, 2, ...``::

    fleet.apply_actuation()      # rotor lag, thrust/torque, drag, wind, downwash, ground effect -> 1 force + 1 torque
    p.stepSimulation()
    fleet.after_step(k)          # read state; outer loops when k % (physics_hz / outer_loop_hz) == 0; inner loops

Frames: world ENU, body FLU; forces and torques are handed to PyBullet in the world frame at the centre of mass
(``WORLD_FRAME``) after rotating them from the body frame here. PyBullet has had ``LINK_FRAME`` and ``WORLD_FRAME``
swapped for torques on the base (bullet3 issue #1949); rotating explicitly does not depend on which behaviour the
installed version has, and ``tests/vehicles/test_quad_physics.py`` checks that a body-frame torque produces
``J^{-1} tau_B``.

Cost per tick: each stage of the cascade is one compiled loop over the UAVs (numba, cached on disk after the first
run), so the numerical work costs about a microsecond per stage whatever N; what grows with N is PyBullet's own work,
four calls per UAV (read pose, read velocity, apply force, apply torque) and the step. ``skytrack bench`` reports
the real-time factor next to the floor of bare PyBullet bodies. At a few UAVs, calling a compiled loop costs more
than its arithmetic (about 0.3 us per call plus 0.1 us per array argument), so the stages that run at every tick are
called through two fused loops, :func:`_actuate` (rotor lag and total wrench) and :func:`_inner_loops` (attitude,
rate and mixer), which run the stages' own compiled loops in the same order on the same numbers, with the per-UAV
constants packed into one array.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pybullet as p
from numba import njit

from interfaces.setpoints import FlightSetpoint
from vehicles.quadrotor.aero import DownwashConfig, downwash_force_W, ground_effect_factor
from vehicles.quadrotor.command_shaping import CommandShaper
from vehicles.quadrotor.inner_loop import AttitudeController, RateController, _attitude_rates, _rate_torques
from vehicles.quadrotor.mixer import MotorMixer, _allocate
from vehicles.quadrotor.outer_loop import ThrustVectorController, VelocityController
from vehicles.quadrotor.params import GRAVITY, QuadrotorParams
from vehicles.quadrotor.rotation import rotation_and_body_rates, yaw_to_quat
from vehicles.quadrotor.rotors import RotorBank, _lag_step
from vehicles.quadrotor.setpoints import AttitudeSetpoint
from vehicles.quadrotor.stack import AirframeStack
from vehicles.quadrotor.state import FleetState
from vehicles.quadrotor.wind import DrydenWind, WindConfig
from vehicles.quadrotor.wrench import total_wrench_W
from worlds.rates import divisor

__all__ = ["FleetOptions", "QuadrotorFleet"]


@dataclass(frozen=True, kw_only=True)
class FleetOptions:
    """Physics and control options shared by every UAV of a fleet.

    Attributes
    ----------
    wind : WindConfig | None
        Mean wind plus Dryden turbulence; ``None`` for still air.
    downwash : bool
        Apply the wake of each UAV to the UAVs below it (:class:`~vehicles.quadrotor.aero.DownwashConfig`).
    downwash_model : DownwashConfig
        Constants of the downwash model.
    ground_effect : bool
        Scale each rotor's thrust by the Cheeseman-Bennett factor near the ground plane.
    ground_z : float
        Height of the ground plane for ground effect (m).
    ground_effect_min_height_ratio : float
        Rotor height floor, in rotor radii, below which the ground-effect factor stops growing (-), > 0.25.
    outer_loop_hz : int
        Rate of the position and velocity loops (Hz); must divide ``physics_hz``.
    """

    wind: WindConfig | None = None
    downwash: bool = False
    downwash_model: DownwashConfig = field(default_factory=DownwashConfig)
    ground_effect: bool = False
    ground_z: float = 0.0
    ground_effect_min_height_ratio: float = 0.5
    outer_loop_hz: int = 48

    def __post_init__(self) -> None:
        hz = self.outer_loop_hz
        if not (isinstance(hz, (int, np.integer)) and not isinstance(hz, bool) and hz > 0):
            raise ValueError(f"FleetOptions.outer_loop_hz must be a positive integer (Hz), got {self.outer_loop_hz!r}")
        if not (self.ground_effect_min_height_ratio > 0.25):
            raise ValueError("FleetOptions.ground_effect_min_height_ratio must be > 0.25, got "
                             f"{self.ground_effect_min_height_ratio!r}")
        if not np.isfinite(self.ground_z):
            raise ValueError(f"FleetOptions.ground_z must be finite, got {self.ground_z!r}")


# Columns of the per-UAV constants of the per-tick stages (``QuadrotorFleet._k``), copied from the stages.
_K_RP, _K_YAW, _MAX_RATE = 0, 1, 2          # attitude: roll/pitch and yaw gains, rate limits (3)
_JK, _J = 5, 8                              # rate: J K_w (3), J (3)
_F_MIN, _F_MAX, _K_F = 11, 12, 13           # mixer: rotor thrust range, thrust coefficient
_ALPHA, _W_MAX = 14, 15                     # rotors: lag factor per step, top speed
_C_LIN, _C_QUAD = 16, 19                    # body drag coefficients (3 + 3)
_N_K = 22
# Columns of the inner loops' outputs (``QuadrotorFleet._w``).
_W_RATE, _W_THRUST, _W_TORQUE, _W_F = 0, 3, 4, 7
_N_W = 11


@njit(cache=True)
def _actuate(omega: np.ndarray, omega_cmd: np.ndarray, k: np.ndarray, f_nom: np.ndarray, f: np.ndarray,
             R_WB: np.ndarray, alloc: np.ndarray, v_rel_W: np.ndarray, F_W: np.ndarray, tau_W: np.ndarray,
             total: np.ndarray) -> None:
    """Out of ground effect, one step of the rotors (:meth:`RotorBank.step`: ``omega`` and ``f_nom`` in place),
    ``f = f_nom``, and the total wrench (:func:`total_wrench_W` into ``F_W``, ``tau_W``, ``total``); ``k`` holds the
    per-UAV constants (columns ``_ALPHA``, ...)."""
    _lag_step(omega, omega_cmd, k[:, _ALPHA], k[:, _W_MAX], k[:, _K_F], f_nom)
    f[:] = f_nom
    total_wrench_W(R_WB, f, f_nom, alloc, v_rel_W, k[:, _C_LIN:_C_LIN + 3], k[:, _C_QUAD:_C_QUAD + 3], F_W, tau_W,
                   total)


@njit(cache=True)
def _inner_loops(R_WB: np.ndarray, omega_B: np.ndarray, F_W: np.ndarray, yaw: np.ndarray, yaw_rate: np.ndarray,
                 k: np.ndarray, alloc_inv: np.ndarray, w: np.ndarray, omega_cmd: np.ndarray) -> None:
    """The inner loops of :class:`AttitudeController`, :class:`RateController` and :class:`MotorMixer` on the attitude
    set-point ``(F_W, yaw, yaw_rate)``: body-rate set-points, collective thrusts, body torques and rotor thrusts into
    the columns of ``w`` (``_W_RATE``, ...), rotor speed commands into ``omega_cmd`` (N, 4)."""
    rate, thrust = w[:, _W_RATE:_W_RATE + 3], w[:, _W_THRUST]
    torque, f = w[:, _W_TORQUE:_W_TORQUE + 3], w[:, _W_F:_W_F + 4]
    _attitude_rates(R_WB, F_W, yaw, yaw_rate, k[:, _K_RP], k[:, _K_YAW], k[:, _MAX_RATE:_MAX_RATE + 3], rate, thrust)
    _rate_torques(rate, omega_B, k[:, _JK:_JK + 3], k[:, _J:_J + 3], torque)
    _allocate(thrust, torque, alloc_inv, k[:, _F_MIN], k[:, _F_MAX], k[:, _K_F], f, omega_cmd)


class QuadrotorFleet:
    """N quadrotor bodies in PyBullet client ``client_id`` with their flight controllers.

    Parameters
    ----------
    client_id : int
        PyBullet physics client (gravity ``-9.81`` m/s^2 and ``fixedTimeStep = 1/physics_hz`` set by the caller).
    airframes : Sequence[QuadrotorParams]
        One airframe per UAV.
    p0_W : np.ndarray
        (N, 3) initial positions (m).
    yaw0 : np.ndarray
        (N,) initial headings (rad).
    physics_hz : int
        Physics rate (Hz).
    options : FleetOptions
        Shared options.
    rng : np.random.Generator
        Randomness (wind turbulence).

    Notes
    -----
    Every UAV starts hovering at ``p0_W`` with rotors at hover speed and the command ``PositionSetpoint(p0_W, yaw0)``.
    A command given with :meth:`set_command` takes effect at the next outer-loop tick.
    """

    def __init__(self, client_id: int, airframes: Sequence[QuadrotorParams], p0_W: np.ndarray, yaw0: np.ndarray,
                 physics_hz: int, options: FleetOptions, rng: np.random.Generator) -> None:
        if not isinstance(physics_hz, (int, np.integer)) or isinstance(physics_hz, bool) or physics_hz <= 0:
            raise ValueError(f"physics_hz must be a positive integer (Hz), got {physics_hz!r}")
        self._outer_div = divisor(options.outer_loop_hz, int(physics_hz), "FleetOptions.outer_loop_hz")
        n = len(airframes)
        p0_W = np.asarray(p0_W, dtype=float)
        yaw0 = np.asarray(yaw0, dtype=float)
        if p0_W.shape != (n, 3) or not np.all(np.isfinite(p0_W)):
            raise ValueError(f"p0_W must be finite with shape ({n}, 3) for {n} airframes, got shape {p0_W.shape}")
        if yaw0.shape != (n,) or not np.all(np.isfinite(yaw0)):
            raise ValueError(f"yaw0 must be finite with shape ({n},) for {n} airframes, got shape {yaw0.shape}")
        self.client_id = client_id
        self.physics_hz = int(physics_hz)
        self.options = options
        self.airframes = tuple(airframes)
        self._dt = 1.0 / self.physics_hz
        s = self._s = AirframeStack.from_params(self.airframes)
        self.body_ids = self._create_bodies(p0_W, yaw0)
        self._body_list: list[int] = self.body_ids.tolist()

        hover = np.sqrt(s.mass * GRAVITY / (4.0 * s.k_f))
        self._rotors = RotorBank(s, self._dt, np.repeat(hover[:, None], 4, axis=1))
        self._thrust = s.k_f[:, None] * self._rotors.omega**2
        self._total_thrust = self._thrust.sum(axis=1)
        self._wind = DrydenWind(options.wind, n, self._dt, rng) if options.wind is not None else None
        self._wake_radius = np.array([a.arm_length + a.rotor_radius for a in self.airframes])
        self._disk_area = 4.0 * np.pi * s.rotor_radius**2
        self._rotor_r = s.rotor_pos_B

        self._vel_ctrl = VelocityController(s, self._outer_div * self._dt)
        self._tv_ctrl = ThrustVectorController(s)
        self._att_ctrl = AttitudeController(s)
        self._rate_ctrl = RateController(s)
        self._mixer = MotorMixer(s)
        # The constants of the per-tick stages, copied into one array, and the inner loops' outputs (_inner_loops).
        k = self._k = np.empty((n, _N_K))
        k[:, _K_RP], k[:, _K_YAW] = self._att_ctrl._k_rp, self._att_ctrl._k_yaw
        k[:, _MAX_RATE:_MAX_RATE + 3] = self._att_ctrl._max_rate
        k[:, _JK:_JK + 3], k[:, _J:_J + 3] = self._rate_ctrl._JK, self._rate_ctrl._J
        k[:, _F_MIN], k[:, _F_MAX], k[:, _K_F] = self._mixer._f_min, self._mixer._f_max, self._mixer._k_f
        k[:, _ALPHA], k[:, _W_MAX] = self._rotors._alpha, self._rotors._w_max
        k[:, _C_LIN:_C_LIN + 3], k[:, _C_QUAD:_C_QUAD + 3] = s.drag_linear, s.drag_quadratic
        self._w = np.zeros((n, _N_W))

        self._tick = 0
        self._events: list[dict] = []
        # The live state: arrays refilled in place at every read (``state`` hands out copies).
        self._x = np.zeros((n, 13))  # rows (p_W, q_WB, v_W, omega_W) as PyBullet reports them
        # the state's arrays are contiguous copies of x's columns, not views: a column view is contiguous for one UAV
        # only, and the compiled kernels they are handed to would be compiled again for each layout
        self._state = FleetState(p_W=np.zeros((n, 3)), q_WB=np.zeros((n, 4)), R_WB=np.zeros((n, 3, 3)),
                                 v_W=np.zeros((n, 3)), omega_B=np.zeros((n, 3)), rotor_speed=self._rotors.omega,
                                 thrust=self._thrust)
        self._read_state()
        self._shaper = CommandShaper(s, self._dt, self._state)
        F0 = np.zeros((n, 3))
        F0[:, 2] = s.mass * GRAVITY
        self._att_sp = AttitudeSetpoint(F_W=F0, yaw=yaw0.copy(), yaw_rate=np.zeros(n))
        self._tilt_saturated = np.zeros(n, dtype=bool)
        self.force_W = np.zeros((n, 3))
        """(N, 3) total external force applied at the last :meth:`apply_actuation`, world frame (N)."""
        self.torque_W = np.zeros((n, 3))
        """(N, 3) total external torque applied at the last :meth:`apply_actuation`, world frame (N m)."""
        self.downwash_W = np.zeros((n, 3))
        """(N, 3) downwash part of ``force_W`` (N)."""
        self.wind_W = np.zeros((n, 3))
        """(N, 3) wind velocity at each UAV at the last step (m/s)."""

    # ------------------------------------------------------------------ construction
    def _create_bodies(self, p0_W: np.ndarray, yaw0: np.ndarray) -> np.ndarray:
        cid = self.client_id
        shapes: dict[tuple[float, float, float], tuple[int, int]] = {}
        q0 = yaw_to_quat(yaw0)
        ids = []
        for i, a in enumerate(self.airframes):
            key = tuple(a.body_half_extents)
            if key not in shapes:
                shapes[key] = (
                    p.createCollisionShape(p.GEOM_BOX, halfExtents=list(a.body_half_extents), physicsClientId=cid),
                    p.createVisualShape(p.GEOM_BOX, halfExtents=list(a.body_half_extents),
                                        rgbaColor=[0.2, 0.2, 0.25, 1.0], physicsClientId=cid),
                )
            col, vis = shapes[key]
            b = p.createMultiBody(baseMass=a.mass, baseCollisionShapeIndex=col, baseVisualShapeIndex=vis,
                                  basePosition=p0_W[i].tolist(), baseOrientation=q0[i].tolist(),
                                  baseInertialFramePosition=[0.0, 0.0, 0.0], physicsClientId=cid)
            p.changeDynamics(b, -1, localInertiaDiagonal=list(a.inertia), linearDamping=0.0, angularDamping=0.0,
                             physicsClientId=cid)
            ids.append(b)
        return np.array(ids, dtype=int)

    # ------------------------------------------------------------------ run loop
    def apply_actuation(self) -> None:
        """Run-loop phase 1: advance the rotors one step and apply each UAV's total force and torque.

        Rotor thrust ``k_f w^2`` (times the ground-effect factor), reaction torques ``k_m w^2``, body drag of the
        air-relative velocity and downwash are evaluated on the state read at the previous :meth:`after_step` and held
        over the step (PyBullet clears external forces after each ``stepSimulation``).
        """
        st, s, opt = self._state, self._s, self.options
        F_W, tau_W = self.force_W, self.torque_W
        v_rel = st.v_W
        if self._wind is not None:
            self.wind_W = self._wind.step()
            v_rel = v_rel - self.wind_W
        if opt.ground_effect:
            f_nom = self._rotors.step()
            f = self._thrust
            rotor_z = st.p_W[:, 2:3] + np.matmul(self._rotor_r, st.R_WB[:, 2, :, None])[:, :, 0] - opt.ground_z
            np.multiply(f_nom, ground_effect_factor(rotor_z, s.rotor_radius[:, None],
                                                    opt.ground_effect_min_height_ratio), out=f)
            total_wrench_W(st.R_WB, f, f_nom, s.alloc, v_rel, s.drag_linear, s.drag_quadratic, F_W, tau_W,
                           self._total_thrust)
        else:
            r = self._rotors
            _actuate(r.omega, r.omega_cmd, self._k, r._thrust, self._thrust, st.R_WB, s.alloc, v_rel, F_W, tau_W,
                     self._total_thrust)
        if opt.downwash:
            self.downwash_W = downwash_force_W(st.p_W, self._total_thrust, self._wake_radius, self._disk_area,
                                               opt.downwash_model)
            F_W += self.downwash_W
        cid, world = self.client_id, p.WORLD_FRAME
        apply_force, apply_torque = p.applyExternalForce, p.applyExternalTorque
        for b, F, tau, pos in zip(self._body_list, F_W.tolist(), tau_W.tolist(), st.p_W.tolist(), strict=True):
            apply_force(b, -1, F, pos, world, cid)
            apply_torque(b, -1, tau, world, cid)

    def after_step(self, tick: int) -> None:
        """Run-loop phase 3: read the new state and run the controllers due at ``tick``."""
        self._tick = tick
        st = self._read_state()
        if tick % self._outer_div == 0:
            vsp = self._shaper.update(st, tick)
            self._vel_ctrl.freeze = self._tv_ctrl.saturated
            self._att_sp = self._tv_ctrl.update(self._vel_ctrl.update(vsp, st), st)
            self._record_tilt_events(tick)
        sp = self._att_sp
        _inner_loops(st.R_WB, st.omega_B, sp.F_W, sp.yaw, sp.yaw_rate, self._k, self._s.alloc_inv, self._w,
                     self._rotors.omega_cmd)

    def set_command(self, i: int, cmd: FlightSetpoint) -> None:
        """Give UAV ``i`` a new command; envelope saturations are recorded as events (see :meth:`pop_events`)."""
        if not 0 <= i < len(self.body_ids):
            raise IndexError(f"uav index {i} out of range for a fleet of {len(self.body_ids)}")
        self._events.extend(self._shaper.set_command(i, cmd, self._state, self._tick))

    def pop_events(self) -> list[dict]:
        """Events since the last call, oldest first, e.g. ``{"type": "command_saturated", "uav": 0, "tick": 480,
        "field": "speed", "requested": 25.0, "applied": 20.0, "limit": "max_speed"}``; the list is then cleared."""
        events, self._events = self._events, []
        return events

    # ------------------------------------------------------------------ state
    @property
    def state(self) -> FleetState:
        """State after the last physics step (arrays are copies)."""
        st = self._state
        return FleetState(p_W=st.p_W.copy(), q_WB=st.q_WB.copy(), R_WB=st.R_WB.copy(), v_W=st.v_W.copy(),
                          omega_B=st.omega_B.copy(), rotor_speed=self._rotors.omega.copy(), thrust=self._thrust.copy())

    @property
    def live_state(self) -> FleetState:
        """State after the last physics step, without copies: the arrays the fleet refills at every step, valid until
        the next one and only to be read (for a check at every tick, where :attr:`state`'s copies would cost more
        than the check)."""
        return self._state

    @property
    def tilt_limit(self) -> np.ndarray:
        """(N,) largest tilt the controllers command (rad): ``tilt_max - tilt_margin``."""
        return self._tv_ctrl.tilt_limit

    def _read_state(self) -> FleetState:
        cid, st = self.client_id, self._state
        get_pose, get_vel = p.getBasePositionAndOrientation, p.getBaseVelocity
        rows = []
        for i in self._body_list:  # one row per UAV: position, quaternion, linear and angular velocity (world)
            (pos, quat), (vel, omega) = get_pose(i, cid), get_vel(i, cid)
            rows.append(pos + quat + vel + omega)
        x = self._x
        x[:] = rows
        st.p_W[:], st.q_WB[:], st.v_W[:] = x[:, 0:3], x[:, 3:7], x[:, 7:10]
        rotation_and_body_rates(x, st.R_WB, st.omega_B)
        return st

    def _record_tilt_events(self, tick: int) -> None:
        sat = self._tv_ctrl.saturated
        if not (sat.any() or self._tilt_saturated.any()):
            return
        for i in np.flatnonzero(sat & ~self._tilt_saturated).tolist():
            self._events.append({"type": "command_saturated", "uav": i, "tick": tick, "field": "tilt",
                                 "requested": float(self._tv_ctrl.requested_tilt[i]),
                                 "applied": float(self._tv_ctrl.tilt_limit[i]), "limit": "tilt_max"})
        self._tilt_saturated = sat.copy()
