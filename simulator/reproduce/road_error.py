"""Where a road-following target's estimation error lies: along the road or across it, and how far from a junction.

A road constraint acts directly on the error across the road only, so how much it can cut depends on how the
error splits. These helpers split each estimate's error in the truth's frame: ``along`` (positive ahead of the car) and
``cross`` (positive left of it), and bin the along-road part by the car's distance to the nearer end of its road (its
last or next junction, where a stop-and-go car stands and starts), read from the run's record. Paper 002's report
(:mod:`simulator.reproduce.paper_002`) tabulates them for the unconstrained and the road-constrained filters.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["JUNCTION_BINS", "ErrorSplit", "road_lengths", "split_error", "split_run"]

JUNCTION_BINS = (0.0, 10.0, 35.0, np.inf)
"""Edges (m) of the distance-to-junction bins: at a junction (where the car stops), leaving or nearing it, mid-block."""


@dataclass(frozen=True)
class ErrorSplit:
    """Error components of a set of estimates (m).

    Attributes
    ----------
    n : int
        Number of estimates.
    mean_error : float
        Mean horizontal error.
    along_mean, cross_mean : float
        Mean along-road (positive ahead of the car) and across-road (positive left) error: the biases.
    along_rms, cross_rms : float
        Root mean square of each component.
    along_mean_by_bin : tuple[float, ...]
        Mean along-road error per bin of :data:`JUNCTION_BINS` (NaN where a bin is empty).
    share_by_bin : tuple[float, ...]
        Fraction of the estimates in each bin.
    """

    n: int
    mean_error: float
    along_mean: float
    cross_mean: float
    along_rms: float
    cross_rms: float
    along_mean_by_bin: tuple[float, ...]
    share_by_bin: tuple[float, ...]


def split_error(est_xy: np.ndarray, truth_xy: np.ndarray, truth_yaw: np.ndarray,
                junction_distance: np.ndarray) -> ErrorSplit:
    """Split the errors ``est_xy − truth_xy`` (N, 2) m into the truth's heading frame ``truth_yaw`` (N,) rad and bin
    them by ``junction_distance`` (N,) m."""
    d = np.asarray(est_xy, dtype=float) - np.asarray(truth_xy, dtype=float)
    c, s = np.cos(truth_yaw), np.sin(truth_yaw)
    along, cross = d[:, 0] * c + d[:, 1] * s, -d[:, 0] * s + d[:, 1] * c
    jd = np.asarray(junction_distance, dtype=float)
    by_bin, share = [], []
    for lo, hi in zip(JUNCTION_BINS[:-1], JUNCTION_BINS[1:], strict=True):
        k = (jd >= lo) & (jd < hi)
        by_bin.append(float(along[k].mean()) if k.any() else float("nan"))
        share.append(float(k.mean()) if len(k) else float("nan"))
    return ErrorSplit(n=len(along), mean_error=float(np.hypot(d[:, 0], d[:, 1]).mean()),
                      along_mean=float(along.mean()), cross_mean=float(cross.mean()),
                      along_rms=float(np.sqrt(np.mean(along ** 2))), cross_rms=float(np.sqrt(np.mean(cross ** 2))),
                      along_mean_by_bin=tuple(by_bin), share_by_bin=tuple(share))


def road_lengths(geometry: Path) -> dict[str, float]:
    """Length (m) of every road of a run's ``geometry.npz`` (its centre-line polyline, sampled every 5 m: a little
    short on curves)."""
    g = np.load(geometry)
    xy, off = g["road_xy"], g["road_offsets"]
    return {str(rid): float(np.linalg.norm(np.diff(xy[off[i]:off[i + 1]], axis=0), axis=1).sum())
            for i, rid in enumerate(g["road_ids"])}


def split_run(run_dir: Path, stream: str = "fused_estimates") -> ErrorSplit | None:
    """:func:`split_error` of the valid estimates of ``stream`` (every UAV's) in a run directory, against the
    tracked ground vehicle's truth (``target_index`` of the metrics) at the nearest recorded time; ``None`` when the
    run has no such estimates or truth. Reads only those two streams and the metrics (a third of loading the whole
    record)."""
    from simulator.runrecord import load_stream

    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise FileNotFoundError(f"no run directory at {run_dir}")
    est, truth = (load_stream(run_dir / "timeseries" / name) for name in (stream, "vehicle_truth"))
    if not est or not truth:
        return None
    metrics_path = run_dir / "metrics.json"
    metrics = json.loads(metrics_path.read_text()) if metrics_path.exists() else {}
    sel = truth["vehicle"] == int(metrics.get("target_index", 0) or 0)
    truth = {k: v[sel] for k, v in truth.items()}
    ok = est["valid"].astype(bool)
    if not ok.any() or len(truth["t"]) == 0:
        return None
    t, tt = est["t"][ok], truth["t"]
    i = np.zeros(len(t), dtype=int)
    if len(tt) > 1:  # the nearest truth sample
        j = np.clip(np.searchsorted(tt, t), 1, len(tt) - 1)
        i = np.where(np.abs(tt[j - 1] - t) <= np.abs(tt[j] - t), j - 1, j)
    lengths = road_lengths(run_dir / "geometry.npz")
    s = truth["s"][i]
    to_end = np.maximum(np.array([lengths.get(str(r), np.inf) for r in truth["road"][i]]) - s, 0.0)
    return split_error(np.column_stack([est["x"][ok], est["y"][ok]]), np.column_stack([truth["x"][i], truth["y"][i]]),
                       truth["yaw"][i], np.minimum(np.maximum(s, 0.0), to_end))
