"""Golden records: a digest of every stream of short runs of every shipped world, so a change of wiring can prove it
changed no number.

``python -m tests.simulator.golden --write`` runs the cases and writes ``golden_records.json``; the test
(:mod:`tests.simulator.test_golden_records`) runs them again and compares. Rewrite the file only with a change that is
meant to alter a record, and say which records and why in its commit.

The digests are of the bytes of each column, so they hold on one machine (the project's determinism promise,
DESIGN.md): another CPU or another numpy/numba build may round differently and needs its own file.
"""

from __future__ import annotations

import argparse
import gzip
import hashlib
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

GOLDEN_FILE = Path(__file__).with_name("golden_records.json")
SEEDS = (1, 2)
DURATION_S = 3.0
# keys of events and metrics that measure the machine (wall-clock time), not the simulation
_VOLATILE = ("wall", "real_time", "solve_time", "solve_ms", "build_s", "elapsed", "complete", "versions", "started")


def cases() -> list[tuple[str, int]]:
    from worlds.loader import shipped_worlds

    return [(name, seed) for name in sorted(shipped_worlds()) for seed in SEEDS]


def _volatile(key: str) -> bool:
    return any(v in key for v in _VOLATILE)


def _scrub(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _scrub(v) for k, v in sorted(obj.items()) if not _volatile(k)}
    if isinstance(obj, list):
        return [_scrub(v) for v in obj]
    return obj


def _digest_bytes(*chunks: bytes) -> str:
    h = hashlib.sha256()
    for c in chunks:
        h.update(c)
    return h.hexdigest()[:20]


def record_digest(out_dir: Path) -> dict[str, str]:
    """One digest per stream column, one for the events and one for the metrics (machine-time keys left out), and
    one for the search sets where the run has them."""
    from simulator.runrecord import load_run

    rec = load_run(out_dir)
    out: dict[str, str] = {}
    for name, cols in sorted(rec.streams.items()):
        for col, values in sorted(cols.items()):
            a = np.ascontiguousarray(values)
            out[f"{name}.{col}"] = _digest_bytes(str(a.dtype).encode(), str(a.shape).encode(), a.tobytes())
    out["events"] = _digest_bytes(json.dumps(_scrub(rec.events), sort_keys=True).encode())
    out["metrics"] = _digest_bytes(json.dumps(_scrub(rec.metrics), sort_keys=True).encode())
    sets = Path(out_dir) / "search_sets.jsonl.gz"
    if sets.exists():
        out["search_sets"] = _digest_bytes(gzip.decompress(sets.read_bytes()))
    return out


def run_case(name: str, seed: int, out_dir: Path) -> dict[str, str]:
    from simulator.api import run

    res = run(name, duration=DURATION_S, seed=seed, out_dir=out_dir)
    if res.status != "completed":
        raise RuntimeError(f"{name} seed {seed}: {res.status} ({res.error})")
    return record_digest(out_dir)


def load_golden() -> dict[str, dict[str, str]]:
    return json.loads(GOLDEN_FILE.read_text(encoding="utf-8"))["records"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="rewrite golden_records.json (else compare and report); "
                    "with --only, only those worlds' records")
    ap.add_argument("--only", default="", help="only worlds whose name contains this")
    args = ap.parse_args(argv)
    records = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, seed in cases():
            if args.only not in name:
                continue
            records[f"{name}/{seed}"] = run_case(name, seed, Path(tmp) / f"{name}-{seed}")
            print(f"{name}/{seed}: {len(records[f'{name}/{seed}'])} digests", file=sys.stderr)
    if args.write:  # with --only, the other worlds' records are kept as they are
        kept = {k: v for k, v in load_golden().items() if args.only and k not in records}
        data = {"duration_s": DURATION_S, "records": {**kept, **records}}
        GOLDEN_FILE.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        return 0
    golden, bad = load_golden(), 0
    for key, digests in records.items():
        want = golden.get(key, {})
        diff = sorted(k for k in set(want) | set(digests) if want.get(k) != digests.get(k))
        bad += bool(diff)
        print(f"{key}: {'ok' if not diff else 'DIFFERS in ' + ', '.join(diff)}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
