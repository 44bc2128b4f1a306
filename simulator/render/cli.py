"""Video flags of ``skytrack run --video`` and the ``skytrack render RUN_DIR`` subcommand.

``skytrack render RUN_DIR [--out FILE] [--camera chase|orbit|topdown|onboard|split] [--uav I] [--width W] [--height H]
[--fps F] [--start S] [--end S] [--renderer auto|egl|tiny] [--workers K]`` replays a recorded run directory (also a
partial one) to an MP4. Exit codes: 0 written; 1 rendering failed; 2 bad input (no run directory, bad flag values).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from simulator.render.config import CAMERAS, RenderConfig

__all__ = ["add_video_arguments", "add_render_parser", "render_config_from_args"]


def add_video_arguments(parser: argparse.ArgumentParser, defaults: dict[str, Any] | None = None) -> None:
    """Add the camera, size, rate and renderer flags (their defaults ``None``: the world's ``render`` section or
    :class:`RenderConfig` fills them)."""
    g = parser.add_argument_group("video")
    g.add_argument("--camera", choices=CAMERAS, default=None, help="camera (default: the world's render.camera, split)")
    g.add_argument("--uav", type=int, default=None, help="index of the UAV the chase/onboard cameras ride with")
    g.add_argument("--width", type=int, default=None, help="frame width, pixels (default 1280)")
    g.add_argument("--height", type=int, default=None, help="frame height, pixels (default 720)")
    g.add_argument("--fps", type=int, default=None, help="video frame rate, Hz (default 30)")
    g.add_argument("--renderer", choices=("auto", "egl", "tiny"), default="auto",
                   help="auto: EGL off-screen when usable, else TinyRenderer (with a warning)")
    g.add_argument("--render-workers", type=int, default=1, metavar="K", help="processes rendering frames (default 1)")


def render_config_from_args(args: argparse.Namespace, out: Path | None, world_render: Any = None,
                            **extra: Any) -> RenderConfig:
    """A :class:`RenderConfig` from the flags of :func:`add_video_arguments`; flags left unset take the world file's
    ``render`` section (``world_render``), then the :class:`RenderConfig` defaults."""
    kw: dict[str, Any] = {"out": out, "renderer": args.renderer, "workers": args.render_workers,
                          "progress": not getattr(args, "quiet", False), **extra}
    for key in ("camera", "uav", "width", "height", "fps"):
        value = getattr(args, key)
        if value is None and world_render is not None:
            value = getattr(world_render, key, None)
        if value is not None:
            kw[key] = value
    return RenderConfig(**kw)


def _render(args: argparse.Namespace) -> int:
    from simulator.render.video import render_run

    run_dir = Path(args.run_dir)
    if not (run_dir / "run.json").exists() and not (run_dir / "timeseries").is_dir():
        print(f"skytrack render: {run_dir} is not a run directory (no run.json or timeseries/)", file=sys.stderr)
        return 2
    try:
        cfg = render_config_from_args(args, Path(args.out) if args.out else None, _world_render(run_dir),
                                      t_start=args.start, t_end=args.end)
    except ValueError as exc:
        print(f"skytrack render: {exc}", file=sys.stderr)
        return 2
    try:
        path = render_run(run_dir, cfg)
    except (FileNotFoundError, ValueError) as exc:
        print(f"skytrack render: {exc}", file=sys.stderr)
        return 2
    print(f"video: {path}")
    return 0


def _world_render(run_dir: Path) -> Any:
    """The ``render`` section of the run's resolved world, or None when it does not load."""
    try:
        from worlds.loader import load_world

        return load_world(run_dir / "world.yaml").world.render
    except Exception:  # noqa: BLE001 - a world from another schema version still renders with the flags' defaults
        return None


def add_render_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``render`` subcommand on a ``skytrack`` subparser set."""
    r = subparsers.add_parser("render", help="replay a recorded run directory as an MP4 video (off-screen)")
    r.add_argument("run_dir", help="run directory written by 'skytrack run'")
    r.add_argument("--out", default=None, help="output .mp4 (default RUN_DIR/video.mp4)")
    r.add_argument("--start", type=float, default=0.0, help="first frame's time, s (default 0)")
    r.add_argument("--end", type=float, default=None, help="last frame's time, s (default: end of the record)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    add_video_arguments(r)
    r.set_defaults(fn=_render)
    return r
