"""Lyapunov vector-field standoff guidance with speed control for phase keeping (Frew, Lawrence, Morris 2008).

Relative position r = p − p_t of the UAV from the target, ρ = |r|, standoff radius r_d, circulation d = ±1 (+1
counter-clockwise). The guidance vector field (relative velocity) is

    ṙ_d = −v_r / (ρ (ρ² + r_d²)) · [ r_x (ρ² − r_d²) + d · r_y · 2 ρ r_d ,
                                     r_y (ρ² − r_d²) − d · r_x · 2 ρ r_d ],

which has magnitude v_r everywhere and the circle ρ = r_d as its globally attracting limit cycle: with
V = (ρ² − r_d²)², V̇ = −4 v_r ρ (ρ² − r_d²)² / (ρ² + r_d²) ≤ 0. The inertial velocity command adds the target
velocity, v_c = ṙ_d + v_t; the UAV flies the heading ψ_d = atan2(v_c) with

    ω = ψ̇_d + k_ψ · wrap(ψ_d − ψ)          (feed-forward by a finite difference along the predicted motion)

and the speed |v_c| (both clamped). Phase keeping (decoupled speed control): with phase angles θ = atan2(r_y, r_x)
and desired spacing Δφ between consecutive slots (slot s trails slot 0 by s·Δφ in the circulation direction), the
phase error against teammate j is e_j = wrap(θ_j − θ + d (s_j − s) Δφ) and the relative speed is scaled,
v_r = v_0 (1 + k_φ · d · mean_j e_j), clamped to [v_r,min, v_r,max]: a UAV that lags behind its slot speeds up.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from autonomy.guidance.base import Guidance
from interfaces.setpoints import UnicycleSetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState
from interfaces.team_states import teammate_slots, teammates_xy

__all__ = ["VectorFieldConfig", "VectorFieldGuidance", "wrap_angle", "phase_errors"]


def wrap_angle(a: np.ndarray | float) -> np.ndarray | float:
    """Wrap an angle (rad) to [−π, π)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def _clip(x: float, lo: float, hi: float) -> float:
    """``float(np.clip(x, lo, hi))`` for one number, without numpy's array dispatch (a few µs a call, several calls a
    step): the value numpy gives, ``x`` itself unless it lies outside [lo, hi] (NaN kept, a zero's sign too)."""
    return float(lo if x < lo else hi if x > hi else x)


def phase_errors(theta: float, slot: int, teammates_theta: Sequence[float], teammates_slot: Sequence[int],
                 separation: float, direction: int) -> np.ndarray:
    """Phase errors e_j = wrap(θ_j − θ + d (s_j − s) Δφ) (rad) against each teammate (see the module docstring)."""
    th = np.asarray(teammates_theta, dtype=float)
    ds = np.asarray(teammates_slot, dtype=float) - slot
    return np.asarray(wrap_angle(th - theta + direction * ds * separation))


@dataclass(frozen=True, kw_only=True)
class VectorFieldConfig:
    """Lyapunov vector-field guidance.

    Attributes
    ----------
    standoff_radius : float
        Desired horizontal distance r_d from the target (m), > 0.
    nominal_speed : float
        Nominal relative speed v_0 along the field (m/s), > 0.
    min_speed, max_speed : float
        Bounds of the commanded ground speed (m/s), 0 <= min < max.
    max_heading_rate : float
        Bound of the commanded heading rate (rad/s), > 0.
    heading_gain : float
        Heading-error gain k_ψ (1/s), > 0.
    phase_gain : float
        Phase-keeping gain k_φ (1/rad), >= 0 (0 disables phase keeping).
    relative_speed_bounds : tuple[float, float]
        Bounds of v_r as fractions of v_0 (−), 0 < low <= 1 <= high.
    team_size : int
        Number of UAVs sharing the orbit, >= 1.
    phase_separation : float | None
        Desired phase spacing between consecutive slots Δφ (rad), in (0, 2π]; ``None`` means 2π / team_size.
    direction : int
        +1 counter-clockwise or −1 clockwise circulation.
    altitude : float
        Commanded altitude (m).
    min_course_speed : float
        Below this horizontal speed the yaw replaces the course angle (m/s), >= 0.
    feedforward_dt : float
        Finite-difference step of the heading-rate feed-forward (s), > 0.
    """

    standoff_radius: float = 120.0
    nominal_speed: float = 12.0
    min_speed: float = 0.0
    max_speed: float = 20.0
    max_heading_rate: float = 0.6
    heading_gain: float = 1.0
    phase_gain: float = 0.5
    relative_speed_bounds: tuple[float, float] = (0.5, 1.5)
    team_size: int = 1
    phase_separation: float | None = None
    direction: int = 1
    altitude: float = 60.0
    min_course_speed: float = 0.5
    feedforward_dt: float = 0.05

    def __post_init__(self) -> None:
        for name in ("standoff_radius", "nominal_speed", "max_heading_rate", "heading_gain", "feedforward_dt"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"VectorFieldConfig.{name} must be > 0, got {v}")
        if not (0 <= self.min_speed < self.max_speed):
            raise ValueError(f"VectorFieldConfig.min_speed/max_speed must satisfy 0 <= min < max, got "
                             f"({self.min_speed}, {self.max_speed})")
        if not (self.phase_gain >= 0):
            raise ValueError(f"VectorFieldConfig.phase_gain must be >= 0 1/rad, got {self.phase_gain}")
        lo, hi = self.relative_speed_bounds
        if not (0 < lo <= 1 <= hi):
            raise ValueError(f"VectorFieldConfig.relative_speed_bounds must satisfy 0 < low <= 1 <= high, got "
                             f"{self.relative_speed_bounds}")
        if int(self.team_size) != self.team_size or self.team_size < 1:
            raise ValueError(f"VectorFieldConfig.team_size must be an integer >= 1, got {self.team_size}")
        if self.phase_separation is not None and not (0 < self.phase_separation <= 2 * np.pi):
            raise ValueError(f"VectorFieldConfig.phase_separation must be in (0, 2π] rad, got {self.phase_separation}")
        if self.direction not in (1, -1):
            raise ValueError(f"VectorFieldConfig.direction must be +1 or -1, got {self.direction}")
        if not (self.min_course_speed >= 0):
            raise ValueError(f"VectorFieldConfig.min_course_speed must be >= 0 m/s, got {self.min_course_speed}")

    @property
    def separation(self) -> float:
        """Phase spacing Δφ between consecutive slots (rad)."""
        return 2 * np.pi / self.team_size if self.phase_separation is None else float(self.phase_separation)


