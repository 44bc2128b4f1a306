"""A campaign run function without physics: writes a small run directory (metrics, run record, one record chunk) as
a real run does, so the campaign's journal and resume can be tested in a second."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from simulator.campaign.config import RunReport, RunTask


def write_run(task: RunTask) -> RunReport:
    out = Path(task.out_dir)
    (out / "timeseries" / "uav_truth").mkdir(parents=True, exist_ok=True)
    metrics = {"targets": {"car1": {"uav1": {"position_error_mean_m": float(task.seed % 1000) / 100.0}}}}
    (out / "metrics.json").write_text(json.dumps(dict(metrics, complete=True)))
    (out / "run.json").write_text(json.dumps({"seed": task.seed}))
    rows = np.zeros(500, dtype=[("tick", "i8"), ("x", "f8")])
    rows["tick"] = np.arange(500)
    rows["x"] = task.seed
    np.save(out / "timeseries" / "uav_truth" / "part-00000.npy", rows)
    return RunReport(index=task.index, seed=task.seed, status="completed", error=None, wall_time_s=0.01,
                     metrics={"targets.car1.uav1.position_error_mean_m": float(task.seed % 1000) / 100.0},
                     run_dir="")
