"""Standoff and phase errors of a recorded run, over the whole run and in steady state (after the approach).

The run metrics (``uavs.<id>.standoff_error_mean_m``, ``phase_error_mean_deg``) average from the first agent step,
so they include the approach, where the UAVs are still reaching their orbit and slots. Here both errors are computed
from the run's truth records (UAVs and car at the record rate) and averaged over every record and over
``t >= steady_start(duration)`` separately.

Steady-state rule: from :data:`STEADY_START_S` (30 s) on, or from a quarter of a shorter run (quick runs). 30 s is
fixed in advance, not read off the errors: it is a quarter of the 120 s runs and about 2.5 times the 12.5 s the paper's
orbit rate (v0 / r_d = 0.08 rad/s) needs to turn a UAV through one radian.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["STEADY_START_S", "Guidance", "steady_start", "guidance_errors"]

STEADY_START_S = 30.0


def steady_start(duration_s: float) -> float:
    """Time (s) from which a run of ``duration_s`` counts as steady state."""
    return min(STEADY_START_S, 0.25 * duration_s)


@dataclass(frozen=True)
class Guidance:
    """Mean standoff error (m, over the UAVs) and phase error (deg) over the whole run and in steady state."""

    standoff: float
    phase: float
    standoff_ss: float
    phase_ss: float


def guidance_errors(run_dir: str | Path, standoff_m: float, vehicle: int = 0) -> Guidance:
    """:class:`Guidance` of the run in ``run_dir``: ``|horizontal distance to the car − standoff_m|`` per UAV and
    ``|angular gap around the car − 360°/n|`` (mean over the gaps), from the truth records."""
    from simulator.runrecord import load_stream

    ts = Path(run_dir) / "timeseries"
    u = load_stream(ts / "uav_truth")
    v = load_stream(ts / "vehicle_truth")
    own = v["vehicle"] == vehicle
    car = {int(k): (x, y) for k, x, y in zip(v["tick"][own], v["x"][own], v["y"][own], strict=True)}
    uavs = sorted(set(int(i) for i in u["uav"]))
    ticks = sorted(set(int(k) for k in u["tick"]) & set(car))
    if not ticks or len(uavs) < 2:
        nan = float("nan")
        return Guidance(nan, nan, nan, nan)
    row = {k: j for j, k in enumerate(ticks)}
    pos = np.full((len(uavs), len(ticks), 2), np.nan)
    t = np.full(len(ticks), np.nan)
    for k, i, tt, x, y in zip(u["tick"], u["uav"], u["t"], u["x"], u["y"], strict=True):
        j = row.get(int(k))
        if j is not None:
            pos[uavs.index(int(i)), j] = (x, y)
            t[j] = tt
    c = np.array([car[k] for k in ticks])
    rel = pos - c[None]
    standoff = np.abs(np.linalg.norm(rel, axis=-1) - standoff_m)  # (n_uavs, M)
    ang = np.sort(np.arctan2(rel[..., 1], rel[..., 0]), axis=0)
    gaps = np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi]), axis=0)
    phase = np.degrees(np.mean(np.abs(gaps - 2 * np.pi / len(uavs)), axis=0))
    ss = t >= t[0] + steady_start(float(t[-1] - t[0]))
    mean = lambda x: float(np.nanmean(x)) if np.isfinite(x).any() else float("nan")  # noqa: E731
    return Guidance(standoff=mean(standoff), phase=mean(phase), standoff_ss=mean(standoff[:, ss]),
                    phase_ss=mean(phase[ss]))
