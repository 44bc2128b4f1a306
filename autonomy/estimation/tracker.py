"""Single-target tracking around any filter: the composed tracker of :mod:`autonomy.estimation.tracking`, configured.

:class:`SingleTargetTracker` is what an agent calls at its rate (:class:`autonomy.agent.TargetEstimator`): a
:class:`~autonomy.estimation.tracking.tracker.Tracker` whose parts are built from one :class:`TrackerConfig`:

- initiation: :class:`~autonomy.estimation.tracking.initiator.FixConfirmingInitiator` (two- or three-point logic on
  position fixes: radar returns inverted to the target plane, boxes and, with ``stack_scans``, crossing bearings);
- gating and association: a :class:`~autonomy.estimation.tracking.gate.ChiSquareGate` of ``gate_probability`` on the
  :class:`~autonomy.estimation.tracking.gate.PredictedNis`, and the
  :class:`~autonomy.estimation.tracking.associator.NearestNeighbourAssociator` (per scan, each sensor's detection of
  the smallest NIS inside the gate);
- deletion: after ``lost_after_s`` without a gated detection
  (:class:`~autonomy.estimation.tracking.deleter.UpdateTimeDeleter`), or after ``max_missed_scans`` position-fixing
  scans in a row that miss the track (:class:`~autonomy.estimation.tracking.deleter.MissedScansDeleter`); either way
  the next detections re-initiate a track;
- the filter: ``ekf``, ``ukf``, ``ckf``, ``scif`` on the ``cv`` or ``singer`` model, or ``imm``: paper 003's IMM of CV
  and CT(±ω) EKFs (:func:`~autonomy.estimation.imm.cv_ct_imm`) on the ``cv`` layout (``imm_modes="cv_ct"``), or a
  car that moves and stops, EKFs on the ``cv`` or ``singer`` model and on a stopped car
  (:func:`~autonomy.estimation.imm.move_stop_imm`, ``imm_modes="move_stop"``) (:class:`ConfiguredFilters`).

In a consensus team (HCMCI, :mod:`autonomy.fusion.hcmci_team`) :meth:`SingleTargetTracker.step_information` replaces
:meth:`~SingleTargetTracker.step` (:mod:`autonomy.estimation.tracking.information`); the team's consensus result goes
back through :meth:`~SingleTargetTracker.set_information`.

With ``stack_scans`` the detections of every sensor taken at one time form one scan (e.g. a UAV's own bearing and
the bearings its teammates shared): each sensor's best gated detection is kept, and the kept ones update the filter
once as a :class:`~autonomy.estimation.measurements.StackedMeasurement` (paper 003's centralised augmented
measurement).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from autonomy.estimation.base import Filter
from autonomy.estimation.factory import make_filter
from autonomy.estimation.imm import cv_ct_imm, move_stop_imm
from autonomy.estimation.measurements import MeasurementLike
from autonomy.estimation.models import ConstantVelocity, MotionModel, Singer
from autonomy.estimation.tracking.associator import NearestNeighbourAssociator
from autonomy.estimation.tracking.deleter import MissedScansDeleter, UpdateTimeDeleter
from autonomy.estimation.tracking.fixes import PositionFixer
from autonomy.estimation.tracking.gate import ChiSquareGate, PredictedNis
from autonomy.estimation.tracking.information import TrackInformation
from autonomy.estimation.tracking.initiator import FilterFactory, FixConfirmingInitiator
from autonomy.estimation.tracking.tracker import Tracker

__all__ = ["ConfiguredFilters", "SingleTargetTracker", "TrackInformation", "TrackerConfig", "make_motion_model"]


@dataclass(frozen=True, kw_only=True)
class TrackerConfig:
    """Single-target tracker settings (each part's, see the module docstring).

    Attributes
    ----------
    filter : str
        ``ekf``, ``ukf``, ``ckf``, ``scif``, or ``imm`` (the modes ``imm_modes`` names).
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
    imm_modes : str
        ``imm``: ``cv_ct`` (paper 003: CV + CT(±``imm_turn_rate``) EKFs; needs ``model="cv"``) or ``move_stop`` (EKFs
        on ``model`` and on a stopped car, :func:`~autonomy.estimation.imm.move_stop_imm`).
    imm_turn_rate : float
        ``imm``: turn rate ω of the two coordinated-turn modes (rad/s), > 0.
    imm_q_turn : float
        ``imm``: white-acceleration spectral density of the turn modes (m²/s³), > 0 (the CV mode uses ``q``).
    imm_p_stay : float
        ``imm`` ``cv_ct``: diagonal of the mode-transition matrix, in (0, 1); the rest is spread evenly.
    imm_mean_moving_s, imm_mean_stopped_s : float
        ``imm`` ``move_stop``: mean time a car drives before it stops, and stays stopped (s), > 0
        (:class:`~autonomy.estimation.imm.MoveStopSwitching`).
    imm_stopped_q : float
        ``imm`` ``move_stop``: position random-walk density of a stopped car (m²/s), >= 0.
    stack_scans : bool
        Stack the detections of all sensors taken at one time into one update (module docstring).
    min_crossing_angle : float
        Smallest angle between two bearing lines for their intersection to fix a position (rad), in (0, π/2].
    ekf_iterations : int
        ``ekf`` (and the EKFs of the ``move_stop`` imm): linearisations per update, >= 1 (1: the plain EKF; more: the
        iterated EKF, :class:`~.ekf.EKF`).
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
    imm_modes: str = "cv_ct"
    imm_mean_moving_s: float = 30.0
    imm_mean_stopped_s: float = 10.0
    imm_stopped_q: float = 0.01
    stack_scans: bool = False
    min_crossing_angle: float = float(np.deg2rad(10.0))
    ekf_iterations: int = 1

    def __post_init__(self) -> None:
        if self.filter not in ("ekf", "ukf", "ckf", "scif", "imm"):
            raise ValueError(f"TrackerConfig.filter must be ekf|ukf|ckf|scif|imm, got {self.filter!r}")
        if self.model not in ("cv", "singer"):
            raise ValueError(f"TrackerConfig.model must be cv|singer, got {self.model!r}")
        if self.imm_modes not in ("cv_ct", "move_stop"):
            raise ValueError(f"TrackerConfig.imm_modes must be cv_ct|move_stop, got {self.imm_modes!r}")
        if self.filter == "imm" and self.imm_modes == "cv_ct" and self.model != "cv":
            raise ValueError(f"TrackerConfig.model must be cv with the cv_ct imm (its modes share the CV layout), "
                             f"got {self.model!r}")
        for name in ("imm_mean_moving_s", "imm_mean_stopped_s"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ValueError(f"TrackerConfig.{name} must be finite and > 0 s, got {getattr(self, name)!r}")
        if not (np.isfinite(self.imm_stopped_q) and self.imm_stopped_q >= 0):
            raise ValueError(f"TrackerConfig.imm_stopped_q must be finite and >= 0 m²/s, got {self.imm_stopped_q!r}")
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
        if int(self.ekf_iterations) != self.ekf_iterations or self.ekf_iterations < 1:
            raise ValueError(f"TrackerConfig.ekf_iterations must be an integer >= 1, got {self.ekf_iterations!r}")
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


class ConfiguredFilters:
    """The filter a new track runs, as :class:`TrackerConfig` names it: ``filter`` on ``model``, or the ``imm``."""

    def __init__(self, config: TrackerConfig, model: MotionModel) -> None:
        self.config = config
        self.model = model

    def __call__(self, x0: np.ndarray, P0: np.ndarray, t0: float) -> Filter:
        """The filter started from ``(x0, P0)`` at ``t0`` (s)."""
        cfg = self.config
        iterations = {"iterations": cfg.ekf_iterations} if cfg.ekf_iterations > 1 else {}
        if cfg.filter == "imm" and cfg.imm_modes == "move_stop":
            return move_stop_imm(x0, P0, t0, moving=self.model, mean_moving_s=cfg.imm_mean_moving_s,
                                 mean_stopped_s=cfg.imm_mean_stopped_s, stopped_q=cfg.imm_stopped_q,
                                 target_height=cfg.target_height, **iterations)
        if cfg.filter == "imm":
            return cv_ct_imm(x0, P0, t0, q_cv=cfg.q, q_ct=cfg.imm_q_turn, turn_rate=cfg.imm_turn_rate,
                             p_stay=cfg.imm_p_stay, target_height=cfg.target_height)
        return make_filter(cfg.filter, self.model, x0, P0, t0, target_height=cfg.target_height,
                           **(iterations if cfg.filter == "ekf" else {}))


class SingleTargetTracker(Tracker):
    """Tracks one ground target from detections of any model the estimation layer knows (module docstring).

    Parameters
    ----------
    config : TrackerConfig
        Settings of every part.
    model : MotionModel, optional
        The motion model (default: :func:`make_motion_model` of ``config``).
    filters : FilterFactory, optional
        Builds a new track's filter from ``(x0, P0, t0)`` (default: :class:`ConfiguredFilters` on ``model``).
    gating_filter : callable, optional
        The filter gated against, given a track's filter (default: that filter; :class:`~.gate.PredictedNis`).
    """

    def __init__(self, config: TrackerConfig, *, model: MotionModel | None = None, filters: FilterFactory | None = None,
                 gating_filter: Callable[[Filter], Filter] | None = None) -> None:
        self.config = config
        self.model = make_motion_model(config) if model is None else model
        fixer = PositionFixer(config.target_height, config.min_crossing_angle if config.stack_scans else None)
        initiator = FixConfirmingInitiator(
            fixer=fixer, filters=ConfiguredFilters(config, self.model) if filters is None else filters,
            layout=self.model.layout, max_target_speed=config.max_target_speed,
            tentative_window_s=config.tentative_window_s, confirm_fixes=config.confirm_fixes,
            max_target_accel=config.max_target_accel, initial_speed_sigma=config.initial_speed_sigma)
        associator = NearestNeighbourAssociator(ChiSquareGate(config.gate_probability),
                                                PredictedNis(self.model, config.target_height, gating_filter))
        super().__init__(layout=self.model.layout, initiator=initiator, associator=associator,
                         coasting=UpdateTimeDeleter(config.lost_after_s),
                         divergence=MissedScansDeleter(config.max_missed_scans), fixer=fixer,
                         stack_scans=config.stack_scans)

    def step_information(self, t: float, detections: Sequence[MeasurementLike]) -> TrackInformation | None:
        """:meth:`Tracker.step_information <autonomy.estimation.tracking.tracker.Tracker.step_information>`; needs
        the information filter (``scif``)."""
        if self.config.filter != "scif":
            raise TypeError(f"step_information needs the information filter (scif), not {self.config.filter!r}")
        return super().step_information(t, detections)
