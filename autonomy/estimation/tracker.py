"""Single-target tracking around any filter: track initiation, χ² gating, nearest-neighbour association, coasting, loss.

The tracker is what an agent calls at its rate (:class:`autonomy.agent.TargetEstimator`). Detections arrive in
``t_meas`` order; the filter predicts to each one's own time stamp. Association is global nearest neighbour per scan
(detections sharing ``t_meas`` and ``sensor_id``): the detection with the smallest NIS inside the gate updates the
track.
A track that has seen no gated detection for ``lost_after_s`` is dropped and re-initiated from the next detection.

Initiation is two-point: each radar or box detection is inverted to a ground position fix (radar range and azimuth to a
point on the target plane) and kept as a tentative fix; a fix of a later scan that lies within
``max_target_speed · Δt`` plus a 3σ margin of a tentative one confirms a track, with the position of the newer fix and
the
velocity of the pair. A lone false alarm therefore never starts a track, and clutter pairs are rare when false alarms
are spread over the radar's whole field of regard.

In a consensus team (HCMCI, :mod:`autonomy.fusion.hcmci_team`) :meth:`SingleTargetTracker.step_information` replaces
:meth:`~SingleTargetTracker.step`: the same initiation, gating and association, but the gated detections of the scans
taken at the step time (one per sensor) are not applied: their information contributions, each made against the
track's prior at that time, are summed (``S_I = tria([S_I,1, S_I,2, …])``, ``i = i_1 + i_2 + …``) and returned with
that prior; the team's consensus result then goes back through :meth:`~SingleTargetTracker.set_information`. Scans
older than the step time are applied locally first: a contribution ``(S_I, i)`` is information about the state at the
scan's own time, and adds exactly to a prior only at that time (there is no exact way to move it to a later prior
through the process noise).

With ``stack_scans`` the detections of every sensor taken at one time form one scan (e.g. a UAV's own bearing and
the bearings its teammates shared): each sensor's best gated detection is kept, and the kept ones update the filter
once as a :class:`~autonomy.estimation.measurements.StackedMeasurement` (paper 003's centralised augmented
measurement). Bearings of two or more sensors whose lines cross at ``min_crossing_angle`` or more also fix a position
(their least-squares intersection, with the inverse of the bearings' Fisher information as its covariance), which
initiates tracks and judges divergence like a radar fix. The ``imm`` filter is paper 003's IMM of CV and CT(±ω) EKFs
(:func:`~autonomy.estimation.imm.cv_ct_imm`) on the ``cv`` layout.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import gammaincinv

from autonomy.estimation.base import TIME_TOLERANCE
from autonomy.estimation.factory import make_filter
from autonomy.estimation.imm import cv_ct_imm
from autonomy.estimation.measurements import StackedMeasurement, measurement_model
from autonomy.estimation.models import ConstantVelocity, MotionModel, Singer
from autonomy.estimation.scif import SqrtInformation, add_information
from interfaces.state import TargetEstimate

__all__ = ["SingleTargetTracker", "TrackInformation", "TrackerConfig", "make_motion_model"]


@dataclass(frozen=True)
class TrackInformation:
    """A track's share of one consensus step at time ``t`` (s).

    Attributes
    ----------
    t : float
        Step time, s; both quantities hold at it.
    prior : SqrtInformation
        The track predicted to ``t`` (after any older scans were applied locally): ``(S_h⁻, ĥ⁻)``.
    contribution : SqrtInformation | None
        Information ``(S_I, i)`` of the gated detections of the scans taken at ``t`` (one per scan, summed); None if
        there was none.
    """

    t: float
    prior: SqrtInformation
    contribution: SqrtInformation | None


@dataclass(frozen=True, kw_only=True)
class TrackerConfig:
    """Single-target tracker settings.

    Attributes
    ----------
    filter : str
        ``ekf``, ``ukf``, ``ckf``, ``scif``, or ``imm`` (CV + CT(±``imm_turn_rate``) EKFs; needs ``model="cv"``).
    model : str
        Motion model: ``cv`` (nearly constant velocity) or ``singer``.
    q : float
        CV: white-acceleration spectral density (m²/s³), > 0.
    singer_alpha : float
        Singer: manoeuvre decorrelation rate (1/s), > 0.
    singer_sigma_a : float
        Singer: acceleration standard deviation (m/s²), > 0.
    gate_probability : float
        Probability mass of the χ² validation gate, in (0, 1).
    max_target_speed : float
        Fastest plausible target (m/s), > 0: bounds the distance between two fixes that confirm a track.
    tentative_window_s : float
        How long a tentative fix waits for its confirming partner (s), > 0.
    lost_after_s : float
        Drop the track after this long without a gated detection (s), > 0.
    max_missed_scans : int
        Drop the track after this many consecutive position-fixing scans (radar, box) whose detections all fall
        outside the gate, >= 1: a track that rejects every fix it is shown has diverged (e.g. a bad two-point
        velocity, or a track started on clutter) and is re-initiated from the new fixes instead of coasting for
        ``lost_after_s``. Bearing-only scans neither count nor reset the count: a bearing fits a wrong track
        anywhere along its line.
    confirm_fixes : int
        Position fixes that confirm a track, 2 or 3: two fixes within ``max_target_speed · Δt`` (plus 3σ) of each
        other, or additionally a third fix where that pair predicts (within 3σ plus ``max_target_accel · Δt² / 2``).
        Three suppress tracks started on pairs of false alarms in clutter, at the cost of one more scan.
    max_target_accel : float
        Largest plausible target acceleration (m/s²), > 0: widens the third fix's gate.
    initial_speed_sigma : float | None
        Standard deviation (m/s) of a zero-mean prior on each velocity component, fused with the two-point velocity
        at initiation (None: the two-point velocity alone). Two fixes 0.5 s apart with 30 m range noise give a
        velocity σ near 90 m/s; a car's speed prior bounds that.
    target_height : float
        Height of the ground targets (m).
    imm_turn_rate : float
        ``imm``: turn rate ω of the two coordinated-turn modes (rad/s), > 0.
    imm_q_turn : float
        ``imm``: white-acceleration spectral density of the turn modes (m²/s³), > 0 (the CV mode uses ``q``).
    imm_p_stay : float
        ``imm``: diagonal of the mode-transition matrix, in (0, 1); the rest is spread evenly.
    stack_scans : bool
        Stack the detections of all sensors taken at one time into one update (module docstring).
    min_crossing_angle : float
        Smallest angle between two bearing lines for their intersection to fix a position (rad), in (0, π/2].
    """

    filter: str = "ekf"
    model: str = "cv"
    q: float = 1.0
    singer_alpha: float = 0.1
    singer_sigma_a: float = 1.0
    gate_probability: float = 0.999
    max_target_speed: float = 30.0
    tentative_window_s: float = 3.0
    lost_after_s: float = 10.0
    max_missed_scans: int = 4
    confirm_fixes: int = 2
    max_target_accel: float = 4.0
    initial_speed_sigma: float | None = 15.0
    target_height: float = 0.0
    imm_turn_rate: float = 0.3
    imm_q_turn: float = 0.05
    imm_p_stay: float = 0.95
    stack_scans: bool = False
    min_crossing_angle: float = float(np.deg2rad(10.0))

    def __post_init__(self) -> None:
        if self.filter not in ("ekf", "ukf", "ckf", "scif", "imm"):
            raise ValueError(f"TrackerConfig.filter must be ekf|ukf|ckf|scif|imm, got {self.filter!r}")
        if self.model not in ("cv", "singer"):
            raise ValueError(f"TrackerConfig.model must be cv|singer, got {self.model!r}")
        if self.filter == "imm" and self.model != "cv":
            raise ValueError(f"TrackerConfig.model must be cv with the imm filter (its modes share the CV layout), "
                             f"got {self.model!r}")
        for name in ("imm_turn_rate", "imm_q_turn"):
            if not getattr(self, name) > 0:
                raise ValueError(f"TrackerConfig.{name} must be > 0, got {getattr(self, name)!r}")
        if not 0 < self.imm_p_stay < 1:
            raise ValueError(f"TrackerConfig.imm_p_stay must be in (0, 1), got {self.imm_p_stay!r}")
        if not 0 < self.min_crossing_angle <= np.pi / 2:
            raise ValueError(f"TrackerConfig.min_crossing_angle must be in (0, π/2] rad, got "
                             f"{self.min_crossing_angle!r}")
        for name in ("q", "singer_alpha", "singer_sigma_a", "max_target_speed", "tentative_window_s", "lost_after_s"):
            if not getattr(self, name) > 0:
                raise ValueError(f"TrackerConfig.{name} must be > 0, got {getattr(self, name)!r}")
        if self.confirm_fixes not in (2, 3):
            raise ValueError(f"TrackerConfig.confirm_fixes must be 2 or 3, got {self.confirm_fixes!r}")
        if not self.max_target_accel > 0:
            raise ValueError(f"TrackerConfig.max_target_accel must be > 0 m/s², got {self.max_target_accel!r}")
        if int(self.max_missed_scans) != self.max_missed_scans or self.max_missed_scans < 1:
            raise ValueError(f"TrackerConfig.max_missed_scans must be an integer >= 1, got {self.max_missed_scans!r}")
        if self.initial_speed_sigma is not None and not self.initial_speed_sigma > 0:
            raise ValueError(f"TrackerConfig.initial_speed_sigma must be > 0 m/s or None, got "
                             f"{self.initial_speed_sigma!r}")
        if not 0 < self.gate_probability < 1:
            raise ValueError(f"TrackerConfig.gate_probability must be in (0, 1), got {self.gate_probability!r}")


def make_motion_model(cfg: TrackerConfig) -> MotionModel:
    """The configured 2-D motion model."""
    if cfg.model == "cv":
        return ConstantVelocity(q=cfg.q, dim=2)
    return Singer(alpha=cfg.singer_alpha, sigma_a=cfg.singer_sigma_a, dim=2)


def _fixes_position(det: object) -> bool:
    """Whether ``det`` alone fixes a ground position (what :func:`_ground_fix` inverts): a box, or a radar return."""
    return det.kind == "box" or (det.kind == "radar" and np.size(det.z) >= 2)


def _triangulate(dets: Sequence[object], min_crossing_angle: float) -> tuple[object, np.ndarray, np.ndarray] | None:
    """Least-squares intersection of the azimuth lines of the bearing / camera detections among ``dets`` (taken at
    one time): ``(stacked measurement, (x, y), 2x2 covariance)``, or None unless two lines cross at
    ``min_crossing_angle`` (rad) or more with the target ahead of every sensor. The covariance is the inverse of the
    bearings' Fisher information ``Σ n_i n_iᵀ / (σ_i² r_i²)`` at the intersection (n_i: normal of line i)."""
    bearings = [d for d in dets if d.kind in ("bearing", "camera")]
    if len(bearings) < 2:
        return None
    az = np.array([float(np.atleast_1d(d.z)[0]) for d in bearings])
    p_s = np.array([np.asarray(d.p_sensor_W, dtype=float)[:2] for d in bearings])
    n = np.c_[-np.sin(az), np.cos(az)]
    A = n.T @ n
    # two lines at angle β give λ_min(Σ n nᵀ) = 1 − |cos β|; more lines only add
    if np.linalg.eigvalsh(A)[0] < 1.0 - np.cos(min_crossing_angle):
        return None
    xy = np.linalg.solve(A, n.T @ np.sum(n * p_s, axis=1))
    ahead = np.sum((xy - p_s) * np.c_[np.cos(az), np.sin(az)], axis=1)
    if np.any(ahead <= 0):
        return None
    var = np.array([float(np.atleast_2d(d.R)[0, 0]) for d in bearings]) * np.sum((xy - p_s) ** 2, axis=1)
    F = (n / var[:, None]).T @ n
    return StackedMeasurement(parts=tuple(bearings)), xy, np.linalg.inv(F)