class VectorFieldGuidance(Guidance):
    """Lyapunov vector-field standoff guidance (see the module docstring) for the UAV in ``slot``."""

    def __init__(self, config: VectorFieldConfig, slot: int = 0) -> None:
        super().__init__()
        if int(slot) != slot or slot < 0:
            raise ValueError(f"slot must be a non-negative integer, got {slot}")
        self.config = config
        self.slot = int(slot)

    def field(self, r: np.ndarray, v_rel: float) -> np.ndarray:
        """Relative-velocity field ṙ_d (m/s) at relative position ``r`` (2,) (m) for relative speed ``v_rel`` (m/s)."""
        c = self.config
        rx, ry = float(r[0]), float(r[1])
        rho = max(float(np.hypot(rx, ry)), 1e-6)
        rd = c.standoff_radius
        k = -v_rel / (rho * (rho * rho + rd * rd))
        a, b = rho * rho - rd * rd, 2.0 * rho * rd * c.direction
        return k * np.array([rx * a + ry * b, ry * a - rx * b])

    def relative_speed(self, r: np.ndarray, target: TargetEstimate, teammates: Sequence[TeammateState],
                       t: float) -> float:
        """v_r = v_0 (1 + k_φ d mean_j e_j), clamped (m/s); v_0 without teammates."""
        c = self.config
        if not teammates or c.phase_gain == 0:
            return c.nominal_speed
        theta = float(np.arctan2(r[1], r[0]))
        d = teammates_xy(teammates, t) - target.predict_xy(t)  # the whole team at once: flat cost per teammate
        th_j = np.arctan2(d[:, 1], d[:, 0])
        e = phase_errors(theta, self.slot, th_j, teammate_slots(teammates), c.separation, c.direction)
        lo, hi = c.relative_speed_bounds
        factor = _clip(1.0 + c.phase_gain * c.direction * float(np.mean(e)), lo, hi)
        return c.nominal_speed * factor

    def command(self, own: OwnState, target: TargetEstimate | None, teammates: Sequence[TeammateState],
                t: float) -> UnicycleSetpoint:
        """Speed / heading-rate / altitude set-point at time ``t`` (s)."""
        c = self.config
        self.stats.calls += 1
        if target is None:  # nothing to track: loiter at the nominal orbit turn rate
            return UnicycleSetpoint(speed=_clip(c.nominal_speed, c.min_speed, c.max_speed),
                                    heading_rate=_clip(c.direction * c.nominal_speed / c.standoff_radius,
                                                       -c.max_heading_rate, c.max_heading_rate),
                                    altitude=c.altitude)
        psi = own.course(c.min_course_speed)
        p = own.p_W[:2]
        pt = target.predict_xy(t)
        r = p - pt
        v_rel = self.relative_speed(r, target, teammates, t)
        v_c = self.field(r, v_rel) + target.v_W[:2]
        psi_d = float(np.arctan2(v_c[1], v_c[0]))
        # feed-forward: desired heading after a short step along the predicted own and target motion
        h = c.feedforward_dt
        speed_now = max(own.speed, c.min_course_speed)
        p_next = p + h * speed_now * np.array([np.cos(psi), np.sin(psi)])
        v_c_next = self.field(p_next - target.predict_xy(t + h), v_rel) + target.v_W[:2]
        psi_d_next = float(np.arctan2(v_c_next[1], v_c_next[0]))
        ff = float(wrap_angle(psi_d_next - psi_d)) / h
        omega = ff + c.heading_gain * float(wrap_angle(psi_d - psi))
        omega = _clip(omega, -c.max_heading_rate, c.max_heading_rate)
        speed = _clip(float(np.hypot(v_c[0], v_c[1])), c.min_speed, c.max_speed)
        return UnicycleSetpoint(speed=speed, heading_rate=omega, altitude=c.altitude)
