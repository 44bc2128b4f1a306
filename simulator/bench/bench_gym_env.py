"""Benchmark of the Gymnasium environment: learner steps (autonomy steps) per wall-clock second, and the cost of a
reset.

Each figure is the median of 3 episodes of 20 simulated seconds with seed 1, the learner flying a fixed unicycle
set-point (12 m/s, no turn, 60 m) so that every repeat does the same work. A step runs the physics and the rest of the
world from one learner autonomy step to the next: ``road_standoff`` (2 Hz autonomy: 120 ticks at 240 Hz per step, the
other UAV's NMPC included) and ``demo`` (10 Hz: 24 ticks per step, four cars, multi-target tracking). The reset (a
world built from scratch: town, scene, estimators, guidance, run to the first autonomy step) is timed apart. As a
reference measured in the same window, ``gym_env_rtf_over_run`` divides the environment's simulated seconds per wall
second on ``road_standoff`` (resets excluded) by those of ``skytrack run road_standoff`` of the same length and seed
(its setup excluded: ``wall_time_breakdown_s.setup``): what stopping at every learner step, and the learner's own
fixed set-point in place of its NMPC, change against a plain run.
"""

from __future__ import annotations

import time

import numpy as np

from simulator.bench.registry import BenchRecord, benchmark

__all__: list[str] = []

_EPISODE_S = 20.0
_REPEATS = 3
_ACTION = np.array([12.0, 0.0, 60.0], dtype=np.float32)


def _episode(world: str) -> tuple[float, float, float]:
    """(steps per wall second, simulated seconds per wall second, reset seconds) of one episode of ``world``."""
    import gymnasium

    import simulator.envs  # noqa: F401 - registers skytrack/Tracking-v0

    env = gymnasium.make("skytrack/Tracking-v0", world=world, duration=_EPISODE_S)
    try:
        t0 = time.perf_counter()
        _, info = env.reset(seed=1)
        t1 = time.perf_counter()
        steps, done, t_sim0 = 0, False, info["t"]
        while not done:
            _, _, terminated, truncated, info = env.step(_ACTION)
            steps += 1
            done = terminated or truncated
        wall = time.perf_counter() - t1
        return steps / wall, (info["t"] - t_sim0) / wall, t1 - t0
    finally:
        env.close()


def _run_rtf(world: str) -> float:
    """Simulated seconds per wall second of a plain run of ``world``, its setup excluded."""
    import tempfile

    from simulator.api import run

    with tempfile.TemporaryDirectory(prefix="skytrack-bench-gym-") as tmp:
        m = run(world, duration=_EPISODE_S, seed=1, out_dir=tmp).metrics
    return m["sim_time_s"] / (m["wall_time_s"] - m["wall_time_breakdown_s"]["setup"])


@benchmark("gym_env", produces=("gym_env_steps_per_s", "gym_env_steps_per_s_demo", "gym_env_reset_s",
                                "gym_env_rtf_over_run"))
def bench_gym_env() -> list[BenchRecord]:
    """Learner steps per second on road_standoff (2 Hz) and demo (10 Hz), the reset time of road_standoff, and the
    environment's speed over a plain run's."""
    road = [_episode("road_standoff") for _ in range(_REPEATS)]
    demo = [_episode("demo") for _ in range(_REPEATS)]
    over_run = float(np.median([r[1] for r in road])) / _run_rtf("road_standoff")
    return [BenchRecord(name="gym_env_steps_per_s", value=float(np.median([r[0] for r in road])), unit="1/s"),
            BenchRecord(name="gym_env_rtf_over_run", value=over_run, unit="x"),
            BenchRecord(name="gym_env_steps_per_s_demo", value=float(np.median([r[0] for r in demo])), unit="1/s"),
            BenchRecord(name="gym_env_reset_s", value=float(np.median([r[2] for r in road])), unit="s",
                        better="lower")]
