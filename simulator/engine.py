"""The run loop: one tick = one physics step, in the order of DESIGN.md.

1. vehicles apply actuator forces from their controllers' last outputs;
2. PyBullet steps;
3. low-level controllers run at their rates on the true vehicle state;
4. sensors due at this tick measure from ground truth (occlusion raycasts, noise, Pd, clutter);
5. agents due at this tick take the detections that have arrived, estimate, plan and hand set-points to their UAV;
6. the recorder stores truth, estimates, set-points and events, and flushes to disk every ``sim.flush_every_s``.

Every run starts from a clean directory (an earlier run there is moved aside: :mod:`simulator.rundir`). Once the
directory exists, however the run ends — completed, ``interrupted`` (Ctrl-C, SIGTERM: :mod:`simulator.interrupts`),
``diverged`` (the physics blew up: :mod:`simulator.watchdog`) or ``error`` (an exception, before or during the loop) —
it flushes what it has, writes its metrics, and ends ``events.jsonl`` with a ``run_end`` event saying how it ended.
"""

from __future__ import annotations

import json
import math
import numbers
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from simulator.prepare import build_assembly, prepare
from simulator.provenance import source_fingerprint
from simulator.clock import MAX_DURATION_S, Clock
from simulator.plots import write_geometry, write_plots
from simulator.interrupts import DeferredInterrupts, caused_by_interrupt
from simulator.record import RunRecorder
from simulator.rundir import fresh_run_dir
from simulator.seeding import RunSeeds
from simulator.streams import STREAMS
from simulator.summary import MetricsTracker
from simulator.tick import Assembly
from simulator.watchdog import Divergence, world_watchdog
from worlds.loader import LoadedWorld

__all__ = ["RunOptions", "RunOutcome", "run_world"]


@dataclass(frozen=True, kw_only=True)
class RunOptions:
    """How to run a loaded world.

    Attributes
    ----------
    duration_s : float | None
        Simulated seconds; None = the world's ``sim.duration_s``.
    seed : int | None
        Run seed; None = the world's ``sim.seed``.
    out_dir : Path | None
        Run directory; None = a temporary directory is not made: the caller must give one.
    progress : bool
        Show a progress bar.
    plots : bool
        Write PNG plots at the end.
    estimator_factory, guidance_factory : callable | None
        ``f(uav_index, uav_spec) -> object`` building a user's estimator / guidance for each UAV in code (they take
        precedence over the world file's autonomy settings).
    on_tick : callable | None
        ``f(tick)`` called after every tick (tests use it to interrupt a run).
    notify : callable | None
        ``f(text)`` told what the run did to its directory (an earlier run moved aside); None: said nowhere.
    """

    duration_s: float | None = None
    seed: int | None = None
    out_dir: Path | None = None
    progress: bool = False
    plots: bool = True
    estimator_factory: Callable[[int, Any], Any] | None = None
    guidance_factory: Callable[[int, Any], Any] | None = None
    on_tick: Callable[[int], None] | None = None
    notify: Callable[[str], None] | None = None

    def __post_init__(self) -> None:
        d = self.duration_s
        if d is not None and not (isinstance(d, numbers.Real) and math.isfinite(d) and 0 < d <= MAX_DURATION_S):
            raise ValueError(f"RunOptions.duration_s must be a finite number of seconds in (0, {MAX_DURATION_S:g}], "
                             f"got {d!r}")
        seed = self.seed
        if seed is not None and (not isinstance(seed, numbers.Integral) or isinstance(seed, bool) or seed < 0):
            raise ValueError(f"RunOptions.seed must be an integer >= 0, got {self.seed!r}")
        if self.out_dir is None:
            raise ValueError("RunOptions.out_dir is required")


@dataclass
class RunOutcome:
    """How a run ended and where its record is."""

    status: str
    out_dir: Path
    metrics: dict[str, Any]
    error: str | None = None
    ticks: int = 0
    extra: dict[str, Any] = field(default_factory=dict)


def _versions() -> dict[str, str]:
    import importlib.metadata as md

    out = {}
    for pkg in ("skytrack", "pybullet", "numpy", "scipy", "casadi"):
        try:
            out[pkg] = md.version(pkg)
        except md.PackageNotFoundError:
            out[pkg] = "unknown"
    return out


def _breakdown(wall: float, setup_s: float, phases: dict[str, float]) -> dict[str, float]:
    """Where a run's wall time went: ``setup`` (world, solvers, scene), each phase of the tick
    (:data:`simulator.tick.WALL_PHASES`) and ``other`` (metrics, flushes, the run directory, the rest)."""
    out = {"setup": setup_s, **phases}
    out["other"] = max(wall - sum(out.values()), 0.0)
    return {k: round(v, 4) for k, v in out.items()}


