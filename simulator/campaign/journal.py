"""The campaign directory's journal: ``campaign.json`` (parameters) and the append-only ``campaign.jsonl`` (one line per
finished run), written by the parent process only and flushed line by line, so a campaign killed at any moment resumes
with every finished run kept and no run recorded twice.

The journal and the run directories are untrusted on resume: a line that cannot be read (a torn last line, garbage,
a run index outside the campaign) is dropped with a warning and its run runs again, and every journaled run whose
stored files are damaged (:mod:`simulator.campaign.verify`) runs again too; its new line, appended later, supersedes
the old one.

One process at a time: the journal holds an exclusive lock on ``campaign.lock`` while open (released by the kernel when
the process dies, so it never goes stale). Two processes running the same campaign directory would both run a pending
run into the same run directory, each moving the other's aside, and journal it twice; the second is refused instead.
"""

from __future__ import annotations

import dataclasses
import errno
import json
import logging
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from simulator.campaign.config import CampaignError, CampaignParams, RunReport, run_dir_name
from simulator.campaign.verify import damage, manifest
from simulator.record import atomic_write_text, json_default

__all__ = ["CampaignJournal", "QuietDrop", "exclusive_lock", "read_jsonl"]

_LOG = logging.getLogger(__name__)
REJECTED_FILE = "campaign.rejected.jsonl"
T = TypeVar("T")

