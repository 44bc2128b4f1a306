"""The ``skytrack`` command: run worlds, list them, run benchmarks and Monte Carlo campaigns.

Exit codes: 0 success; 1 a run or benchmark failed; 2 bad input (invalid world, bad flag, an ``--out`` that cannot
be used); 3 the run diverged (the divergence watchdog stopped it: a body under the ground, faster than its airframe
can fly, or with a non-finite state); 130 interrupted (Ctrl-C, SIGTERM).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import signal
import sys
from pathlib import Path

from simulator.render.cli import add_video_arguments
from simulator.stdio import stdout_to_fd
from worlds.errors import WorldError

__all__ = ["EXIT_DIVERGED", "main"]

EXIT_DIVERGED = 3
"""Exit code of a run the divergence watchdog stopped (:mod:`simulator.watchdog`)."""


def _check_run_flags(args: argparse.Namespace) -> None:
    """The ``run`` flags' values, checked before anything is loaded or written (exit 2, the flag named)."""
    from simulator.clock import MAX_DURATION_S
    from simulator.rundir import RunDirError, check_out_dir

    d = args.duration
    if d is not None and not (math.isfinite(d) and 0 < d <= MAX_DURATION_S):
        raise _BadFlag(f"--duration {d:g}: the simulated duration must be a finite number of seconds in "
                       f"(0, {MAX_DURATION_S:g}]")
    if args.seed is not None and args.seed < 0:
        raise _BadFlag(f"--seed {args.seed}: a seed must be an integer >= 0")
    if args.out is not None:
        try:
            check_out_dir(Path(args.out))
        except RunDirError as exc:
            raise _BadFlag(f"--out {args.out}: {exc}") from None


def _run(args: argparse.Namespace) -> int:
    _check_run_flags(args)
    import simulator.registry  # noqa: F401  (registers the components' own rules with the loader's checks)
    from worlds.loader import load_world

    loaded = load_world(args.world, args.set or [])  # WorldError is reported by main() before PyBullet starts

    from simulator.engine import RunOptions, run_world
    from simulator.rundir import RunDirError

    out = Path(args.out) if args.out else Path("runs") / loaded.world.name
    opts = RunOptions(duration_s=args.duration, seed=args.seed, out_dir=out, progress=not args.quiet,
                      plots=not args.no_plots, notify=lambda text: print(f"skytrack: {text}", flush=True))
    video = _video_config(args, loaded, out)  # flag errors surface before the run, not after it
    try:
        result = run_world(loaded, opts)
    except RunDirError as exc:  # the default runs/<world> (or a directory changed since the check)
        raise _BadFlag(f"--out {out}: {exc}") from None
    _print_summary(result.metrics, out)
    if result.status == "diverged":
        print(f"skytrack: run stopped: {result.error}", file=sys.stderr)
    elif result.error:
        print(f"skytrack: run failed: {result.error} (traceback in {out / 'events.jsonl'})", file=sys.stderr)
    if result.status == "interrupted":
        return 130
    if video is not None:  # a failed run's partial record still makes a video of what happened up to the failure
        from simulator.render.video import render_run

        try:
            print(f"video: {render_run(out, video)}")
        except Exception as exc:  # noqa: BLE001 - the run record stays valid; the failure is reported
            print(f"skytrack: rendering the video failed: {exc}", file=sys.stderr)
            return 1
    return {"completed": 0, "diverged": EXIT_DIVERGED}.get(result.status, 1)


def _video_config(args: argparse.Namespace, loaded: object, out: Path) -> object | None:
    """The video settings of a run: ``--video [FILE]`` or the world's ``render.enabled``; None for no video."""
    from simulator.render.cli import render_config_from_args

    world_render = loaded.world.render
    if args.video is None and not world_render.enabled:
        return None
    path = out / "video.mp4" if args.video in (None, "") else Path(args.video)
    try:
        cfg = render_config_from_args(args, path, world_render)
    except ValueError as exc:
        raise _BadFlag(str(exc)) from None
    if cfg.uav >= len(loaded.world.uavs):
        raise _BadFlag(f"--uav {cfg.uav}: the world has {len(loaded.world.uavs)} UAV(s)")
    return cfg


class _BadFlag(ValueError):
    """A command-line flag with a bad value (exit code 2, nothing run)."""


def _print_summary(metrics: dict, out: Path) -> None:
    rows = [(k, v) for k, v in metrics.items() if not isinstance(v, (dict, list))]
    width = max((len(k) for k, _ in rows), default=10)
    print(f"\nrun record: {out}")
    for k, v in rows:
        text = f"{v:.4g}" if isinstance(v, float) else str(v)
        print(f"  {k:<{width}}  {text}")
    def shown(vals: dict) -> str:
        return ", ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in vals.items()
                         if not isinstance(v, dict))

    for section in ("uavs", "targets"):
        for name, vals in (metrics.get(section) or {}).items():
            print(f"  {section[:-1]} {name}: {shown(vals)}".rstrip(": "))
            for sub, inner in vals.items():
                if isinstance(inner, dict):
                    print(f"    {sub}: {shown(inner)}")
    base = metrics.get("base_station")
    if base:
        print(f"  base station: {shown(base)}")
        for name, vals in (base.get("uavs") or {}).items():
            print(f"    {name}: {shown(vals)}")


