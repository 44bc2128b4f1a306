"""The ``skytrack export RUN_DIR --format rerun|mcap [--out FILE]`` subcommand.

Writes a recorded run directory (also a partial one) as a Rerun recording or an MCAP file for Foxglove. Exit codes:
0 written; 1 the export failed; 2 bad input (no run directory, a format whose package is not installed, an --out
suffix that contradicts --format).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

__all__ = ["FORMATS", "add_export_parser", "export_run"]

FORMATS = {"rerun": (".rrd", "rerun", "rerun-sdk"), "mcap": (".mcap", "mcap", "mcap")}
"""Format name -> (file suffix, module it needs, the package that provides it)."""


def export_run(run_dir: Path, fmt: str, out: Path) -> Path:
    """Write the run directory ``run_dir`` as ``fmt`` (``rerun`` or ``mcap``) to ``out``; returns the path."""
    from simulator.export.scene import read_scene

    scene = read_scene(run_dir)
    if fmt == "rerun":
        from simulator.export.rerun_file import write_rrd

        return write_rrd(scene, out)
    if fmt == "mcap":
        from simulator.export.mcap_file import write_mcap

        return write_mcap(scene, out)
    raise ValueError(f"unknown format {fmt!r} (one of {', '.join(FORMATS)})")


def _format(args: argparse.Namespace) -> str:
    """The format: ``--format``, else the suffix of ``--out``, else rerun."""
    by_suffix = {suffix: name for name, (suffix, _m, _p) in FORMATS.items()}
    suffix = Path(args.out).suffix if args.out else ""
    if args.format is None:
        return by_suffix.get(suffix, "rerun")
    if suffix in by_suffix and by_suffix[suffix] != args.format:
        raise ValueError(f"--out {args.out} is a {by_suffix[suffix]} file name but --format is {args.format}")
    return args.format


def _export(args: argparse.Namespace) -> int:
    run_dir = Path(args.run_dir)
    if not (run_dir / "run.json").exists() and not (run_dir / "timeseries").is_dir():
        print(f"skytrack export: {run_dir} is not a run directory (no run.json or timeseries/)", file=sys.stderr)
        return 2
    try:
        fmt = _format(args)
    except ValueError as exc:
        print(f"skytrack export: {exc}", file=sys.stderr)
        return 2
    suffix, module, package = FORMATS[fmt]
    if importlib.util.find_spec(module) is None:
        print(f"skytrack export: the {fmt} format needs the '{package}' package (pip install {package})",
              file=sys.stderr)
        return 2
    out = Path(args.out) if args.out else run_dir / f"run{suffix}"
    from simulator.stdio import stdout_to_fd

    try:
        with stdout_to_fd(2):  # PyBullet's C code prints on import (the replay's geometry reader): stdout stays ours
            path = export_run(run_dir, fmt, out)
    except Exception as exc:  # noqa: BLE001 - the run record is untouched; the failure is reported
        print(f"skytrack export: writing {out} failed: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
    print(f"{fmt}: {path}")
    return 0


def add_export_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``export`` subcommand on a ``skytrack`` subparser set."""
    e = subparsers.add_parser("export", help="write a run directory for Rerun (.rrd) or Foxglove (.mcap)")
    e.add_argument("run_dir", help="run directory written by 'skytrack run'")
    e.add_argument("--format", choices=tuple(FORMATS), default=None,
                   help="rerun (.rrd) or mcap (.mcap, Foxglove); default: from --out's suffix, else rerun")
    e.add_argument("--out", default=None, help="output file (default RUN_DIR/run.rrd or RUN_DIR/run.mcap)")
    e.set_defaults(fn=_export)
    return e
