"""Flight set-points -> stacked velocity set-points (position loop, unicycle integrator) with envelope saturation."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from interfaces import setpoints as flight
from vehicles.quadrotor.params import GRAVITY
from vehicles.quadrotor.setpoints import VelocitySetpoint
from vehicles.quadrotor.stack import AirframeStack
from vehicles.quadrotor.state import FleetState

__all__ = ["CommandShaper", "sqrt_speed", "TURN_ACCEL_FRACTION", "BRAKE_ACCEL_FRACTION"]

TURN_ACCEL_FRACTION = 0.7
"""Share of the tilt-limited horizontal acceleration ``g tan(tilt)`` a unicycle turn may use; the rest is left for
drag and disturbances (-)."""

BRAKE_ACCEL_FRACTION = 0.5
"""Share of the tilt-limited horizontal acceleration (and of ``g`` vertically) the position loop plans to brake
with when approaching its target (-)."""

_POSITION, _VELOCITY, _UNICYCLE = 0, 1, 2


@njit(cache=True)
def sqrt_speed(distance: float, k_p: float, accel: float) -> float:
    """Speed towards a target ``distance`` (>= 0) away: ``k_p d`` near it, ``sqrt(2 a (d - a / (2 k_p^2)))`` beyond
    ``d = a / k_p^2`` (continuous, with its derivative), so the UAV can always stop with deceleration ``a``."""
    linear = accel / k_p**2
    if distance > linear:
        return math.sqrt(2.0 * accel * (distance - 0.5 * linear))
    return k_p * distance


@njit(cache=True)
def _shape(mode: np.ndarray, p_sp: np.ndarray, v_sp: np.ndarray, yaw: np.ndarray, speed: np.ndarray,
           rate: np.ndarray, alt: np.ndarray, tick0: np.ndarray, tick: int, dt: float, p_W: np.ndarray,
           pos_p: np.ndarray, brake_xy: np.ndarray, brake_z: np.ndarray, max_speed: np.ndarray,
           max_climb: np.ndarray, v_W: np.ndarray, a_ff: np.ndarray, yaw_out: np.ndarray) -> None:
    """Velocity set-points ``v_W`` (N, 3), feed-forward accelerations ``a_ff`` (N, 3) and headings ``yaw_out`` (N,) of
    :meth:`CommandShaper.update` (the laws in :class:`CommandShaper`), written into the given arrays."""
    for i in range(mode.shape[0]):
        a_ff[i, 0], a_ff[i, 1], a_ff[i, 2] = 0.0, 0.0, 0.0
        yaw_out[i] = yaw[i]
        if mode[i] == _POSITION:
            ex, ey, ez = p_sp[i, 0] - p_W[i, 0], p_sp[i, 1] - p_W[i, 1], p_sp[i, 2] - p_W[i, 2]
            d_xy = math.hypot(ex, ey)
            k = min(sqrt_speed(d_xy, pos_p[i, 0], brake_xy[i]), max_speed[i]) / max(d_xy, 1e-12)
            v_W[i, 0], v_W[i, 1] = ex * k, ey * k
            v_W[i, 2] = np.sign(ez) * min(sqrt_speed(abs(ez), pos_p[i, 2], brake_z[i]), max_climb[i])
        elif mode[i] == _VELOCITY:
            v_W[i] = v_sp[i]
        else:  # unicycle: heading from the integer tick count (no accumulated float time)
            psi = yaw[i] + rate[i] * ((tick - tick0[i]) * dt)
            c, sn = math.cos(psi), math.sin(psi)
            v_W[i, 0], v_W[i, 1] = speed[i] * c, speed[i] * sn
            v_W[i, 2] = min(max(pos_p[i, 2] * (alt[i] - p_W[i, 2]), -max_climb[i]), max_climb[i])
            turn = speed[i] * rate[i]
            a_ff[i, 0], a_ff[i, 1] = -turn * sn, turn * c
            yaw_out[i] = psi


class CommandShaper:
    """Hold every UAV's current command and produce the stacked :class:`VelocitySetpoint` at each outer-loop tick.

    The commands are the flight set-points of :mod:`interfaces.setpoints`:

    - ``PositionSetpoint``: towards the target at :func:`sqrt_speed` (``K_p e`` close to it, a braking-distance
      law further away, horizontally and vertically), clipped to ``max_speed`` and ``max_climb_rate`` (the normal way
      to approach a far point; not reported as saturation).
    - ``VelocitySetpoint``: used as given after saturation at :meth:`set_command`.
    - ``UnicycleSetpoint``: ``psi_c = psi_0 + r (k - k_0) dt`` from the integer tick count ``k``,
      ``v = V (cos psi_c, sin psi_c, 0) + (0, 0, K_pz (h - z))``, feed-forward ``a = V r (-sin psi_c, cos psi_c, 0)``
      and heading rate ``r``.

    Parameters
    ----------
    stack : AirframeStack
        Envelope and gains per UAV.
    physics_dt : float
        Physics step (s), to turn tick counts into time.
    state : FleetState
        Initial state; every UAV starts holding its initial position and heading.
    """

    def __init__(self, stack: AirframeStack, physics_dt: float, state: FleetState) -> None:
        s = stack
        self._s = s
        self._dt = physics_dt
        n = s.n
        self._mode = np.full(n, _POSITION)
        self._p = state.p_W.copy()
        self._v = np.zeros((n, 3))
        """Velocity set-points of UAVs in velocity mode (zero for the others)."""
        self._yaw = np.arctan2(state.R_WB[:, 1, 0], state.R_WB[:, 0, 0])
        """Held heading (position and velocity modes) or initial heading psi_0 (unicycle mode)."""
        self._speed = np.zeros(n)
        self._rate = np.zeros(n)
        """Heading rate of UAVs in unicycle mode (zero for the others)."""
        self._alt = state.p_W[:, 2].copy()
        self._tick0 = np.zeros(n, dtype=np.int64)
        self._max_turn_accel = TURN_ACCEL_FRACTION * GRAVITY * np.tan(s.tilt_max - s.tilt_margin)
        self._brake_xy = BRAKE_ACCEL_FRACTION * GRAVITY * np.tan(s.tilt_max - s.tilt_margin)
        self._brake_z = np.full(n, BRAKE_ACCEL_FRACTION * GRAVITY)
        self._out = VelocitySetpoint(v_W=np.zeros((n, 3)), a_ff_W=np.zeros((n, 3)), yaw=np.zeros(n),
                                     yaw_rate=np.zeros(n))

    def set_command(self, i: int, cmd: flight.FlightSetpoint, state: FleetState, tick: int) -> list[dict]:
        """Make ``cmd`` UAV ``i``'s command from ``tick`` on; return the saturation events it caused."""
        s = self._s
        yaw_now = float(math.atan2(state.R_WB[i, 1, 0], state.R_WB[i, 0, 0]))
        events: list[dict] = []

        def saturate(field: str, requested: float, limit: float, limit_name: str) -> float:
            if abs(requested) <= limit:
                return requested
            applied = math.copysign(limit, requested)
            events.append({"type": "command_saturated", "uav": i, "tick": tick, "field": field,
                           "requested": float(requested), "applied": float(applied), "limit": limit_name})
            return applied

        if not isinstance(cmd, (flight.PositionSetpoint, flight.VelocitySetpoint, flight.UnicycleSetpoint)):
            raise TypeError(f"unsupported command type {type(cmd).__name__}")
        self._v[i] = 0.0
        self._rate[i] = 0.0
        if isinstance(cmd, flight.PositionSetpoint):
            self._mode[i] = _POSITION
            self._p[i] = cmd.p_W
            self._yaw[i] = yaw_now if cmd.yaw is None else cmd.yaw
        elif isinstance(cmd, flight.VelocitySetpoint):
            v = np.array(cmd.v_W, dtype=float)
            h = float(np.hypot(v[0], v[1]))
            h_applied = saturate("speed", h, float(s.max_speed[i]), "max_speed")
            if h > 0:
                v[:2] *= h_applied / h
            v[2] = saturate("climb_rate", float(v[2]), float(s.max_climb_rate[i]), "max_climb_rate")
            self._mode[i] = _VELOCITY
            self._v[i] = v
            if cmd.yaw is not None:
                self._yaw[i] = cmd.yaw
            elif h_applied > flight.FACE_VELOCITY_MIN_SPEED:
                self._yaw[i] = math.atan2(v[1], v[0])
            else:
                self._yaw[i] = yaw_now
        else:
            speed = saturate("speed", cmd.speed, float(s.max_speed[i]), "max_speed")
            rate = saturate("heading_rate", cmd.heading_rate, float(s.max_heading_rate[i]), "max_heading_rate")
            if speed > 0:
                rate = saturate("heading_rate", rate, float(self._max_turn_accel[i]) / speed, "tilt_max")
            self._mode[i] = _UNICYCLE
            self._speed[i], self._rate[i], self._alt[i] = speed, rate, cmd.altitude
            self._yaw[i] = yaw_now
            self._tick0[i] = tick
        return events

    def update(self, state: FleetState, tick: int) -> VelocitySetpoint:
        """Velocity set-points (N, 3), feed-forward accelerations and headings for all UAVs at ``tick`` (the shaper's
        own set-point, overwritten at the next update)."""
        s, out = self._s, self._out
        _shape(self._mode, self._p, self._v, self._yaw, self._speed, self._rate, self._alt, self._tick0, tick,
               self._dt, state.p_W, s.pos_p, self._brake_xy, self._brake_z, s.max_speed, s.max_climb_rate, out.v_W,
               out.a_ff_W, out.yaw)
        out.yaw_rate[:] = self._rate
        return out