def _ground_fix(det: object, target_height: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(x, y) position and its 2x2 covariance from one detection, or None if it cannot fix a position alone."""
    z = np.asarray(det.z, dtype=float)
    R = np.asarray(det.R, dtype=float)
    if not _fixes_position(det):
        return None
    if det.kind == "box":
        return z[:2].copy(), R[:2, :2].copy()
    p_s = np.asarray(det.p_sensor_W, dtype=float)
    rng, az = z[0], z[1]
    dz = target_height - p_s[2]
    rho2 = rng * rng - dz * dz
    rho = np.sqrt(rho2) if rho2 > 0 else 0.0
    xy = p_s[:2] + rho * np.array([np.cos(az), np.sin(az)])
    # first-order covariance: range error along the line of sight (scaled by r/rho), azimuth error across it
    along = (rng / rho) if rho > 1e-6 else 1.0
    J = np.array([[np.cos(az) * along, -rho * np.sin(az)], [np.sin(az) * along, rho * np.cos(az)]])
    P = J @ R[:2, :2] @ J.T
    return xy, P


class SingleTargetTracker:
    """Tracks one ground target from detections of any kind the estimation layer models."""

    def __init__(self, config: TrackerConfig) -> None:
        self.config = config
        self.model = make_motion_model(config)
        self.layout = self.model.layout
        self.filter = None
        self.last_update_t = -np.inf
        self._ix = [self.layout.index("x"), self.layout.index("y")]
        self._iv = [self.layout.index("vx"), self.layout.index("vy")]
        self.gated_out = 0
        self.updates = 0
        self.initiations = 0
        self.used_by_sensor: dict[str, int] = {}  # detections that updated the track, per sensor id
        self.dropped_diverged = 0
        self._missed = 0
        self._gates: dict[int, float] = {}
        # tentative fixes (t, xy, P_xy) and, with confirm_fixes = 3, tentative pairs (t, xy, P_xy, v, P_v)
        self._tentative: list[tuple] = []

    def _initiate(self, dets: Sequence[object]) -> bool:
        """Try to confirm a track from this scan's fixes and the tentative fixes of earlier scans; keep the new
        fixes."""
        cfg = self.config
        fixes = [(d, f) for d in dets if (f := _ground_fix(d, cfg.target_height)) is not None]
        if cfg.stack_scans and (tri := _triangulate(dets, cfg.min_crossing_angle)) is not None:
            fixes.append((tri[0], tri[1:]))
        if not fixes:
            return False
        t_now = fixes[0][0].t_meas
        self._tentative = [tf for tf in self._tentative if 0 < t_now - tf[0] <= cfg.tentative_window_s]
        best, pairs = None, []
        for det, (xy, Pxy) in fixes:
            for t_old, xy_old, P_old, *vel in self._tentative:
                dt = t_now - t_old
                v, Pv = (xy - xy_old) / dt, (Pxy + P_old) / dt ** 2
                if vel:  # a pair: does this fix lie where it predicts?
                    v_old, Pv_old = vel
                    gap = float(np.linalg.norm(xy - xy_old - v_old * dt))
                    margin = (3.0 * float(np.sqrt(np.linalg.eigvalsh(Pxy + P_old + dt ** 2 * Pv_old).max()))
                              + 0.5 * cfg.max_target_accel * dt ** 2)
                    ok = gap <= margin
                else:
                    gap = float(np.linalg.norm(xy - xy_old))
                    ok = gap <= cfg.max_target_speed * dt + 3.0 * float(np.sqrt(np.linalg.eigvalsh(Pxy + P_old).max()))
                    if ok and cfg.confirm_fixes == 3:
                        pairs.append((t_now, xy, Pxy, v, Pv))
                        ok = False
                if ok and (best is None or gap < best[0]):
                    best = (gap, det, xy, Pxy, v, Pv)
        if best is None:
            self._tentative.extend((t_now, xy, Pxy) for _, (xy, Pxy) in fixes)
            self._tentative.extend(pairs)
            return False
        _, det, xy, Pxy, v, Pv = best
        if cfg.initial_speed_sigma is not None:  # fuse with the zero-mean speed prior N(0, σ² I)
            P_prior = np.eye(2) * cfg.initial_speed_sigma**2
            K = Pv @ np.linalg.inv(Pv + P_prior)
            v = v - K @ v
            Pv = Pv - K @ Pv
            Pv = 0.5 * (Pv + Pv.T)
        n = self.model.n
        x0 = np.zeros(n)
        P0 = np.zeros((n, n))
        x0[self._ix], x0[self._iv] = xy, v
        P0[np.ix_(self._ix, self._ix)] = Pxy + np.eye(2) * 1e-6
        P0[np.ix_(self._iv, self._iv)] = Pv + np.eye(2) * 1e-6
        for name in ("ax", "ay"):
            if name in self.layout:
                i = self.layout.index(name)
                P0[i, i] = 4.0
        if cfg.filter == "imm":
            self.filter = cv_ct_imm(x0, P0, det.t_meas, q_cv=cfg.q, q_ct=cfg.imm_q_turn, turn_rate=cfg.imm_turn_rate,
                                    p_stay=cfg.imm_p_stay, target_height=cfg.target_height)
        else:
            self.filter = make_filter(cfg.filter, self.model, x0, P0, det.t_meas, target_height=cfg.target_height)
        self.last_update_t = det.t_meas
        self._tentative = []
        self.initiations += 1
        self._missed = 0
        return True

    def _gate(self, dof: int) -> float:
        if dof not in self._gates:
            self._gates[dof] = float(2.0 * gammaincinv(dof / 2.0, self.config.gate_probability))  # χ² quantile
        return self._gates[dof]

    def _nis(self, det: object) -> float:
        """NIS of ``det`` against the track predicted to its time (EKF linearisation; does not change the track)."""
        f = self.filter
        F = self.model.jacobian(f.x, det.t_meas - f.t)
        x = self.model.propagate(f.x, det.t_meas - f.t)
        P = F @ f.P @ F.T + self.model.process_noise(det.t_meas - f.t, f.x)
        h = measurement_model(det, self.layout, self.config.target_height)
        H = h.jacobian(x)
        nu = h.residual(np.asarray(det.z, dtype=float), h.h(x))
        S = H @ P @ H.T + np.asarray(det.R, dtype=float)
        return float(nu @ np.linalg.solve(S, nu))

    def step(self, t: float, detections: Sequence[object]) -> TargetEstimate | None:
        """Absorb ``detections`` (sorted by ``t_meas``) and return the estimate at ``t`` (s), or None without a
        track."""
        self._absorb(detections, defer_at=None)
        return self.estimate(t)

    def step_information(self, t: float, detections: Sequence[object]) -> TrackInformation | None:
        """Like :meth:`step`, but the gated detections of the scans taken at ``t`` (s) are not applied: the sum of
        their information contributions is returned beside the track's prior at ``t`` (module docstring). Older scans
        are applied locally first.

        Apply the fused result with :meth:`set_information`, then read it with :meth:`current_estimate`. Needs an
        information filter (``scif``). Returns None without a track (also when the track was dropped as lost).
        """
        if self.config.filter != "scif":
            raise TypeError(f"step_information needs the information filter (scif), not {self.config.filter!r}")
        contribution = self._absorb(detections, defer_at=t)
        if not self._still_tracked(t):
            return None
        if contribution is None and t > self.filter.t:
            self.filter.predict(t)
        return TrackInformation(t=float(t), prior=self.filter.information_state, contribution=contribution)

    def set_information(self, info: SqrtInformation) -> None:
        """Replace the track's estimate by ``info`` (e.g. the consensus posterior at the time of the last
        :meth:`step_information`)."""
        if self.filter is None:
            raise ValueError("set_information needs a track")
        self.filter.set_information(info)

    def _absorb(self, detections: Sequence[object], defer_at: float | None) -> SqrtInformation | None:
        """Initiate, gate and update from ``detections``; with ``defer_at`` (s), the gated detections of the scans
        taken at ``defer_at`` give their summed information contribution (returned) instead of updates."""
        scans: dict[tuple[float, str], list] = {}
        stack = self.config.stack_scans
        for d in detections:
            scans.setdefault((d.t_meas, "" if stack else d.sensor_id), []).append(d)
        ordered = sorted(scans.items(), key=lambda kv: kv[0][0])
        deferred: list[SqrtInformation] = []  # contributions against the current filter's prior at defer_at
        for (t_meas, _), dets in ordered:
            if self.filter is not None and t_meas - self.last_update_t > self.config.lost_after_s:
                self.filter = None
            if self.filter is None:
                deferred = []  # made against a track that is gone
                self._initiate(dets)
                continue
            if t_meas < self.filter.t:
                continue  # out of sequence: older than the track
            chosen, gated_out = self._associate(dets)
            self.gated_out += gated_out
            if not chosen:
                # only scans that fix a position (radar, box, crossing bearings) judge divergence: a single bearing
                # fits any range on its line
                self._missed += self._fixing(dets)
                if self._missed >= self.config.max_missed_scans:  # diverged: start again from these fixes
                    self.filter = None
                    deferred = []
                    self.dropped_diverged += 1
                    self._tentative = []
                    self._initiate(dets)
                continue
            best = chosen[0] if len(chosen) == 1 else StackedMeasurement(parts=tuple(chosen))
            if defer_at is not None and abs(t_meas - defer_at) <= TIME_TOLERANCE:
                deferred.append(self.filter.information(best)[0])
            else:
                self.filter.update(best)
            if self._fixing(chosen):
                self._missed = 0
            self.updates += 1
            for d in chosen:
                self.used_by_sensor[d.sensor_id] = self.used_by_sensor.get(d.sensor_id, 0) + 1
            self.last_update_t = t_meas
        if not deferred:
            return None
        if len(deferred) == 1:
            return deferred[0]
        return add_information(*deferred)

    def _associate(self, dets: Sequence[object]) -> tuple[list, int]:
        """Each sensor's detection of the smallest NIS inside the gate (global nearest neighbour per sensor), in the
        order of ``dets``, and the number of detections of the sensors that had none inside."""
        by_sensor: dict[str, list] = {}
        for d in dets:
            by_sensor.setdefault(d.sensor_id, []).append(d)
        chosen, gated_out = [], 0
        for group in by_sensor.values():
            best, best_nis = None, np.inf
            for d in group:
                nis = self._nis(d)
                if nis <= self._gate(np.size(d.z)) and nis < best_nis:
                    best, best_nis = d, nis
            if best is None:
                gated_out += len(group)
            else:
                chosen.append(best)
        return chosen, gated_out

    def _fixing(self, dets: Sequence[object]) -> bool:
        """Whether ``dets`` (one scan) fix a position: a radar or box detection, or (stacking) crossing bearings."""
        return any(_fixes_position(d) for d in dets) or (
            self.config.stack_scans and _triangulate(dets, self.config.min_crossing_angle) is not None)

    def estimate(self, t: float) -> TargetEstimate | None:
        """The track's estimate predicted to ``t`` (s), or None without a track (dropping it if lost by ``t``)."""
        if not self._still_tracked(t):
            return None
        if t > self.filter.t:
            self.filter.predict(t)
        return self.current_estimate()

    def _still_tracked(self, t: float) -> bool:
        """Whether a track remains at ``t`` (s): one that has gone ``lost_after_s`` without an update is dropped."""
        if self.filter is not None and t - self.last_update_t > self.config.lost_after_s:
            self.filter = None
        return self.filter is not None

    def current_estimate(self) -> TargetEstimate | None:
        """The track's estimate at its filter's own time, without the loss check or prediction of :meth:`estimate`
        (e.g. right after :meth:`step_information`, which made both, and :meth:`set_information`); None without a
        track."""
        if self.filter is None:
            return None
        x, P = self.filter.x, self.filter.P
        idx = self._ix + self._iv
        return TargetEstimate(t=self.filter.t, p_W=x[self._ix], v_W=x[self._iv], P=P[np.ix_(idx, idx)])
