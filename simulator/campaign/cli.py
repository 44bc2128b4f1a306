"""The ``skytrack campaign`` subcommand.

``skytrack campaign WORLD --runs N [--workers K] [--ray ADDRESS|auto] --out DIR [--seed S] [--duration D] [--set k=v
...]``

Exit codes: 0 at least one run completed; 1 every run failed; 2 invalid input or a resume with other parameters (nothing
was run); 130 interrupted (finished runs are kept: the same command resumes).
``python -m simulator.campaign.cli campaign ...`` runs it without the ``skytrack`` entry point.
"""

from __future__ import annotations

import argparse
import signal
import sys
from pathlib import Path

from worlds.errors import WorldError

__all__ = ["add_campaign_parser", "main"]


def _campaign(args: argparse.Namespace) -> int:
    from simulator.campaign.aggregate import format_table
    from simulator.campaign.config import CampaignConfig, CampaignError
    from simulator.campaign.runner import run_campaign

    try:
        config = CampaignConfig(world=args.world, runs=args.runs, out_dir=Path(args.out), seed=args.seed,
                                duration_s=args.duration, overrides=tuple(args.set or ()), workers=args.workers,
                                ray_address=args.ray, progress=not args.quiet)
        result = run_campaign(config)
    except (CampaignError, ValueError) as exc:
        if isinstance(exc, WorldError):
            raise
        print(f"skytrack campaign: {exc}", file=sys.stderr)
        return 2
    s = result.summary
    redone = f", {len(result.redone)} of them redone: their stored files were damaged" if result.redone else ""
    print(f"\ncampaign {result.out_dir}: {s.runs} of {result.params.runs} runs recorded "
          f"({result.ran} run now{redone}), {s.completed} completed, {s.failed} failed")
    for index, why in sorted(result.redone.items()):
        print(f"  run {index} redone: {why}", file=sys.stderr)
    if s.metrics:
        print(format_table(s))
    for index, error in s.failures:
        print(f"  run {index} failed: {error}", file=sys.stderr)
    if result.missing:
        print(f"skytrack campaign: runs {result.missing} were interrupted; run the same command to resume",
              file=sys.stderr)
    return 1 if result.all_failed else 0


def add_campaign_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``campaign`` subcommand (handler in ``fn``) on a ``skytrack`` subparser set."""
    c = subparsers.add_parser("campaign", help="Monte Carlo campaign: N seeded runs of a world, resumable, aggregated")
    c.add_argument("world", help="shipped world name (see 'skytrack worlds') or path to a world YAML file")
    c.add_argument("--runs", type=int, required=True, help="number of runs N")
    c.add_argument("--out", required=True, help="campaign directory (an interrupted campaign resumes from it)")
    c.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    c.add_argument("--ray", default=None, metavar="ADDRESS|auto",
                   help="run on a Ray cluster ('auto': a running local one, else start one); needs skytrack[cluster]")
    c.add_argument("--seed", type=int, default=None, help="campaign seed (default: the world's sim.seed)")
    c.add_argument("--duration", type=float, default=None, help="simulated seconds per run (overrides sim.duration_s)")
    c.add_argument("--set", action="append", metavar="KEY.PATH=VALUE", help="override a world value (repeatable)")
    c.add_argument("--quiet", action="store_true", help="no progress bar")
    c.set_defaults(fn=_campaign)
    return c


def _sigterm_as_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def main(argv: list[str] | None = None) -> int:
    """Stand-alone entry point: ``python -m simulator.campaign.cli campaign WORLD --runs N --out DIR ...``."""
    ap = argparse.ArgumentParser(prog="skytrack")
    add_campaign_parser(ap.add_subparsers(dest="command", required=True))
    args = ap.parse_args(argv)
    signal.signal(signal.SIGTERM, _sigterm_as_interrupt)
    try:
        return args.fn(args)
    except WorldError as exc:
        print(f"skytrack: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("skytrack: interrupted; run the same command to resume", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
