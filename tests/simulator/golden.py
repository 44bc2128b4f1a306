"""Golden records: a digest of every stream of short runs of every shipped world, so a change of wiring can prove it
changed no number.

``python -m tests.simulator.golden --write`` runs the cases and writes ``golden_records.json``; the test
(:mod:`tests.simulator.test_golden_records`) runs them again and compares. Rewrite the file only with a change that is
meant to alter a record, and say which records and why in its commit.

The digests are of the bytes of each column, so they hold on one machine (the project's determinism promise,
DESIGN.md): another CPU or another numpy/numba build rounds differently. The file therefore also keeps the machine
that wrote it (:func:`tests.numeric_record.machine_key`) and a summary of every column, of the events and of the
metrics (:mod:`tests.numeric_record`): that machine checks the digests bit for bit, any other the summaries to a
relative 1e-6 (rounding moves them by 1e-11; a change of wiring or arithmetic by far more).
"""

from __future__ import annotations

import argparse
import gzip
import hashlib
import json
import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any


from tests.numeric_record import column_digest, differences, flatten, machine_key, summarise

if TYPE_CHECKING:
    from simulator.runrecord import RunRecord

GOLDEN_FILE = Path(__file__).with_name("golden_records.json")
BITS_ONLY = ("helsinki_chase",)
"""Worlds checked on the machine that wrote the file only: rounding alone changes their discrete outcomes (with
OpenBLAS made to take another kernel, a camera blob at the detector's threshold came and went, and the NMPC's
commands moved by more than 1e-6)."""
VALUES_FILE = Path(__file__).with_name("golden_values.json.gz")
"""The summaries, beside the digests (gzipped JSON: a megabyte as text)."""
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


def record_digest(rec: RunRecord, out_dir: Path) -> dict[str, str]:
    """One digest per stream column of the run record ``rec``, one for the events and one for the metrics
    (machine-time keys left out), and one for the search sets where the run in ``out_dir`` has them."""
    out = {f"{name}.{col}": column_digest(values) for name, cols in sorted(rec.streams.items())
           for col, values in sorted(cols.items())}
    out["events"] = _digest_bytes(json.dumps(_scrub(rec.events), sort_keys=True).encode())
    out["metrics"] = _digest_bytes(json.dumps(_scrub(rec.metrics), sort_keys=True).encode())
    sets = Path(out_dir) / "search_sets.jsonl.gz"
    if sets.exists():
        out["search_sets"] = _digest_bytes(gzip.decompress(sets.read_bytes()))
    return out


def record_values(rec: RunRecord) -> dict[str, Any]:
    """The summary of every stream column of the run record ``rec``, and its events and metrics flattened
    (machine-time keys left out), for the check on another machine (:mod:`tests.numeric_record`)."""
    return {"streams": {f"{name}.{col}": summarise(values) for name, cols in sorted(rec.streams.items())
                        for col, values in sorted(cols.items())},
            "events": flatten(_scrub(rec.events)), "metrics": flatten(_scrub(rec.metrics))}


def run_case(name: str, seed: int, out_dir: Path) -> tuple[dict[str, str], dict[str, Any]]:
    """Digests and summaries (:func:`record_digest`, :func:`record_values`) of a short run of world ``name``."""
    from simulator.api import run
    from simulator.runrecord import load_run

    res = run(name, duration=DURATION_S, seed=seed, out_dir=out_dir)
    if res.status != "completed":
        raise RuntimeError(f"{name} seed {seed}: {res.status} ({res.error})")
    rec = load_run(out_dir)
    return record_digest(rec, out_dir), record_values(rec)


def load_golden() -> dict[str, Any]:
    """The golden file: ``machine`` (the key of the machine that wrote it), ``records`` (digests per case) and
    ``values`` (summaries per case)."""
    data = json.loads(GOLDEN_FILE.read_text(encoding="utf-8"))
    data["values"] = json.loads(gzip.decompress(VALUES_FILE.read_bytes())) if VALUES_FILE.exists() else {}
    return data


def compare(golden: dict[str, Any], key: str, digests: dict[str, str], values: dict[str, Any]) -> tuple[str, list[str]]:
    """How case ``key`` is checked here (``"bits"`` on the machine that wrote the file, ``"tolerance"`` elsewhere,
    ``"unchecked"`` for a world of :data:`BITS_ONLY` elsewhere) and what differs."""
    if golden.get("machine") == machine_key():
        want = golden["records"].get(key, {})
        return "bits", sorted(k for k in set(want) | set(digests) if want.get(k) != digests.get(k))
    if key.split("/")[0] in BITS_ONLY:
        return "unchecked", []
    want = golden["values"].get(key, {})
    diff = differences(want.get("streams", {}), values["streams"])
    for part in ("events", "metrics"):
        diff += [f"{part}:{k}" for k in differences(want.get(part, {}), values[part])]
    return "tolerance", diff


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="rewrite golden_records.json (else compare and report); "
                    "with --only, only those worlds' records")
    ap.add_argument("--only", default="", help="only worlds whose name contains this")
    args = ap.parse_args(argv)
    records, values = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, seed in cases():
            if args.only not in name:
                continue
            key = f"{name}/{seed}"
            records[key], values[key] = run_case(name, seed, Path(tmp) / f"{name}-{seed}")
            print(f"{key}: {len(records[key])} digests", file=sys.stderr)
    golden = load_golden()
    if args.write:  # with --only, the other worlds' records are kept as they are, and must hold on this machine
        if args.only and golden.get("machine") != machine_key():
            print("--write --only keeps the other worlds' digests, which another machine wrote: rewrite them all "
                  "here (no --only)", file=sys.stderr)
            return 2
        kept_keys = {k for k in golden["records"] if args.only and k not in records}
        data = {"duration_s": DURATION_S, "machine": machine_key(),
                "records": {**{k: golden["records"][k] for k in kept_keys}, **records}}
        kept = {**{k: v for k, v in golden["values"].items() if k in kept_keys}, **values}
        GOLDEN_FILE.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        VALUES_FILE.write_bytes(gzip.compress(json.dumps(kept, sort_keys=True).encode(), mtime=0))
        return 0
    bad = 0
    for key in records:
        how, diff = compare(golden, key, records[key], values[key])
        bad += bool(diff)
        print(f"{key} ({how}): {'ok' if not diff else 'DIFFERS in ' + ', '.join(diff)}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
