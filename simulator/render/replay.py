"""Rendering the frames of a recorded run directory (:func:`simulator.render.video.render_run` encodes them).

Per video frame (at ``fps``, not at the physics rate): interpolate the recorded truth to the frame time, pose the
stage's bodies, move each panel's camera, render, scale to the panel size, draw the overlays and encode. A ``split``
frame is a chase view (left half) beside a top-down map (right half); every other layout is one panel.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from simulator.render.cameras import CameraInputs, CameraRig, ChaseCamera, OnboardCamera, OrbitCamera, TopDownCamera
from simulator.render.config import RenderConfig
from simulator.render.overlays import (LEGEND, SEARCH_LEGEND, TRACKS_LEGEND, EstimateMark, GroundRegion, OverlayFrame,
                                       TrackMark, draw_hud, draw_overlays)
from simulator.render.projection import CameraView
from simulator.render.stage import UAV_COLORS, Stage, load_geometry
from simulator.render.timeline import HIDDEN_Z, Timeline
from simulator.render.world_marks import RadioLinks, radar_regards
from simulator.render.world_view import ReplayWorld, read_world
from simulator.runrecord import load_run, load_search_sets

__all__ = ["Panel", "RenderedFrame", "Replayer"]

log = logging.getLogger(__name__)

_TOPDOWN_MARGIN = 0.08  # fraction of the framed area added on each side
_X_RGB, _X_ALPHA = (0.85, 0.1, 0.1), 0.45  # the search's sets, as in plots/search.png
_XBAR_RGB, _XBAR_ALPHA = (0.2, 0.45, 0.9), 0.3


@dataclass(frozen=True)
class Panel:
    """One camera's part of a frame: the view, and the panel's left edge and size in the frame, pixels."""

    name: str
    view: CameraView
    x0: int
    width: int
    height: int
    seg: np.ndarray | None = None


@dataclass(frozen=True)
class RenderedFrame:
    """A finished frame (H, W, 3) RGB uint8 at time ``t`` s and its panels."""

    t: float
    rgb: np.ndarray
    panels: list[Panel]


class Replayer:
    """Renders frames of a recorded run.

    Parameters
    ----------
    run_dir : Path
        A run directory (complete or partial) with a ``uav_truth`` stream. Without vehicles the cameras look at the
        ground below the fleet's centre.
    config : RenderConfig
        Size, camera, renderer, overlays.
    """

    def __init__(self, run_dir: Path, config: RenderConfig) -> None:
        self.run_dir = Path(run_dir)
        self.config = cfg = config
        rec = load_run(self.run_dir)
        self.metrics = rec.metrics
        world_name, seed = rec.run.get("world"), rec.run.get("seed")
        self.title = f"{world_name} (seed {seed})" if world_name is not None else self.run_dir.name
        self.timeline = tl = Timeline(rec.streams)
        self.world = world = ReplayWorld(read_world(self.run_dir))
        self.uav_index = sorted(tl.uavs)
        self.vehicle_index = sorted(tl.vehicles)
        self.uav_names = {u: world.uav_name(u) for u in self.uav_index}
        self.standoff: dict[int, float | None] = {u: world.standoff(u) for u in self.uav_index}
        target = cfg.target if cfg.target is not None else int(rec.metrics.get("target_index") or 0)
        self.target: int | None = target if target in tl.vehicles else (self.vehicle_index or [None])[0]
        if cfg.uav not in tl.uavs:
            raise ValueError(f"RenderConfig.uav = {cfg.uav}: the run has UAVs {self.uav_index}")
        self.geometry = load_geometry(self.run_dir / "geometry.npz")
        self.uav_span = 2.0 * world.uav_arm_length() * cfg.uav_scale  # tip to tip, m
        self._sizes = [cfg.car_size or world.vehicle_size(v) for v in self.vehicle_index]
        # other cars: those of role traffic (every car but the target when the world does not say)
        self._traffic = [v for v in self.vehicle_index
                         if v != self.target and world.vehicle_role(v) in ("traffic", None)]
        self._decoys = world.decoys()
        self.layout = self._layout()
        self.stage = self._choose_stage()
        self.regards = radar_regards(world.world)
        self._road_index = {rid: k for k, rid in enumerate(self.geometry.road_ids) if rid}
        self.links = self._radio_links()
        self.search_sets = _SearchSets(self.run_dir, cfg.uav, rec.streams.get("search"))

    def _radio_links(self) -> RadioLinks | None:
        """The run's radio model on the stage's buildings, or None (perfect radio, or a model that cannot be built)."""
        try:
            links = RadioLinks(self.world.world, self.geometry.buildings)
        except Exception as exc:  # noqa: BLE001 - links are a decoration: a replay must not fail for them
            log.info("no radio links drawn: %s", exc)
            return None
        return links if links.active else None

    # -- layout and renderer -----------------------------------------------------------------------------------

    def _layout(self) -> list[tuple[str, int, int]]:
        w = self.config.width
        if self.config.camera == "split":
            return [("chase", 0, w // 2), ("topdown", w // 2, w - w // 2)]
        return [(self.config.camera, 0, w)]

    def _rig(self, name: str, aspect: float) -> CameraRig:
        cfg = self.config
        if name == "chase":
            return ChaseCamera(cfg.chase_vfov, cfg.smoothing_s, cfg.chase_back_m, cfg.chase_up_m)
        if name == "orbit":
            return OrbitCamera(cfg.vfov, cfg.smoothing_s, cfg.orbit_radius_m, cfg.orbit_height_m, cfg.orbit_period_s)
        if name == "onboard":
            return OnboardCamera(cfg.vfov, cfg.smoothing_s, cfg.onboard_pitch, 0.75 * self.uav_span, cfg.onboard_track)
        return TopDownCamera(np.deg2rad(40.0), cfg.smoothing_s, aspect,
                             None if cfg.topdown_follow else self._area(), cfg.topdown_span_m)

    def _area(self) -> tuple[float, float, float, float]:
        xy = [np.c_[tr.p_W[:, 0], tr.p_W[:, 1]] for tr in (*self.timeline.uavs.values(),
                                                           *self.timeline.vehicles.values())]
        b = self.geometry.bounds()
        if b is not None:
            xy.append(np.array([[b[0], b[2]], [b[1], b[3]]]))
        pts = np.concatenate(xy)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        m = _TOPDOWN_MARGIN * max(hi - lo)
        return float(lo[0] - m), float(hi[0] + m), float(lo[1] - m), float(hi[1] + m)

    def _new_stage(self, egl: bool) -> Stage:
        return Stage(self.geometry, len(self.uav_index), self._sizes, self.uav_span, use_egl=egl,
                     decoys=self._decoys)

    def _choose_stage(self) -> Stage:
        want = self.config.renderer
        if want == "tiny":
            return self._new_stage(False)
        egl = self._new_stage(True)
        if not egl.egl:
            egl.close()
            warnings.warn("the EGL renderer is not usable here: rendering with TinyRenderer (slower on GPUs)",
                          stacklevel=3)
            return self._new_stage(False)
        if want == "egl":
            return egl
        tiny = self._new_stage(False)
        t0 = self.frame_times()[0]
        cost = {}
        for stage in (tiny, egl):
            self.stage = stage
            self._pose(t0)
            name, _, pw = self.layout[0]
            view = self._rig(name, pw / self.config.height).view(self._inputs(t0), 0.0)
            w, h = self._render_size(pw)
            cost[stage] = stage.time_render(view, w, h)
        best = min(cost, key=cost.get)
        (egl if best is tiny else tiny).close()
        other = egl if best is tiny else tiny
        log.info("renderer: %s (%.0f ms/frame) over %s (%.0f ms)", best.renderer_name, 1e3 * cost[best],
                 other.renderer_name, 1e3 * cost[other])
        return best

    # -- frames ------------------------------------------------------------------------------------------------

    def frame_times(self) -> np.ndarray:
        """Times of the video frames, s: every 1/fps from the start to the end of the record (or of the config)."""
        tl, cfg = self.timeline, self.config
        t0 = max(cfg.t_start, tl.t_start)
        t1 = tl.t_end if cfg.t_end is None else min(cfg.t_end, tl.t_end)
        n = max(1, int(np.floor((t1 - t0) * cfg.fps + 1e-6)))
        return t0 + np.arange(n) / cfg.fps

    def _render_size(self, panel_w: int) -> tuple[int, int]:
        s = self.config.render_scale
        return max(8, int(round(panel_w * s))), max(8, int(round(self.config.height * s)))

    def _pose(self, t: float) -> None:
        tl = self.timeline
        self.stage.set_poses([tl.uavs[u].at(t) for u in self.uav_index], [tl.vehicles[v].at(t) for v in
                                                                          self.vehicle_index])

    def _inputs(self, t: float) -> CameraInputs:
        p_u, q_u = self.timeline.uavs[self.config.uav].at(t)
        return CameraInputs(t=t, p_uav_W=p_u, q_uav_WB=q_u, p_target_W=self._target_at(t))

    def _target_at(self, t: float) -> np.ndarray:
        """The target's true position at ``t`` s, or the ground below the fleet's centre when there is none, m."""
        if self.target is not None:
            return self.timeline.vehicles[self.target].at(t)[0]
        c = np.mean([self.timeline.uavs[u].at(t)[0] for u in self.uav_index], axis=0)
        return np.array([c[0], c[1], 0.0])

    def overlay_frame(self, t: float) -> OverlayFrame:
        """The marks to draw at time ``t`` s."""
        tl, cfg = self.timeline, self.config
        p_t = self._target_at(t)
        marks = []
        for u, est in sorted(tl.estimates.items()):
            got = est.at(t)
            if got is not None:
                marks.append(EstimateMark(u, UAV_COLORS[u % len(UAV_COLORS)], got[0], got[1], self.standoff.get(u)))
        trails = [(UAV_COLORS[u % len(UAV_COLORS)], tl.uavs[u].trail(t, cfg.trail_s)) for u in self.uav_index]
        traffic_W = np.array([tl.vehicles[v].at(t)[0] for v in self._traffic]) if self._traffic else None
        if traffic_W is not None:  # no brackets on free slots (kept below the ground)
            traffic_W = traffic_W[traffic_W[:, 2] > 0.5 * HIDDEN_Z]
        return OverlayFrame(target_W=p_t if self.target is not None else None, estimates=marks, trails=trails,
                            scans=tl.radar_scans(t),
                            scan_rgb={u: UAV_COLORS[u % len(UAV_COLORS)] for u in self.uav_index},
                            uavs=[(UAV_COLORS[u % len(UAV_COLORS)], self.uav_names[u], tl.uavs[u].at(t)[0])
                                  for u in self.uav_index],
                            ground_z=float(p_t[2]), regards=self._regard_marks(t, float(p_t[2])),
                            links=self._link_marks(t), constrained_roads=self._road_marks(t, float(p_t[2])),
                            regions=self.search_sets.regions(t), tracks=self._track_marks(t), traffic_W=traffic_W)

    def _track_marks(self, t: float) -> list[TrackMark]:
        marks = []
        for u, steps in sorted(self.timeline.tracks.items()):
            got = steps.at(t)
            if got is not None:
                marks.append(TrackMark(u, UAV_COLORS[u % len(UAV_COLORS)], got.track, got.xy, got.p_target,
                                       got.is_target))
        return marks

    def _road_marks(self, t: float, z: float) -> list[tuple[tuple[float, float, float], np.ndarray]]:
        marks = []
        for u, est in sorted(self.timeline.estimates.items()):
            k = self._road_index.get(est.road_at(t))
            if k is not None:
                line = self.geometry.roads[k][:, :2]
                marks.append((UAV_COLORS[u % len(UAV_COLORS)], np.c_[line, np.full(len(line), z + 0.3)]))
        return marks

    def _regard_marks(self, t: float, z: float) -> list[tuple[tuple[float, float, float], np.ndarray]]:
        marks = []
        for r in self.regards:
            if r.uav in self.timeline.uavs:
                p, q = self.timeline.uavs[r.uav].at(t)
                yaw = float(np.arctan2(2.0 * (q[3] * q[2] + q[0] * q[1]), 1.0 - 2.0 * (q[1] ** 2 + q[2] ** 2)))
                marks.append((UAV_COLORS[r.uav % len(UAV_COLORS)], r.outline(p, yaw, z)))
        return marks

    def _link_marks(self, t: float) -> list[tuple[np.ndarray, np.ndarray, float]]:
        if self.links is None or len(self.uav_index) != len(self.links.names):
            return []
        return self.links.at(t, [self.timeline.uavs[u].at(t)[0] for u in self.uav_index])

    def hud_lines(self, t: float) -> list[tuple[str, tuple[float, float, float]]]:
        """HUD text: the time, then per UAV its estimate's position error and 2σ, its tracks and target track if it
        keeps tracks, and its solver time if recorded."""
        tl = self.timeline
        p_t = self._target_at(t)
        lines = [(f"{self.title}  t = {t:6.2f} s", (1.0, 1.0, 1.0))]
        per_uav = self.metrics.get("uavs") or {}
        for u in self.uav_index:
            name = self.uav_names[u]
            got = tl.estimates[u].at(t) if u in tl.estimates else None
            areas = self.search_sets.areas(u, t)
            text = f"{name}: no estimate" if areas is None else f"{name}: {areas}"
            if got is not None and self.target is None:
                text = f"{name}: estimate at ({got[0][0]:.0f}, {got[0][1]:.0f}) m"
            elif got is not None:
                err = float(np.hypot(*(got[0] - p_t[:2])))
                two_sigma = 2.0 * float(np.sqrt(max(np.trace(got[1]), 0.0)))
                text = f"{name}: error {err:5.1f} m  2sigma {two_sigma:5.1f} m"
            held = tl.tracks[u].at(t) if u in tl.tracks else None
            if held is not None:
                text += f"  {len(held.track)} tracks"
                if held.is_target.any():
                    k = int(np.argmax(np.where(held.is_target, held.p_target, -np.inf)))
                    text += f", target {int(held.track[k])} (p {float(held.p_target[k]):.2f})"
            solve = (per_uav.get(name) or {}).get("solve_ms_p50")
            if solve is not None:
                text += f"  solve {float(solve):.1f} ms"
            lines.append((text, UAV_COLORS[u % len(UAV_COLORS)]))
        if self.search_sets and self.search_sets.regions(t):
            lines.append((f"sets drawn: {self.uav_names[self.config.uav]}'s", (0.9, 0.9, 0.9)))
        return lines

    def render_frames(self, segmentation: bool = False, start: int = 0,
                      stop: int | None = None) -> Iterator[RenderedFrame]:
        """Yield a :class:`RenderedFrame` per video frame ``start <= k < stop`` (a generator).

        The cameras move smoothly from the first frame on: frames before ``start`` advance them without being
        rendered, so any range of frames comes out exactly as in one pass over the whole video.
        """
        cfg = self.config
        rigs = [self._rig(name, pw / cfg.height) for name, _, pw in self.layout]
        times = self.frame_times()
        stop = len(times) if stop is None else min(stop, len(times))
        prev = None
        for k, t in enumerate(times[:stop]):
            dt = 0.0 if prev is None else float(t - prev)
            prev = t
            views = [rig.view(self._inputs(float(t)), dt) for rig in rigs]
            if k >= start:
                yield self._frame(float(t), views, segmentation)

    def _frame(self, t: float, views: list[CameraView], segmentation: bool) -> RenderedFrame:
        cfg = self.config
        self._pose(t)
        marks = self.overlay_frame(t) if cfg.overlays else None
        out = np.empty((cfg.height, cfg.width, 3), dtype=np.uint8)
        panels = []
        for (name, x0, pw), view in zip(self.layout, views, strict=True):
            rw, rh = self._render_size(pw)
            rgb, seg = self.stage.render(view, rw, rh, segmentation=segmentation, aspect=pw / cfg.height,
                                         ground_level=marks is not None and bool(marks.regions))
            ground = self.stage.ground_visible
            if (rw, rh) != (pw, cfg.height):
                rgb = cv2.resize(rgb, (pw, cfg.height), interpolation=cv2.INTER_LINEAR)
                if seg is not None:
                    seg = cv2.resize(seg.astype(np.int32), (pw, cfg.height), interpolation=cv2.INTER_NEAREST)
                if ground is not None:
                    ground = cv2.resize(ground.astype(np.uint8), (pw, cfg.height),
                                        interpolation=cv2.INTER_NEAREST).astype(bool)
            if marks is not None:
                draw_overlays(rgb, view, marks, ground_visible=ground)
            out[:, x0:x0 + pw] = rgb
            panels.append(Panel(name, view, x0, pw, cfg.height, seg))
        if cfg.overlays:
            draw_hud(out, self.hud_lines(t))
            if cfg.legend:
                draw_hud(out, LEGEND + (SEARCH_LEGEND if self.search_sets else ())
                         + (TRACKS_LEGEND if self.timeline.tracks else ()), corner="bottom", size=0.7)
            for pnl in panels[1:]:
                cv2.line(out, (pnl.x0, 0), (pnl.x0, cfg.height - 1), (20, 20, 20), 2)
        return RenderedFrame(t=t, rgb=out, panels=panels)

    def close(self) -> None:
        self.stage.close()


class _SearchSets:
    """The sets of one UAV of a set-membership search (``search_sets.jsonl.gz``) over time: the last snapshot at or
    before a frame's time, parsed once; every UAV's set areas from the ``search`` stream for the HUD. Empty for other
    runs."""

    def __init__(self, run_dir: Path, uav: int, stream: dict[str, np.ndarray] | None) -> None:
        snaps = [s for s in load_search_sets(run_dir) if uav in s.sets]
        self._t = np.array([s.t for s in snaps])
        self._wkt = [s.sets[uav] for s in snaps]
        self._parsed: tuple[int, tuple[Any, Any]] | None = None
        self._areas: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        if stream is not None:
            for u in np.unique(stream.get("uav", [])).tolist():
                m = stream["uav"] == u
                self._areas[int(u)] = (stream["t"][m], stream["area_X"][m], stream["area_Xbar"][m])

    def __bool__(self) -> bool:
        return len(self._wkt) > 0

    def regions(self, t: float) -> list[GroundRegion]:
        """X̄ then X at time ``t`` s (none before the first snapshot)."""
        k = int(np.searchsorted(self._t, t + 1e-9, side="right")) - 1
        if k < 0:
            return []
        if self._parsed is None or self._parsed[0] != k:
            import shapely

            # rounded to 0.1 m, a set can touch itself: made valid once for the cuts of every frame
            X, Xbar = (shapely.make_valid(shapely.from_wkt(w)) for w in self._wkt[k])
            self._parsed = (k, (X, Xbar))
        X, Xbar = self._parsed[1]
        return [GroundRegion(_XBAR_RGB, _XBAR_ALPHA, Xbar), GroundRegion(_X_RGB, _X_ALPHA, X)]

    def areas(self, uav: int, t: float) -> str | None:
        """UAV ``uav``'s set areas at its last step at or before ``t`` s, as HUD text (None: not a searcher, or
        before its first step)."""
        if uav not in self._areas:
            return None
        ts, aX, aXb = self._areas[uav]
        j = int(np.searchsorted(ts, t + 1e-9, side="right")) - 1
        return None if j < 0 else f"X-bar {aXb[j]:.1%}  X {aX[j]:.2%} of the search area"
