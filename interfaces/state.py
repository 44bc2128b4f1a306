"""Typed states shared by estimation, fusion, guidance and the simulator: a UAV's own state, a target estimate, what
a teammate shares.

Frames: world ENU, metres, seconds, radians. Positions may be given in 2-D (x, y) where only the horizontal
plane matters; guidance laws use the horizontal components and say so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from interfaces._checks import all_finite, finite_number, finite_vector

__all__ = ["OwnState", "TargetEstimate", "TeammateState", "TrackPicture", "TrackReport"]


@dataclass(frozen=True, kw_only=True)
class OwnState:
    """The UAV's own (estimated) state.

    Attributes
    ----------
    t : float
        Time of the state (s).
    p_W : np.ndarray
        (3,) position in the world frame (m).
    v_W : np.ndarray
        (3,) velocity in the world frame (m/s).
    yaw : float
        Body yaw (rad), counter-clockwise from +x. Used as the heading when the horizontal speed is too small
        to define a course.
    """

    t: float
    p_W: np.ndarray
    v_W: np.ndarray
    yaw: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "t", finite_number("OwnState", "t", self.t))
        object.__setattr__(self, "p_W", finite_vector("OwnState", "p_W", self.p_W, (3,)))
        object.__setattr__(self, "v_W", finite_vector("OwnState", "v_W", self.v_W, (3,)))
        object.__setattr__(self, "yaw", finite_number("OwnState", "yaw", self.yaw))

    def course(self, min_speed: float) -> float:
        """Course angle atan2(v_y, v_x) (rad), or ``yaw`` when the horizontal speed is below ``min_speed`` (m/s)."""
        vx, vy = float(self.v_W[0]), float(self.v_W[1])
        if np.hypot(vx, vy) < min_speed:
            return self.yaw
        return float(np.arctan2(vy, vx))

    @property
    def speed(self) -> float:
        """Horizontal ground speed (m/s)."""
        return float(np.hypot(self.v_W[0], self.v_W[1]))


@dataclass(frozen=True, kw_only=True)
class TargetEstimate:
    """A (fused) estimate of the ground target.

    Attributes
    ----------
    t : float
        Time of validity of the estimate (s); guidance predicts from here.
    p_W : np.ndarray
        (2,) or (3,) position in the world frame (m).
    v_W : np.ndarray
        Velocity of the same length as ``p_W`` (m/s).
    P : np.ndarray | None
        Optional covariance of (p_W, v_W) stacked, (2n, 2n) with n = len(p_W) (m², m²/s, m²/s²).
    """

    t: float
    p_W: np.ndarray
    v_W: np.ndarray
    P: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "t", finite_number("TargetEstimate", "t", self.t))
        p = finite_vector("TargetEstimate", "p_W", self.p_W, (2, 3))
        v = finite_vector("TargetEstimate", "v_W", self.v_W, (p.shape[0],))
        object.__setattr__(self, "p_W", p)
        object.__setattr__(self, "v_W", v)
        if self.P is not None:
            P = np.array(self.P, dtype=float)
            n = 2 * p.shape[0]
            if P.shape != (n, n) or not all_finite(P):
                raise ValueError(f"TargetEstimate.P must be a finite ({n}, {n}) array, got shape {P.shape}")
            P.setflags(write=False)
            object.__setattr__(self, "P", P)

    @classmethod
    def of_arrays(cls, t: float, p_W: np.ndarray, v_W: np.ndarray, P: np.ndarray | None) -> TargetEstimate:
        """The estimate made of float64 arrays the caller hands over (made read-only, not copied: pass fresh ones),
        checked as the constructor checks them (anything else goes through the constructor, with its errors). A
        fraction of the constructor's cost, which converts and copies whatever it is given: for a tracker reporting
        hundreds of tracks at every step."""
        n = p_W.shape[0] if p_W.ndim == 1 else 0
        plain = (isinstance(t, float) and math.isfinite(t) and n in (2, 3) and p_W.dtype == np.float64
                 and v_W.dtype == np.float64 and v_W.shape == (n,) and all_finite(p_W) and all_finite(v_W)
                 and (P is None or (P.dtype == np.float64 and P.shape == (2 * n, 2 * n) and all_finite(P))))
        if not plain:
            return cls(t=t, p_W=p_W, v_W=v_W, P=P)
        est = object.__new__(cls)
        for name, value in (("t", float(t)), ("p_W", p_W), ("v_W", v_W), ("P", P)):
            if isinstance(value, np.ndarray):
                value.setflags(write=False)
            object.__setattr__(est, name, value)
        return est

    @classmethod
    def rows_of(cls, t: list[float], p_W: np.ndarray, v_W: np.ndarray, P: np.ndarray) -> list[TargetEstimate]:
        """One estimate per row of float64 arrays the caller hands over: ``t`` (N,) times, ``p_W`` and ``v_W``
        (N, n), ``P`` (N, 2n, 2n); each estimate holds read-only views of its rows (the arrays are made read-only,
        not copied: pass fresh ones). The same estimates as :meth:`of_arrays` of each row, the arrays checked once
        for all rows (a tracker reporting hundreds of tracks at every step); anything that check does not pass goes
        through :meth:`of_arrays` row by row, with its errors."""
        m = len(t)
        plain = (p_W.ndim == 2 and p_W.shape[0] == m and p_W.shape[1] in (2, 3) and v_W.shape == p_W.shape
                 and P.shape == (m, 2 * p_W.shape[1], 2 * p_W.shape[1]) and p_W.dtype == np.float64
                 and v_W.dtype == np.float64 and P.dtype == np.float64
                 and all(isinstance(x, float) and math.isfinite(x) for x in t)
                 and bool(np.isfinite(p_W).all()) and bool(np.isfinite(v_W).all()) and bool(np.isfinite(P).all()))
        if not plain:
            return [cls.of_arrays(t[k], p_W[k], v_W[k], P[k]) for k in range(m)]
        for arr in (p_W, v_W, P):
            arr.setflags(write=False)  # and so every row view of it
        out = []
        setattr_, new = object.__setattr__, object.__new__
        for k in range(m):
            est = new(cls)
            setattr_(est, "t", float(t[k]))
            setattr_(est, "p_W", p_W[k])
            setattr_(est, "v_W", v_W[k])
            setattr_(est, "P", P[k])
            out.append(est)
        return out

    def predict_xy(self, t: np.ndarray | float) -> np.ndarray:
        """Constant-velocity prediction of the horizontal position, p(t) = p + v (t − t_est) (m); shape (..., 2)."""
        dt = np.asarray(t, dtype=float) - self.t
        return self.p_W[:2] + np.multiply.outer(dt, self.v_W[:2])


@dataclass(frozen=True, kw_only=True)
class TrackReport:
    """One track of a UAV's multi-target tracker, as it is recorded and shared with the team.

    Attributes
    ----------
    track_id : int
        The tracker's id of the track (unique within one UAV's tracker for the whole run, >= 0).
    estimate : TargetEstimate
        The track's estimate (position, velocity, covariance).
    target_probability : float
        Probability that this track is the designated target, in [0, 1] (the tracker's identity belief).
    evidence : float
        Log-likelihood ratio ``log p(classes | target) − log p(classes | background car)`` of the class measurements
        of the UAV's own sensors that updated this track (0 without any): what a teammate may add to its own belief
        without counting anything twice.
    confirmed : bool
        Whether the track passed its confirmation logic (tentative tracks are recorded but not shared).
    """

    track_id: int
    estimate: TargetEstimate
    target_probability: float
    evidence: float = 0.0
    confirmed: bool = True

    def __post_init__(self) -> None:
        if int(self.track_id) != self.track_id or self.track_id < 0:
            raise ValueError(f"TrackReport.track_id must be a non-negative integer, got {self.track_id}")
        p = finite_number("TrackReport", "target_probability", self.target_probability)
        if not 0.0 <= p <= 1.0:
            raise ValueError(f"TrackReport.target_probability must be in [0, 1], got {p}")
        object.__setattr__(self, "target_probability", p)
        object.__setattr__(self, "evidence", finite_number("TrackReport", "evidence", self.evidence))


@dataclass(frozen=True, kw_only=True)
class TrackPicture:
    """What a UAV with a multi-target tracker shares: its confirmed tracks and which it takes for the target.

    Attributes
    ----------
    t : float
        When it was sent (s); each track's estimate holds at its own ``estimate.t``.
    tracks : tuple[TrackReport, ...]
        The confirmed tracks.
    target_track_id : int | None
        The track the sender takes for the target, or None.
    """

    t: float
    tracks: tuple[TrackReport, ...]
    target_track_id: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "t", finite_number("TrackPicture", "t", self.t))
        object.__setattr__(self, "tracks", tuple(self.tracks))


@dataclass(frozen=True, kw_only=True)
class TeammateState:
    """What a teammate shares: its state and, optionally, its planned path.

    Attributes
    ----------
    id : int
        Team index of the teammate, 0 ≤ id < team size.
    t : float
        Time of the shared state (s).
    p_W : np.ndarray
        (3,) position (m).
    v_W : np.ndarray
        (3,) velocity (m/s).
    yaw : float
        Yaw (rad).
    phase_slot : int | None
        Slot of the teammate on the tracking orbit (desired phase = slot · Δφ); ``None`` means ``id``.
    plan_p_W : np.ndarray | None
        (K, 2) or (K, 3) planned positions at times ``t + plan_dt · (k + 1)``, k = 0..K−1 (m); ``None`` when the
        teammate shares no plan (constant-velocity extrapolation is used instead).
    plan_dt : float
        Step of ``plan_p_W`` (s), > 0.
    """

    id: int
    t: float
    p_W: np.ndarray
    v_W: np.ndarray
    yaw: float = 0.0
    phase_slot: int | None = None
    plan_p_W: np.ndarray | None = None
    plan_dt: float = 1.0

    def __post_init__(self) -> None:
        if int(self.id) != self.id or self.id < 0:
            raise ValueError(f"TeammateState.id must be a non-negative integer, got {self.id}")
        object.__setattr__(self, "t", finite_number("TeammateState", "t", self.t))
        object.__setattr__(self, "p_W", finite_vector("TeammateState", "p_W", self.p_W, (3,)))
        object.__setattr__(self, "v_W", finite_vector("TeammateState", "v_W", self.v_W, (3,)))
        object.__setattr__(self, "yaw", finite_number("TeammateState", "yaw", self.yaw))
        if not (self.plan_dt > 0):
            raise ValueError(f"TeammateState.plan_dt must be > 0 s, got {self.plan_dt}")
        if self.plan_p_W is not None:
            plan = np.array(self.plan_p_W, dtype=float)
            if plan.ndim != 2 or plan.shape[1] not in (2, 3) or plan.shape[0] < 1 or not np.all(np.isfinite(plan)):
                raise ValueError(f"TeammateState.plan_p_W must be a finite (K, 2|3) array, got shape {plan.shape}")
            plan.setflags(write=False)
            object.__setattr__(self, "plan_p_W", plan)

    @property
    def slot(self) -> int:
        """Phase slot on the orbit (``phase_slot`` or ``id``)."""
        return int(self.id if self.phase_slot is None else self.phase_slot)

    def predict_xy(self, t: np.ndarray) -> np.ndarray:
        """Horizontal positions at times ``t`` (s), shape (len(t), 2) (m).

        Linear interpolation of the shared plan (anchored at the current position at ``self.t``); beyond the plan,
        or without one, constant-velocity extrapolation from the last known point.
        """
        t = np.asarray(t, dtype=float).reshape(-1)
        if self.plan_p_W is None:
            return self.p_W[:2] + np.outer(t - self.t, self.v_W[:2])
        pts = np.vstack([self.p_W[:2], self.plan_p_W[:, :2]])  # point j at t + j·plan_dt
        s = (t - self.t) / self.plan_dt
        j = np.clip(np.floor(s), 0, pts.shape[0] - 2).astype(np.intp)  # the last segment also extrapolates
        out = pts[j] + (s - j)[:, None] * (pts[j + 1] - pts[j])
        early = s < 0
        if early.any():
            out[early] = pts[0] + np.outer(t[early] - self.t, self.v_W[:2])
        return out
