"""The campaign directory's journal: ``campaign.json`` (parameters) and the append-only ``campaign.jsonl`` (one line per
finished run), written by the parent process only and flushed line by line, so a campaign killed at any moment resumes
with every finished run kept and no run recorded twice.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any

from simulator.campaign.config import CampaignError, CampaignParams, RunReport, run_dir_name
from simulator.record import atomic_write_text, json_default

__all__ = ["CampaignJournal"]

PARAMS_FILE = "campaign.json"
JOURNAL_FILE = "campaign.jsonl"


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
    A torn last line (the process was killed while writing it) is cut off on open; a run journaled twice (which the
    parent never does) would count once, the first record winning.
    """

    def __init__(self, out_dir: Path, params: CampaignParams) -> None:
        self.out_dir = Path(out_dir)
        self.params = params
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self._check_params()
        self.path = self.out_dir / JOURNAL_FILE
        self.reports: dict[int, RunReport] = self._read()
        self._file = open(self.path, "a", encoding="utf-8")

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
        else:
            if (self.out_dir / JOURNAL_FILE).exists():
                raise CampaignError(f"{self.out_dir} has {JOURNAL_FILE} but no {PARAMS_FILE}: not resuming blindly")
            atomic_write_text(stored_path, json.dumps(self.params.to_json(), indent=2) + "\n")

    def _read(self) -> dict[int, RunReport]:
        if not self.path.exists():
            return {}
        data = self.path.read_bytes()
        end = data.rfind(b"\n") + 1
        if end < len(data):  # a torn final line from a killed writer: drop it, keep every complete line
            with open(self.path, "r+b") as f:
                f.truncate(end)
        reports: dict[int, RunReport] = {}
        for n, line in enumerate(data[:end].decode("utf-8").splitlines(), start=1):
            if not line.strip():
                continue
            try:
                rep = RunReport.from_json(json.loads(line))
            except (json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
                raise CampaignError(f"{self.path}:{n}: unreadable run record ({exc})") from None
            if not 0 <= rep.index < self.params.runs:
                raise CampaignError(f"{self.path}:{n}: run index {rep.index} outside 0..{self.params.runs - 1}")
            reports.setdefault(rep.index, rep)
        return reports

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
        """Append one finished run and flush it to disk (``interrupted`` runs are not recorded: they run again)."""
        if not report.finished:
            return
        if report.index in self.reports:
            raise CampaignError(f"run {report.index} is already recorded in {self.path}")
        self._file.write(json.dumps(report.to_json(), default=json_default, allow_nan=True) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())
        self.reports[report.index] = report

    def ordered(self) -> list[RunReport]:
        """All recorded runs by index."""
        return [self.reports[i] for i in sorted(self.reports)]

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> CampaignJournal:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
