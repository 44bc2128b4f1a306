"""The Python API: run a world and get truth, estimates and metrics back as arrays — for tests of autonomy modules.

>>> from simulator.api import run
>>> result = run("road_standoff", duration=20, seed=3, estimator=MyEstimator)   # doctest: +SKIP
>>> result.metrics["targets"]["car1"]["uav1"]["position_rmse_m"]                  # doctest: +SKIP
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from simulator.engine import RunOptions, run_world
from simulator.runrecord import RunRecord, load_run
from worlds.loader import LoadedWorld, load_world

__all__ = ["RunResult", "run"]


@dataclass
class RunResult:
    """A finished (or interrupted) run.

    Attributes
    ----------
    status : str
        ``completed``, ``interrupted``, ``diverged`` (the physics blew up: :mod:`simulator.watchdog`) or ``error``.
    error : str | None
        The exception, when ``status == "error"``; what diverged, when ``status == "diverged"``.
    out_dir : Path
        The run directory.
    metrics : dict
        Contents of ``metrics.json``.
    record : RunRecord
        The whole record: ``record.streams["uav_truth"]``, ``["vehicle_truth"]``, ``["estimates"]``, ``["commands"]``,
        ``["detections"]`` (dicts of numpy columns), ``record.events``.
    """

    status: str
    error: str | None
    out_dir: Path
    metrics: dict[str, Any]
    record: RunRecord

    def stream(self, name: str, **where: int) -> dict[str, np.ndarray]:
        """Columns of stream ``name``, optionally filtered, e.g. ``stream("estimates", uav=0)``."""
        data = self.record.stream(name)
        mask = np.ones(len(next(iter(data.values()))), dtype=bool)
        for col, value in where.items():
            mask &= data[col] == value
        return {k: v[mask] for k, v in data.items()}

    def target_truth_at(self, t: np.ndarray, vehicle: int = 0) -> np.ndarray:
        """True (x, y) of ground vehicle ``vehicle`` at times ``t`` (linear interpolation of the record), (len(t),
        2)."""
        vt = self.stream("vehicle_truth", vehicle=vehicle)
        t = np.asarray(t, dtype=float)
        return np.stack([np.interp(t, vt["t"], vt["x"]), np.interp(t, vt["t"], vt["y"])], axis=-1)


Factory = Callable[[int, Any], Any] | type


def _factory(obj: Factory | None) -> Callable[[int, Any], Any] | None:
    if obj is None:
        return None
    if isinstance(obj, type):
        return lambda i, spec: obj()
    return obj


def run(world: str | Path | LoadedWorld, *, duration: float | None = None, seed: int | None = None,
        overrides: Sequence[str] = (), out_dir: str | Path | None = None, estimator: Factory | None = None,
        guidance: Factory | None = None, progress: bool = False, plots: bool = False) -> RunResult:
    """Run a world and return its record.

    Parameters
    ----------
    world : str | Path | LoadedWorld
        A shipped world's name, a path to a world file, or an already loaded world.
    duration, seed : optional
        Override ``sim.duration_s`` (s) and ``sim.seed``.
    overrides : sequence of str
        ``key.path=value`` strings, as ``--set`` on the command line.
    out_dir : path, optional
        Run directory (default: a new temporary directory). An earlier run there is moved aside to ``<out_dir>.1``
        (``.2`` ...); a non-empty directory that is not a run's is refused (:mod:`simulator.rundir`).
    estimator, guidance : class or callable, optional
        A user's estimator / guidance law for every UAV: a class (instantiated once per UAV with no arguments) or a
        factory ``f(uav_index, uav_spec)``. An estimator needs ``step(t, detections) -> TargetEstimate | None``; a
        guidance law ``command(own, target, teammates, t) -> UnicycleSetpoint | VelocitySetpoint`` (see
        :mod:`autonomy.agent`).
    """
    loaded = world if isinstance(world, LoadedWorld) else load_world(world, list(overrides))
    out = Path(out_dir) if out_dir is not None else Path(tempfile.mkdtemp(prefix="skytrack-"))
    outcome = run_world(loaded, RunOptions(duration_s=duration, seed=seed, out_dir=out, progress=progress,
                                           plots=plots, estimator_factory=_factory(estimator),
                                           guidance_factory=_factory(guidance)))
    return RunResult(status=outcome.status, error=outcome.error, out_dir=out, metrics=outcome.metrics,
                     record=load_run(out))