PARAMS_FILE = "campaign.json"
JOURNAL_FILE = "campaign.jsonl"
LOCK_FILE = "campaign.lock"

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: no lock (one process per directory is then the user's care)
    fcntl = None  # type: ignore[assignment]


def exclusive_lock(path: Path, error: type[Exception], in_use: str):  # noqa: ANN201 - an open file or None
    """Hold an exclusive lock on the file ``path`` for this process (released when the returned file is closed or the
    process dies, so it never goes stale), or raise ``error(in_use + " (pid …); …")`` naming the holder. ``None``
    where the platform has no ``flock``."""
    if fcntl is None:
        return None
    lock = open(path, "a+", encoding="utf-8")
    try:
        fcntl.flock(lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        lock.seek(0)
        holder = lock.read().strip() or "unknown"
        lock.close()
        if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
            raise
        raise error(f"{in_use} (pid {holder}); wait for it to finish or use another --out") from None
    lock.seek(0)
    lock.truncate()
    lock.write(f"{os.getpid()}\n")
    lock.flush()
    return lock


class QuietDrop(ValueError):
    """Raised by a :func:`read_jsonl` parser to drop a line without a warning of its own (the caller sums them up)."""


def read_jsonl(path: Path, parse: Callable[[Any], T], rejected: Path, what: str, redo: str) -> list[T]:
    """``parse`` of each line of the append-only journal ``path``, in order (``[]`` when there is none).

    The journal is untrusted: a line that is not UTF-8 JSON, or that ``parse`` refuses (``KeyError``, ``TypeError``,
    ``ValueError``), and a last line cut off by a killed writer are dropped with a warning ("unreadable <what> …:
    dropped, its <redo> runs again"), appended to ``rejected`` (kept for inspection, never read) and the journal is
    rewritten atomically without them."""
    if not path.exists():
        return []
    lines = path.read_bytes().split(b"\n")
    torn = lines.pop()  # after the last newline: empty, or a line a killed writer did not finish
    out: list[T] = []
    kept: list[bytes] = []
    dropped: list[tuple[int, bytes, str | None]] = []
    for n, raw in enumerate(lines, start=1):
        if not raw.strip():
            continue
        try:
            value = parse(json.loads(raw.decode("utf-8")))
        except QuietDrop:
            dropped.append((n, raw, None))
            continue
        except (UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
            dropped.append((n, raw, f"unreadable {what} ({type(exc).__name__}: {exc})"))
            continue
        kept.append(raw)
        out.append(value)
    if torn:
        dropped.append((len(lines) + 1, torn, f"its last line was cut off ({len(torn)} bytes, no newline)"))
    for n, _raw, why in dropped:
        if why is not None:
            _LOG.warning("%s:%d: %s: dropped, its %s runs again", path, n, why, redo)
    if dropped:
        with open(rejected, "ab") as f:
            f.writelines(raw + b"\n" for _, raw, _ in dropped)
        atomic_write_text(path, "".join(line.decode("utf-8") + "\n" for line in kept))
    return out


class CampaignJournal:
    """Opens (or creates) a campaign directory and records finished runs.

    Parameters
    ----------
    out_dir : Path
        The campaign directory.
    params : CampaignParams
        This campaign's parameters. If ``campaign.json`` exists they must equal it, else :class:`CampaignError` lists
        what differs.

    Notes
    -----
    Lines that cannot be read are moved to ``campaign.rejected.jsonl`` on open (the journal is rewritten atomically
    without them) and their runs run again. A run journaled twice counts once, the last line winning: a run is
    journaled again only when it was redone because its stored files were damaged.
    """

    def __init__(self, out_dir: Path, params: CampaignParams) -> None:
        self.out_dir = Path(out_dir)
        self.params = params
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self._lock = self._acquire_lock()
        try:
            self._check_params()
            self.path = self.out_dir / JOURNAL_FILE
            self.reports: dict[int, RunReport] = self._read()
            self._file = open(self.path, "a", encoding="utf-8")
        except BaseException:
            if self._lock is not None:
                self._lock.close()
            raise

    def _check_params(self) -> None:
        stored_path = self.out_dir / PARAMS_FILE
        if stored_path.exists():
            try:
                stored = json.loads(stored_path.read_text(encoding="utf-8"))
            except json.JSONDecodeError as exc:
                raise CampaignError(f"{stored_path} is not valid JSON ({exc}); move it away to start afresh") from None
            diffs = self.params.differences(stored)
            if diffs:
                raise CampaignError(f"{self.out_dir} holds a campaign with different parameters; use another --out or "
                                    "the same parameters to resume:\n  " + "\n  ".join(diffs))
            if stored.get("runs") != self.params.runs:  # extended: the stored runs are its first runs
                _LOG.info("%s: extending the campaign from %s to %d runs", self.out_dir, stored.get("runs"),
                          self.params.runs)
                atomic_write_text(stored_path, json.dumps(self.params.to_json(), indent=2) + "\n")
        else:
            if (self.out_dir / JOURNAL_FILE).exists():
                raise CampaignError(f"{self.out_dir} has {JOURNAL_FILE} but no {PARAMS_FILE}: not resuming blindly")
            atomic_write_text(stored_path, json.dumps(self.params.to_json(), indent=2) + "\n")

    def _read(self) -> dict[int, RunReport]:
        def parse(obj: Any) -> RunReport:
            rep = RunReport.from_json(obj)
            if not 0 <= rep.index < self.params.runs:
                raise ValueError(f"run index {rep.index} outside 0..{self.params.runs - 1}")
            return rep

        # a later line is a redo of a damaged run: it wins
        return {rep.index: rep for rep in read_jsonl(self.path, parse, self.out_dir / REJECTED_FILE, "run record",
                                                     "run")}

    def drop_damaged(self) -> dict[int, str]:
        """Forget every journaled run whose stored files are damaged (they run again); returns what is wrong with
        each, by index, after logging it."""
        damaged = {}
        for index, report in sorted(self.reports.items()):
            why = damage(self.run_dir(index), report)
            if why is not None:
                damaged[index] = why
                _LOG.warning("run %d of %s is redone: %s", index, self.out_dir, why)
        for index in damaged:
            del self.reports[index]
        return damaged

    def finished(self) -> set[int]:
        """Indices already recorded (completed or failed); they are not run again."""
        return {i for i, r in self.reports.items() if r.finished}

    def pending(self) -> list[int]:
        """Indices still to run, ascending."""
        done = self.finished()
        return [i for i in range(self.params.runs) if i not in done]

    def run_dir(self, index: int) -> Path:
        """Absolute run directory of run ``index``."""
        return self.out_dir / run_dir_name(index)

    def clear_run_dir(self, index: int) -> None:
        """Remove what a killed or interrupted attempt of run ``index`` left behind."""
        path = self.run_dir(index)
        if path.exists():
            shutil.rmtree(path)

    def record(self, report: RunReport) -> None:
        """Append one finished run, with the sizes and SHA-256 of its run directory's files, and flush it to disk
        (``interrupted`` runs are not recorded: they run again)."""
        if not report.finished:
            return
        if report.index in self.reports:
            raise CampaignError(f"run {report.index} is already recorded in {self.path}")
        report = dataclasses.replace(report, files=manifest(self.run_dir(report.index)))
        self._file.write(json.dumps(report.to_json(), default=json_default, allow_nan=True) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())
        self.reports[report.index] = report

    def ordered(self) -> list[RunReport]:
        """All recorded runs by index."""
        return [self.reports[i] for i in sorted(self.reports)]

    def _acquire_lock(self):  # noqa: ANN202 - an open file or None
        """Lock ``campaign.lock`` for this process, or raise :class:`CampaignError` naming the process holding it."""
        return exclusive_lock(self.out_dir / LOCK_FILE, CampaignError,
                              f"{self.out_dir} is in use by another campaign process")

    def close(self) -> None:
        self._file.close()
        if self._lock is not None:
            self._lock.close()  # closing the file releases the lock
            self._lock = None

    def __enter__(self) -> CampaignJournal:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
