"""Closed-loop speed against the physics floor: a world's real-time factor over that of its bodies stepped by
PyBullet alone.

The floor of a world is the real-time factor of the same scene — its buildings, road surface, UAV bodies, cars and
decoys, built by the run's own assembly (:func:`simulator.prepare.build_assembly`) — stepped by
``p.stepSimulation`` alone for the same number of ticks: no drivers, controllers, sensors, autonomy or record. The
cars' motors stay at the targets the assembly leaves (braked at rest: in ``road_standoff`` a step costs the same
73 us with the car driven straight at 8 m/s), kinematic cars' boxes stay where they spawned, and each UAV is held up
by one constant force (its weight, one ``applyExternalForce`` per UAV and tick, the least PyBullet needs to keep the
same bodies in the air). The world runs first (:func:`simulator.engine.run_world`, setup included, as ``skytrack run``
would), then its floor, in the same call, so both see the same load of a shared machine.

The ratio world / floor is 1 when everything the simulator adds to PyBullet's step costs nothing; 0.5 when it costs
as much as the step. The headline figures are per second of this process's CPU time (``time.process_time``: waiting
for a core on a shared machine is not counted), each with its wall-time twin. Note that the floor steps in a tight
loop, where Bullet's data stay in the CPU caches; between the run loop's other phases the same step costs ≈ 1.5x more
(``road_standoff``, 60 s: 67 us per step in the floor's loop, 104 us with the vehicles' controllers and drivers
between the steps, 107 us with 8 MB of unrelated memory traffic between them instead).
"""

from __future__ import annotations

import statistics
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import pybullet as p

from simulator.bench.registry import BenchRecord, benchmark

__all__ = ["FloorMeasure", "floor_seconds", "measure_against_floor"]

REPEATS = 3
TARGET_RATIO = 0.5
HELSINKI_WINDOW_S = 30.0  # simulated seconds of helsinki_chase per repeat (a 120 s run takes minutes here)


@dataclass(frozen=True, kw_only=True)
class FloorMeasure:
    """One world run and its floor over the same window.

    Attributes
    ----------
    sim_s : float
        Simulated seconds of both (s).
    world_cpu_s, world_wall_s : float
        CPU and wall time of the whole run, setup included (s).
    setup_wall_s : float
        Wall time of the run's setup (world, solvers, scene) (s).
    floor_cpu_s, floor_wall_s : float
        CPU and wall time of the floor's stepping, its assembly excluded (s).
    phases_wall_s : dict[str, float]
        The run's ``wall_time_breakdown_s`` (setup, each phase of the tick, other) (s).
    """

    sim_s: float
    world_cpu_s: float
    world_wall_s: float
    setup_wall_s: float
    floor_cpu_s: float
    floor_wall_s: float
    phases_wall_s: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("sim_s", "world_cpu_s", "world_wall_s", "floor_cpu_s", "floor_wall_s"):
            if not getattr(self, name) > 0:
                raise ValueError(f"FloorMeasure.{name} must be > 0 s, got {getattr(self, name)!r}")

    @property
    def world_cpu_rtf(self) -> float:
        return self.sim_s / self.world_cpu_s

    @property
    def world_wall_rtf(self) -> float:
        return self.sim_s / self.world_wall_s

    @property
    def floor_cpu_rtf(self) -> float:
        return self.sim_s / self.floor_cpu_s

    @property
    def floor_wall_rtf(self) -> float:
        return self.sim_s / self.floor_wall_s

    @property
    def cpu_ratio(self) -> float:
        """World over floor real-time factor, per CPU second: the floor's CPU time over the world's."""
        return self.world_cpu_rtf / self.floor_cpu_rtf

    @property
    def wall_ratio(self) -> float:
        return self.world_wall_rtf / self.floor_wall_rtf

    @property
    def loop_wall_ratio(self) -> float:
        """The wall-time ratio without the run's setup (the loop's real-time factor over the floor's)."""
        return self.floor_wall_s / max(self.world_wall_s - self.setup_wall_s, 1e-9)

    @property
    def ceiling_wall_ratio(self) -> float:
        """The wall-time ratio the run would make if everything but its setup and PyBullet's step inside its loop (the
        ``physics`` phase) cost nothing: the floor over those two. The step costs more inside the loop than in the
        floor's tight loop (module docstring), so this is what no faster skytrack code can pass."""
        return self.floor_wall_s / max(self.setup_wall_s + self.phases_wall_s.get("physics", 0.0), 1e-9)


def floor_seconds(loaded: object, duration_s: float, seed: int | None = None) -> tuple[float, float]:
    """(CPU s, wall s) of stepping the assembled scene of world ``loaded`` (a
    :class:`~worlds.loader.LoadedWorld`) by PyBullet alone for ``duration_s`` simulated seconds (see the module)."""
    from simulator.clock import Clock
    from simulator.engine import RunOptions
    from simulator.prepare import build_assembly, prepare
    from simulator.record import RunRecorder
    from simulator.seeding import RunSeeds
    from simulator.streams import STREAMS

    world = loaded.world
    clock = Clock(physics_hz=world.sim.physics_hz)
    seeds = RunSeeds(world.sim.seed if seed is None else seed)
    n_ticks = clock.ticks(duration_s)
    with tempfile.TemporaryDirectory() as tmp:
        prepared = prepare(loaded, clock, seeds, RunOptions(out_dir=Path(tmp), plots=False))
        recorder = RunRecorder(Path(tmp) / "floor", schemas=STREAMS)
        assembly = build_assembly(prepared, seeds, recorder)
        try:
            cid = assembly.scene.client
            quads = assembly.quads
            weight = world.environment.gravity
            held = [] if quads is None else [(int(b), (0.0, 0.0, a.mass * weight))
                                             for b, a in zip(quads.body_ids, quads.airframes, strict=True)]
            force, step, link, origin = p.applyExternalForce, p.stepSimulation, p.LINK_FRAME, (0.0, 0.0, 0.0)
            c0, w0 = time.process_time(), time.perf_counter()
            for _ in range(n_ticks):
                for body, f in held:
                    force(body, -1, f, origin, link, physicsClientId=cid)
                step(physicsClientId=cid)
            return time.process_time() - c0, time.perf_counter() - w0
        finally:
            assembly.close()
            recorder.close()