def run_world(loaded: LoadedWorld, options: RunOptions) -> RunOutcome:
    """Build the world, run it for the requested duration, and write the run directory.

    Raises
    ------
    WorldError
        Bad input found before the run directory is touched.
    simulator.rundir.RunDirError
        ``options.out_dir`` cannot be used (nothing was written).
    """
    world = loaded.world
    seed = world.sim.seed if options.seed is None else options.seed
    duration = world.sim.duration_s if options.duration_s is None else options.duration_s
    clock = Clock(physics_hz=world.sim.physics_hz)
    n_ticks = clock.ticks(duration)
    out = Path(options.out_dir)
    seeds = RunSeeds(seed)
    wall0 = time.perf_counter()
    prepared = prepare(loaded, clock, seeds, options)  # bad input fails here, before PyBullet and the run directory
    moved = fresh_run_dir(out)
    if moved is not None and options.notify is not None:
        options.notify(f"{out} held an earlier run: moved it to {moved}")
    recorder = RunRecorder(out, schemas=STREAMS)

    status, error, tick, diverged = "error", None, 0, None
    assembly: Assembly | None = None
    tracker = MetricsTracker(seed=seed, physics_hz=clock.physics_hz)
    bar = None
    setup_s = 0.0
    try:  # from here on, however the run ends, the record ends with run_end
        resolved = world.model_dump(mode="json")
        resolved["sim"]["seed"] = seed
        resolved["sim"]["duration_s"] = duration
        recorder.write_text("world.yaml",
                            f"# resolved from {loaded.path}\n" + yaml.safe_dump(resolved, sort_keys=False))
        recorder.write_json("run.json", {"world": world.name, "source": str(loaded.path), "seed": seed,
                                         "duration_s": duration, "physics_hz": clock.physics_hz,
                                         "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "versions": _versions(),
                                         "code": source_fingerprint()})
        recorder.event("run_start", 0, 0.0, world=world.name, seed=seed, duration_s=duration)
        write_geometry(out, prepared.geometry.buildings, prepared.geometry.network)
        assembly = build_assembly(prepared, seeds, recorder)
        assembly.watchdog = world_watchdog(world)
        tracker.attach(assembly)
        setup_s = time.perf_counter() - wall0
        recorder.event("scene_built", 0, 0.0, build_s=round(setup_s, 4),
                       uavs=len(assembly.uav_ids), ground_vehicles=len(assembly.car_ids),
                       buildings=len(assembly.buildings))
        flush_every = clock.ticks(world.sim.flush_every_s)
        if options.progress and n_ticks > clock.physics_hz * 2:
            from tqdm import tqdm

            bar = tqdm(total=n_ticks, unit="tick", unit_scale=True, desc=world.name, leave=False)
        with DeferredInterrupts() as interrupts:  # a signal ends the run between two ticks, not inside a solver
            for tick in range(1, n_ticks + 1):
                assembly.step(tick)
                tracker.observe(tick, assembly)
                if tick % flush_every == 0:  # partial metrics unsynced: an fsync takes milliseconds (~4 % of a run)
                    recorder.flush(tracker.metrics(clock.time(tick), time.perf_counter() - wall0, complete=False),
                                   sync=False)
                if bar is not None and tick % 240 == 0:
                    bar.update(240)
                if options.on_tick is not None:
                    options.on_tick(tick)
                interrupts.check()
        status = "completed"
    except KeyboardInterrupt:
        status = "interrupted"
    except Divergence as exc:
        status, error, diverged = "diverged", str(exc), exc.fields()
    except Exception as exc:  # recorded, then reported to the caller through the outcome
        if caused_by_interrupt(exc):  # e.g. Ctrl-C inside a compiled solver while it was being built
            status = "interrupted"
        else:
            status, error = "error", f"{type(exc).__name__}: {exc}"
            recorder.event("exception", tick, clock.time(tick), error=error, traceback=traceback.format_exc())
    finally:
        with DeferredInterrupts():  # the record is finished first; a signal meanwhile is raised after it
            if bar is not None:
                bar.close()
            wall = time.perf_counter() - wall0
            sim_time = clock.time(max(tick - (0 if status == "completed" else 1), 0))
            metrics = tracker.metrics(sim_time, wall, complete=True)
            metrics["status"] = status
            if diverged is not None:
                metrics["diverged"] = diverged
            if assembly is not None:
                metrics["wall_time_breakdown_s"] = _breakdown(wall, setup_s, assembly.wall_s)
            recorder.flush(metrics)
            if assembly is not None:
                assembly.close()
            end = {} if diverged is None else {"diverged": diverged}
            recorder.event("run_end", tick, sim_time, status=status, error=error, wall_time_s=round(wall, 3), **end)
            recorder.close()
    if options.plots and tick > 0:
        try:
            write_plots(out)
        except Exception as exc:  # a plot must never hide the run's own outcome
            with open(out / "events.jsonl", "a", encoding="utf-8") as f:
                f.write(json.dumps({"type": "plot_failed", "error": f"{type(exc).__name__}: {exc}"}) + "\n")
    return RunOutcome(status=status, out_dir=out, metrics=metrics, error=error, ticks=tick,
                      extra={} if diverged is None else {"diverged": diverged})