def _worlds(args: argparse.Namespace) -> int:
    """Each shipped world's name and its ``description`` (else its header comment's first paragraph), whole, wrapped
    to the terminal's width beside the names."""
    import shutil
    import textwrap

    import yaml

    from worlds.loader import shipped_worlds

    worlds = shipped_worlds()
    col = max((len(n) for n in worlds), default=0) + 2
    width = max(col + 30, min(shutil.get_terminal_size((100, 24)).columns, 120))
    for name, path in worlds.items():
        text = path.read_text(encoding="utf-8")
        try:
            raw = yaml.safe_load(text)
        except yaml.YAMLError:
            raw = None
        desc = str(raw.get("description") or "") if isinstance(raw, dict) else ""
        if not desc:  # the header comment's first paragraph
            head = []
            for line in text.splitlines():
                if not line.startswith("#") or (head and not line.lstrip("# ").strip()):
                    break
                head.append(line.lstrip("# ").strip())
            desc = " ".join(h for h in head if h)
        lines = textwrap.wrap(desc, width=width - col, break_long_words=False, break_on_hyphens=False) or [""]
        print(f"{name:<{col}}{lines[0]}".rstrip())
        for line in lines[1:]:
            print(" " * col + line)
    return 0


def _bench(args: argparse.Namespace) -> int:
    from simulator.bench.runner import run_benchmarks

    if args.json:  # PyBullet's C code prints to file descriptor 1: keep stdout for the JSON alone
        with stdout_to_fd(2):
            records, failures = run_benchmarks(args.only, progress=False)
    else:
        records, failures = run_benchmarks(args.only, progress=True)
    if args.json:
        print(json.dumps([r.to_json() for r in records], indent=2))
    else:
        print(f"\n{'name':<42} {'value':>12} {'unit':<6} {'target':>10}  ok")
        for r in records:
            target = "" if r.target is None else f"{r.target:g}"
            ok = {True: "yes", False: "NO", None: ""}[r.meets_target]
            print(f"{r.name:<42} {r.value:>12.4g} {r.unit:<6} {target:>10}  {ok}")
    for name, err in failures:
        print(f"benchmark {name} failed: {err}", file=sys.stderr)
    return 1 if failures else 0


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="skytrack", description="Multi-UAV ground-target tracking simulator")
    from simulator.cli_tools import add_tools_parsers, package_version

    ap.add_argument("--version", action="version", version=f"%(prog)s {package_version()}")
    sub = ap.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="run a world headless and write a run directory")
    r.add_argument("world", help="shipped world name (see 'skytrack worlds') or path to a world YAML file")
    r.add_argument("--duration", type=float, default=None, help="simulated seconds (overrides sim.duration_s)")
    r.add_argument("--seed", type=int, default=None, help="run seed (overrides sim.seed)")
    r.add_argument("--out", default=None, help="run directory (default runs/<world name>)")
    r.add_argument("--set", action="append", metavar="KEY.PATH=VALUE",
                   help="override a world value, e.g. --set uavs[0].autonomy.guidance.standoff_m=150 (repeatable)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    r.add_argument("--video", nargs="?", const="", default=None, metavar="FILE",
                   help="render an MP4 after the run (default FILE: <out>/video.mp4); also on with render.enabled")
    add_video_arguments(r)
    r.set_defaults(fn=_run)

    w = sub.add_parser("worlds", help="list the shipped worlds")
    w.set_defaults(fn=_worlds)

    b = sub.add_parser("bench", help="run the benchmark suite")
    b.add_argument("--only", type=re.compile, default=None, metavar="REGEX", help="only benchmarks whose names match")
    b.add_argument("--json", action="store_true", help="print a JSON list of records")
    b.set_defaults(fn=_bench)

    from simulator.render.cli import add_render_parser

    add_render_parser(sub)

    from simulator.campaign.cli import add_campaign_parser

    add_campaign_parser(sub)

    from simulator.reproduce.cli import add_reproduce_parser

    add_reproduce_parser(sub)

    from simulator.export.cli import add_export_parser

    add_export_parser(sub)

    add_tools_parsers(sub)
    return ap


def _sigterm_as_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    previous = signal.signal(signal.SIGTERM, _sigterm_as_interrupt)
    try:
        return args.fn(args)
    except (WorldError, _BadFlag) as exc:
        print(f"skytrack: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("skytrack: interrupted", file=sys.stderr)
        return 130
    finally:  # called in-process (tests, notebooks): SIGTERM as it was
        signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
