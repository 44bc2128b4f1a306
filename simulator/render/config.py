"""Settings of a replay video: size, rate, camera, renderer, overlays, encoding."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

__all__ = ["CAMERAS", "RenderConfig"]

CAMERAS = ("chase", "orbit", "topdown", "onboard", "split")


@dataclass(frozen=True, kw_only=True)
class RenderConfig:
    """How to replay a run directory as a video.

    Attributes
    ----------
    out : Path | None
        Output file (``.mp4``); None writes ``video.mp4`` in the run directory.
    width, height : int
        Frame size, pixels (even numbers: H.264 with yuv420p needs them).
    fps : int
        Video frame rate, Hz. Frames are rendered at this rate, not at the physics rate.
    camera : {"chase", "orbit", "topdown", "onboard", "split"}
        ``split`` puts a chase view (left) beside a top-down map (right).
    uav : int
        Index of the UAV the chase and onboard cameras ride with.
    target : int | None
        Index of the vehicle the cameras look at; None takes the run's target (``target_index`` in ``metrics.json``,
        else 0).
    t_start : float
        First frame's time, s (clamped to the record).
    t_end : float | None
        Last frame's time, s; None renders to the end of the record.
    renderer : {"auto", "egl", "tiny"}
        ``auto`` times one frame with each usable renderer and keeps the faster.
    render_scale : float
        The 3D scene is rendered at this fraction of the frame size and scaled up (overlays are drawn at full size),
        in (0, 1].
    overlays : bool
        Draw truth, estimates, covariance ellipses, trails, detections, standoff circles and the HUD.
    legend : bool
        Explain the overlay marks in a line of text at the bottom (with ``overlays``).
    trail_s : float
        Length of UAV trails, s.
    uav_scale : float
        The UAV bodies are drawn this many times their real size (a 0.5 m quadrotor is a few pixels at 100 m), > 0.
    car_size : tuple[float, float, float] | None
        Car body length, width, height, m; None takes each vehicle's parameter file (``vehicles/cars``).
    vfov : float
        Vertical field of view of the orbit and onboard cameras, rad.
    chase_vfov : float
        Vertical field of view of the chase camera, rad (narrower: it looks past the UAV at a distant car).
    smoothing_s : float
        Time constant of the critically damped camera motion, s (0: cameras jump to their goal).
    chase_back_m, chase_up_m : float
        Chase eye: this far behind the UAV (away from the target) and above it, m.
    orbit_radius_m, orbit_height_m, orbit_period_s : float
        Orbit eye: circle radius around the target, height above it (m) and time per revolution (s).
    topdown_follow : bool
        Top-down map centred on the target (span ``topdown_span_m``) instead of framing the whole run.
    topdown_span_m : float
        Ground width shown by a following top-down map, m.
    onboard_pitch : float
        Onboard camera gimbal pitch below the horizon, rad, when it does not track the target.
    onboard_track : bool
        The onboard gimbal points at the target.
    crf : int
        H.264 constant rate factor (0–51; lower is better quality and bigger files).
    preset : str
        x264 speed preset (``ultrafast`` … ``veryslow``).
    progress : bool
        Show a progress bar.
    workers : int
        Processes rendering frames in parallel (each with its own PyBullet client), >= 1; 1 renders in this process.
    """

    out: Path | None = None
    width: int = 1280
    height: int = 720
    fps: int = 30
    camera: Literal["chase", "orbit", "topdown", "onboard", "split"] = "split"
    uav: int = 0
    target: int | None = None
    t_start: float = 0.0
    t_end: float | None = None
    renderer: Literal["auto", "egl", "tiny"] = "auto"
    render_scale: float = 0.5
    overlays: bool = True
    legend: bool = True
    trail_s: float = 15.0
    uav_scale: float = 8.0
    car_size: tuple[float, float, float] | None = None
    vfov: float = float(np.deg2rad(50.0))
    chase_vfov: float = float(np.deg2rad(35.0))
    smoothing_s: float = 0.5
    chase_back_m: float = 60.0
    chase_up_m: float = 30.0
    orbit_radius_m: float = 140.0
    orbit_height_m: float = 90.0
    orbit_period_s: float = 60.0
    topdown_follow: bool = False
    topdown_span_m: float = 400.0
    onboard_pitch: float = float(np.deg2rad(35.0))
    onboard_track: bool = True
    crf: int = 23
    preset: str = "veryfast"
    progress: bool = True
    workers: int = 1

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            v = getattr(self, name)
            if not isinstance(v, int) or v < 16 or v % 2:
                raise ValueError(f"RenderConfig.{name} must be an even integer >= 16 pixels, got {v!r}")
        if not isinstance(self.fps, int) or not 1 <= self.fps <= 240:
            raise ValueError(f"RenderConfig.fps must be an integer in [1, 240] Hz, got {self.fps!r}")
        if self.camera not in CAMERAS:
            raise ValueError(f"RenderConfig.camera must be one of {CAMERAS}, got {self.camera!r}")
        if self.renderer not in ("auto", "egl", "tiny"):
            raise ValueError(f"RenderConfig.renderer must be 'auto', 'egl' or 'tiny', got {self.renderer!r}")
        if self.uav < 0 or (self.target is not None and self.target < 0):
            raise ValueError(f"RenderConfig.uav / target must be >= 0, got {self.uav}, {self.target}")
        if self.t_end is not None and self.t_end <= self.t_start:
            raise ValueError(f"RenderConfig.t_end must exceed t_start {self.t_start} s, got {self.t_end}")
        if not 0.0 < self.render_scale <= 1.0:
            raise ValueError(f"RenderConfig.render_scale must be in (0, 1], got {self.render_scale}")
        for name in ("vfov", "chase_vfov"):
            if not 0.0 < getattr(self, name) < np.pi:
                raise ValueError(f"RenderConfig.{name} must be in (0, pi) rad, got {getattr(self, name)}")
        if not 0.0 <= self.onboard_pitch < np.pi / 2:
            raise ValueError(f"RenderConfig.onboard_pitch must be in [0, pi/2) rad, got {self.onboard_pitch}")
        positive = ("uav_scale", "trail_s", "chase_back_m", "orbit_radius_m", "orbit_period_s", "topdown_span_m")
        for name in positive:
            if not getattr(self, name) > 0:
                raise ValueError(f"RenderConfig.{name} must be > 0, got {getattr(self, name)}")
        if self.smoothing_s < 0:
            raise ValueError(f"RenderConfig.smoothing_s must be >= 0 s, got {self.smoothing_s}")
        if self.car_size is not None and (len(self.car_size) != 3 or min(self.car_size) <= 0):
            raise ValueError(f"RenderConfig.car_size must be three positive lengths (m), got {self.car_size}")
        if not isinstance(self.workers, int) or self.workers < 1:
            raise ValueError(f"RenderConfig.workers must be an integer >= 1, got {self.workers!r}")
        if not 0 <= self.crf <= 51:
            raise ValueError(f"RenderConfig.crf must be in [0, 51], got {self.crf}")
