"""What a Gymnasium or PettingZoo tracking environment is built from: the world, who learns, what the learner sees and
does, and how it is rewarded."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from worlds.loader import LoadedWorld

__all__ = ["ACTION_KINDS", "EnvConfig", "RewardConfig"]

ACTION_KINDS = ("unicycle", "velocity")
"""The set-points a learner may hand its UAV (:mod:`interfaces.setpoints`): ``unicycle`` is (speed m/s, heading rate
rad/s, altitude m), ``velocity`` the world-frame velocity (vx, vy, vz) m/s with the body facing the velocity."""


@dataclass(frozen=True, kw_only=True)
class RewardConfig:
    """The default reward of one learner step (it may use truth; the observation never does)::

        r = - w_standoff · min(|d - R| / R, 1) - w_error · min(e / e_scale, 1)
            - collision_penalty · [collided] - lost_penalty · [lost]

    ``d`` the horizontal distance from the UAV to the true target, ``R`` the standoff radius, ``e`` the horizontal
    error of the learner's target estimate (``e = e_scale`` without one). A step costs between 0 and
    ``w_standoff + w_error`` while the episode runs; the penalties come once, on the step that ends it.

    Attributes
    ----------
    w_standoff : float
        Weight of the normalised standoff error (1/1), >= 0.
    w_error : float
        Weight of the normalised estimation error (1/1), >= 0.
    error_scale_m : float
        Estimation error that costs the whole ``w_error`` (m), > 0.
    standoff_m : float | None
        Standoff radius R (m), > 0; None takes the learner's ``autonomy.guidance.standoff_m`` from the world file.
    collision_penalty : float
        Charged once when the learner's UAV touches anything (ground, building, vehicle, UAV), >= 0.
    lost_penalty : float
        Charged once when the track is lost (:class:`EnvConfig` ``lost_after_s``), >= 0.
    """

    w_standoff: float = 1.0
    w_error: float = 1.0
    error_scale_m: float = 50.0
    standoff_m: float | None = None
    collision_penalty: float = 100.0
    lost_penalty: float = 50.0

    def __post_init__(self) -> None:
        for name in ("w_standoff", "w_error", "collision_penalty", "lost_penalty"):
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"RewardConfig.{name} must be >= 0, got {getattr(self, name)!r}")
        if not self.error_scale_m > 0.0:
            raise ValueError(f"RewardConfig.error_scale_m must be > 0 m, got {self.error_scale_m!r}")
        if self.standoff_m is not None and not self.standoff_m > 0.0:
            raise ValueError(f"RewardConfig.standoff_m must be > 0 m or None, got {self.standoff_m!r}")


@dataclass(frozen=True, kw_only=True)
class EnvConfig:
    """A tracking environment.

    Attributes
    ----------
    world : str | Path | LoadedWorld
        A shipped world's name, a world file, or a loaded world.
    overrides : tuple of str
        ``key.path=value`` strings applied when loading (as ``skytrack run --set``).
    duration : float | None
        Episode length in simulated seconds (s), > 0; None = the world's ``sim.duration_s``. Reaching it truncates.
    uav : str | None
        Id of the learning UAV (Gymnasium environment); None = the world's first UAV. The others fly their world-file
        autonomy.
    action : {"unicycle", "velocity"}
        The set-point the action is (:data:`ACTION_KINDS`).
    altitude_range_m : (float, float)
        Lowest and highest altitude a unicycle action may command (m).
    image : (int, int) | None
        (height, width) px of the onboard camera image added to the observation (gimbal on the learner's target
        estimate); None = no image.
    lost_radius_m : float
        The track is held while the learner's estimate lies within this horizontal distance of the true target (m).
    lost_after_s : float
        The episode terminates as lost once the track has not been held for this long without a break (s), the
        start of the episode included.
    render_size : (int, int)
        (height, width) px of ``render()`` frames.
    render_camera : {"chase", "topdown"}
        The view of ``render()``: behind the learner looking at the target, or the whole area from above.
    """

    world: str | Path | LoadedWorld = "road_standoff"
    overrides: tuple[str, ...] = ()
    duration: float | None = None
    uav: str | None = None
    action: Literal["unicycle", "velocity"] = "unicycle"
    altitude_range_m: tuple[float, float] = (10.0, 150.0)
    image: tuple[int, int] | None = None
    reward: RewardConfig = field(default_factory=RewardConfig)
    lost_radius_m: float = 50.0
    lost_after_s: float = 15.0
    render_size: tuple[int, int] = (240, 320)
    render_camera: Literal["chase", "topdown"] = "chase"

    def __post_init__(self) -> None:
        object.__setattr__(self, "overrides", tuple(self.overrides))
        if self.duration is not None and not self.duration > 0.0:
            raise ValueError(f"EnvConfig.duration must be > 0 s or None, got {self.duration!r}")
        if self.action not in ACTION_KINDS:
            raise ValueError(f"EnvConfig.action must be one of {ACTION_KINDS}, got {self.action!r}")
        lo, hi = self.altitude_range_m
        if not 0.0 < lo < hi:
            raise ValueError(f"EnvConfig.altitude_range_m must be (low, high) with 0 < low < high m, got "
                             f"{self.altitude_range_m!r}")
        for name in ("image", "render_size"):
            size = getattr(self, name)
            if size is not None and (len(size) != 2 or min(size) < 1 or any(int(s) != s for s in size)):
                raise ValueError(f"EnvConfig.{name} must be (height, width) in whole pixels >= 1, got {size!r}")
        if not self.lost_radius_m > 0.0:
            raise ValueError(f"EnvConfig.lost_radius_m must be > 0 m, got {self.lost_radius_m!r}")
        if not self.lost_after_s > 0.0:
            raise ValueError(f"EnvConfig.lost_after_s must be > 0 s, got {self.lost_after_s!r}")
        if self.render_camera not in ("chase", "topdown"):
            raise ValueError(f"EnvConfig.render_camera must be 'chase' or 'topdown', got {self.render_camera!r}")
