"""The ``skytrack reproduce`` subcommand.

``skytrack reproduce 000|001|002|003|004|all [--runs N] [--workers K] [--seed S] [--quick] --out DIR``

Each paper's reproduction writes ``DIR/<paper>/report.md`` with its figures beside it and ``verdicts.json`` (every
claim with its verdict, rule, figures, runs and whether it was judged on the paper's configuration);
``DIR/report.md`` lists the papers run with their tallies: the paper's claims on the paper's configuration first, on
ours second, our extensions apart. ``--runs`` defaults to each paper's own count (:data:`PAPER_RUNS`).

Exit codes: 0 every requested reproduction ran; 1 one of them raised (the others still ran, and the index says which
failed); 2 bad input; 130 interrupted.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import json
import shlex
import sys
import time
import traceback
from pathlib import Path

from simulator.record import atomic_write_text
from simulator.reproduce.seeds import EVAL_SEED

__all__ = ["PAPERS", "add_reproduce_parser", "reproduce_papers"]

PAPERS: dict[str, tuple[str, str]] = {
    "000": ("simulator.reproduce.paper_000", "Hu et al. 2018: SCIF, HCMCI consensus and fast MPC"),
    "001": ("simulator.reproduce.paper_001", "Liu, Fu, Gao 2018: co-optimised communication and sensing"),
    "002": ("simulator.reproduce.paper_002", "Oh, Kim, Tsourdos 2015: road-map-assisted NMPC standoff tracking"),
    "003": ("simulator.reproduce.paper_003", "Yang, Wang 2019: FIM-optimal formation and IMM bearings-only tracking"),
    "004": ("simulator.reproduce.paper_004", "Ibenenthal et al.: set-membership search with decoys and obstacles"),
}
"""Paper code → (module defining ``reproduce(ctx) -> PaperReport``, one-line title)."""


def _available(code: str) -> bool:
    return importlib.util.find_spec(PAPERS[code][0]) is not None


def reproduce_papers(codes: list[str], out: Path, runs: int | None, workers: int | None, seed: int, quick: bool,
                     progress: bool, command: str) -> list[tuple[str, str, object]]:
    """Run the reproductions of ``codes`` into ``out`` (``runs`` None: each paper's own count); returns
    ``(code, "ok" | "error", report or traceback)``."""
    from simulator.reproduce.report import ReproContext, verdicts_record, write_paper_report
    from simulator.reproduce.seeds import PAPER_RUNS

    out.mkdir(parents=True, exist_ok=True)
    results: list[tuple[str, str, object]] = []
    for code in codes:
        paper_dir = out / code
        paper_dir.mkdir(parents=True, exist_ok=True)
        ctx = ReproContext(out_dir=paper_dir, runs=runs or PAPER_RUNS[code], workers=workers, seed=seed,
                           progress=progress, quick=quick)
        t0 = time.perf_counter()
        try:
            module = importlib.import_module(PAPERS[code][0])
            rep = module.reproduce(ctx)
        except KeyboardInterrupt:
            raise
        except Exception:  # noqa: BLE001 - one paper's failure must not stop the others; it is reported
            tb = traceback.format_exc()
            atomic_write_text(paper_dir / "error.txt", tb)
            print(f"skytrack reproduce: paper {code} failed:\n{tb}", file=sys.stderr)
            results.append((code, "error", tb))
            continue
        from dataclasses import replace

        rep = replace(rep, wall_time_s=time.perf_counter() - t0, quick=quick, seeds=rep.seeds or ctx.seeds_text(),
                      reused=dict(ctx.reused), codes=dict(ctx.codes))
        write_paper_report(rep, paper_dir, command)
        atomic_write_text(paper_dir / "verdicts.json",
                          json.dumps(verdicts_record(rep, command), indent=1, ensure_ascii=False) + "\n")
        (paper_dir / "error.txt").unlink(missing_ok=True)
        results.append((code, "ok", rep))
    _write_index(out)
    return results


def _tally_text(t: dict[str, int]) -> str:
    """``reproduced / not reproduced / inconclusive / not comparable`` counts of one tally."""
    return " / ".join(str(t.get(v, 0)) for v in ("reproduced", "not reproduced", "inconclusive", "not comparable"))


def _read_verdicts(path: Path) -> dict | None:
    """A ``verdicts.json`` written by this command, or None when it is missing, unreadable or of another form
    (stored results are untrusted input: an old or hand-edited file is listed as unreadable, never trusted)."""
    try:
        v = json.loads(path.read_text(encoding="utf-8"))
        tally = v["tally"]
        if not all(isinstance(tally[k], dict) for k in ("paper", "ours", "extensions")):
            return None
        int(v["runs"]), str(v["command"])
        return v
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _write_index(out: Path) -> None:
    """``out/report.md``: every paper reproduced into ``out`` so far (by this or an earlier command). Counts are
    reproduced / not reproduced / inconclusive / not comparable; only the paper's own claims enter the first two
    columns, judged on the paper's configuration first; our extensions are counted apart."""
    md = ["# Reproductions", "",
          "Counts: reproduced / not reproduced / inconclusive / not comparable.", "",
          "| paper | runs | paper's claims, paper's configuration | paper's claims, our configuration | "
          "our extensions | report | command |",
          "|---|---:|---|---|---|---|---|"]
    for code, (_, title) in PAPERS.items():
        paper_dir = out / code
        if (paper_dir / "error.txt").exists():
            md.append(f"| {code} {title} | | | | | failed: see `{code}/error.txt` | |")
            continue
        if not (paper_dir / "verdicts.json").exists():
            continue
        v = _read_verdicts(paper_dir / "verdicts.json")
        if v is None:
            md.append(f"| {code} {title} | | | | | unreadable `{code}/verdicts.json`: rerun | |")
            continue
        runs = f"{v['runs']}" + (" (quick)" if v.get("quick") else "") + (
            f" of {v['runs_asked']}" if v.get("runs_asked") and v["runs"] < v["runs_asked"] else "")
        t = v["tally"]
        md.append(f"| {code} {title} | {runs} | {_tally_text(t['paper'])} | {_tally_text(t['ours'])} | "
                  f"{_tally_text(t['extensions'])} | [{code}/report.md]({code}/report.md) | `{v['command']}` |")
    atomic_write_text(out / "report.md", "\n".join(md) + "\n")


def _reproduce(args: argparse.Namespace) -> int:
    if args.runs is not None and args.runs < 1:
        print(f"skytrack reproduce: --runs must be >= 1, got {args.runs}", file=sys.stderr)
        return 2
    codes = [c for c in PAPERS if _available(c)] if args.paper == "all" else [args.paper]
    missing = [c for c in codes if not _available(c)]
    if missing:
        print(f"skytrack reproduce: no reproduction of paper {missing[0]} is available", file=sys.stderr)
        return 2
    command = "skytrack reproduce " + " ".join(shlex.quote(a) for a in sys.argv[2:]) if len(sys.argv) > 2 else \
        f"skytrack reproduce {args.paper}" + (f" --runs {args.runs}" if args.runs else "")
    results = reproduce_papers(codes, Path(args.out), args.runs, args.workers, args.seed, args.quick,
                               not args.quiet, command)
    print(f"\nreports in {args.out}/report.md")
    for code, status, rep in results:
        if status == "ok":
            print(f"  {code}: " + ", ".join(f"{f.verdict}" for f in rep.findings))
        else:
            print(f"  {code}: FAILED")
    return 0 if all(s == "ok" for _, s, _ in results) else 1


def add_reproduce_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``reproduce`` subcommand on a ``skytrack`` subparser set."""
    r = subparsers.add_parser("reproduce", help="reproduce a paper's tables and figures into report.md")
    r.add_argument("paper", choices=[*PAPERS, "all"], help="paper code, or all")
    r.add_argument("--runs", type=int, default=None,
                   help="Monte Carlo runs per configuration (default: the paper's own count, 50 or 100)")
    r.add_argument("--out", required=True, help="output folder: <out>/report.md and <out>/<paper>/report.md")
    r.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    r.add_argument("--seed", type=int, default=EVAL_SEED,
                   help=f"base seed of the evaluation runs (default {EVAL_SEED}; 1 is the tuning base)")
    r.add_argument("--quick", action="store_true", help="shortened experiments for a smoke test (not a reproduction)")
    r.add_argument("--quiet", action="store_true", help="no progress bars")
    r.set_defaults(fn=_reproduce)
    return r
