"""Flight commands -> velocity set-points (the position loop, the unicycle integrator) with envelope saturation."""

from __future__ import annotations

import math

import numpy as np

from vehicles.quadrotor.commands import (
    FACE_VELOCITY_MIN_SPEED,
    FlightCommand,
    PositionCommand,
    UnicycleCommand,
    VelocityCommand,
)
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


def sqrt_speed(distance: np.ndarray, k_p: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """Speed towards a target ``distance`` (>= 0) away: ``k_p d`` near it, ``sqrt(2 a (d - a / (2 k_p^2)))`` beyond
    ``d = a / k_p^2`` (continuous, with its derivative), so the UAV can always stop with deceleration ``a``."""
    linear = accel / k_p**2
    far = np.sqrt(2.0 * accel * np.maximum(distance - 0.5 * linear, 0.0))
    return np.where(distance > linear, far, k_p * distance)


class CommandShaper:
    """Hold every UAV's current command and produce the stacked :class:`VelocitySetpoint` at each outer-loop tick.

    - :class:`PositionCommand`: towards the target at :func:`sqrt_speed` (``K_p e`` close to it, a braking-distance
      law further away, horizontally and vertically), clipped to ``max_speed`` and ``max_climb_rate`` (the normal way
      to approach a far point; not reported as saturation).
    - :class:`VelocityCommand`: used as given after saturation at :meth:`set_command`.
    - :class:`UnicycleCommand`: ``psi_c = psi_0 + r (k - k_0) dt`` from the integer tick count ``k``,
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
        self._update_masks()

    def _update_masks(self) -> None:
        self._pos_mask = self._mode == _POSITION
        self._uni_mask = self._mode == _UNICYCLE
        self._any_pos = bool(self._pos_mask.any())
        self._any_uni = bool(self._uni_mask.any())
        self._pos_col = self._pos_mask[:, None]
        self._uni_col = self._uni_mask[:, None]

    def set_command(self, i: int, cmd: FlightCommand, state: FleetState, tick: int) -> list[dict]:
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

        if not isinstance(cmd, (PositionCommand, VelocityCommand, UnicycleCommand)):
            raise TypeError(f"unsupported command type {type(cmd).__name__}")
        self._v[i] = 0.0
        self._rate[i] = 0.0
        if isinstance(cmd, PositionCommand):
            self._mode[i] = _POSITION
            self._p[i] = cmd.p_W
            self._yaw[i] = yaw_now if cmd.yaw is None else cmd.yaw
        elif isinstance(cmd, VelocityCommand):
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
            elif h_applied > FACE_VELOCITY_MIN_SPEED:
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
        self._update_masks()
        return events

    def update(self, state: FleetState, tick: int) -> VelocitySetpoint:
        """Velocity set-points (N, 3), feed-forward accelerations and headings for all UAVs at ``tick``.

        Only the branches of the modes in use are evaluated.
        """
        s = self._s
        v_W, yaw, a_ff = self._v, self._yaw, np.zeros_like(self._v)
        if self._any_pos:
            e = self._p - state.p_W
            d_xy = np.hypot(e[:, 0], e[:, 1])
            speed_xy = np.minimum(sqrt_speed(d_xy, s.pos_p[:, 0], self._brake_xy), s.max_speed)
            v_pos = e * (speed_xy / np.maximum(d_xy, 1e-12))[:, None]
            v_pos[:, 2] = np.sign(e[:, 2]) * np.minimum(sqrt_speed(np.abs(e[:, 2]), s.pos_p[:, 2], self._brake_z),
                                                         s.max_climb_rate)
            v_W = np.where(self._pos_col, v_pos, v_W)
        if self._any_uni:
            # Heading from the integer tick count (no accumulated float time).
            psi = self._yaw + self._rate * ((tick - self._tick0) * self._dt)
            c, sn = np.cos(psi), np.sin(psi)
            v_uni = np.empty_like(a_ff)
            v_uni[:, 0] = self._speed * c
            v_uni[:, 1] = self._speed * sn
            v_uni[:, 2] = np.minimum(np.maximum(s.pos_p[:, 2] * (self._alt - state.p_W[:, 2]), -s.max_climb_rate),
                                     s.max_climb_rate)
            turn = self._speed * self._rate
            a_ff[:, 0] = -turn * sn
            a_ff[:, 1] = turn * c
            v_W = np.where(self._uni_col, v_uni, v_W)
            a_ff *= self._uni_col
            yaw = np.where(self._uni_mask, psi, yaw)
        return VelocitySetpoint(v_W=v_W, a_ff_W=a_ff, yaw=yaw, yaw_rate=self._rate.copy())