def measure_against_floor(world: str, overrides: tuple[str, ...] = (), duration_s: float | None = None,
                          seed: int | None = None) -> FloorMeasure:
    """Run the shipped (or file) world ``world`` with ``overrides`` for ``duration_s`` (its own duration if None),
    then its floor over the same window."""
    from simulator.engine import RunOptions, run_world
    from worlds.loader import load_world

    loaded = load_world(world, list(overrides))
    duration = loaded.world.sim.duration_s if duration_s is None else duration_s
    with tempfile.TemporaryDirectory() as tmp:
        options = RunOptions(duration_s=duration, seed=seed, out_dir=Path(tmp) / "run", plots=False)
        c0, w0 = time.process_time(), time.perf_counter()
        outcome = run_world(loaded, options)
        world_cpu, world_wall = time.process_time() - c0, time.perf_counter() - w0
    if outcome.status != "completed":
        raise RuntimeError(f"{world} did not complete: {outcome.error}")
    floor_cpu, floor_wall = floor_seconds(loaded, duration, seed)
    return FloorMeasure(sim_s=float(outcome.metrics["sim_time_s"]), world_cpu_s=world_cpu, world_wall_s=world_wall,
                        setup_wall_s=float(outcome.metrics["wall_time_breakdown_s"]["setup"]),
                        floor_cpu_s=floor_cpu, floor_wall_s=floor_wall,
                        phases_wall_s=dict(outcome.metrics["wall_time_breakdown_s"]))


def floor_records(prefix: str, runs: list[FloorMeasure]) -> list[BenchRecord]:
    """The records of repeated measures of one world: medians of the real-time factors, and of the per-repeat ratios
    (so the load of a shared machine cancels within each pair)."""
    med = statistics.median

    def rec(name: str, values: list[float], target: float | None = None) -> BenchRecord:
        return BenchRecord(name=f"{prefix}_{name}", value=float(med(values)), unit="x", target=target, better="higher")

    return [rec("floor_ratio", [r.cpu_ratio for r in runs], TARGET_RATIO),
            rec("floor_ratio_wall", [r.wall_ratio for r in runs]),
            rec("floor_loop_ratio_wall", [r.loop_wall_ratio for r in runs]),
            rec("floor_ratio_ceiling_wall", [r.ceiling_wall_ratio for r in runs]),
            rec("floor_cpu_rtf", [r.floor_cpu_rtf for r in runs]),
            rec("floor_wall_rtf", [r.floor_wall_rtf for r in runs]),
            rec("cpu_rtf", [r.world_cpu_rtf for r in runs]),
            rec("wall_rtf", [r.world_wall_rtf for r in runs])]


def _produces(prefix: str) -> tuple[str, ...]:
    return tuple(f"{prefix}_{k}" for k in ("floor_ratio", "floor_ratio_wall", "floor_loop_ratio_wall",
                                           "floor_ratio_ceiling_wall", "floor_cpu_rtf", "floor_wall_rtf", "cpu_rtf",
                                           "wall_rtf"))


@benchmark("road_standoff_floor", produces=_produces("road_standoff"))
def bench_road_standoff_floor() -> list[BenchRecord]:
    """Paper 002's ``road_standoff`` (2 radar UAVs, EKF, fusion, NMPC; one physics car in a town; 120 s, seed 1)
    against its physics floor, 3 repeats: ``road_standoff_floor_ratio`` (CPU time; target >= 0.5) and its wall-time
    twin, the floor's and the world's real-time factors. ``..._floor_loop_ratio_wall``: without the run's setup.
    ``..._floor_ratio_ceiling_wall``: the most the ratio could be if all but the setup and PyBullet's step in the
    loop cost nothing."""
    return floor_records("road_standoff", [measure_against_floor("road_standoff") for _ in range(REPEATS)])


@benchmark("helsinki_chase_floor", produces=_produces("helsinki_chase"))
def bench_helsinki_chase_floor() -> list[BenchRecord]:
    """``helsinki_chase`` without its cameras (3 radar UAVs tracking every car, ECUKF, covariance intersection, NMPC
    among buildings; one physics car among 50 kinematic traffic cars in Helsinki), as ``helsinki_chase_rtf`` runs it,
    for its first ``HELSINKI_WINDOW_S`` simulated seconds, against its physics floor over that window, 3 repeats:
    ``helsinki_chase_floor_ratio`` (CPU time; target >= 0.5) with the same figures as ``road_standoff_floor``."""
    from simulator.bench.bench_core import _radar_only

    overrides = _radar_only("helsinki_chase")
    return floor_records("helsinki_chase", [measure_against_floor("helsinki_chase", overrides, HELSINKI_WINDOW_S)
                                            for _ in range(REPEATS)])
