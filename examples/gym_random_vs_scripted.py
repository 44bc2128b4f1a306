"""A random and a scripted policy flying one UAV of a world through the Gymnasium environment, with their returns.

    python examples/gym_random_vs_scripted.py                      # road_standoff, 20 s, seed 3
    python examples/gym_random_vs_scripted.py --world demo --duration 30 --seed 1

The scripted policy steers from the observation alone (never truth): a Lyapunov vector field around the target
*estimate* at the world's standoff radius, turned into a heading rate toward the field's course; without an estimate
it holds its heading. Both episodes use the same seed, so the other UAV, the target and the sensors' noise start
alike; the returns differ by how the learner flew.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import simulator.envs  # noqa: F401 - registers skytrack/Tracking-v0

SPEED_MPS = 12.0
ALTITUDE_M = 60.0
TURN_GAIN = 1.5  # heading rate per radian of course error (1/s)


def scripted(obs: dict[str, np.ndarray], standoff_m: float, max_rate: float) -> np.ndarray:
    """Unicycle action (speed, heading rate, altitude) circling the estimate at ``standoff_m``."""
    x, y, _, _, _, _, c, s = obs["own"]
    yaw = float(np.arctan2(s, c))
    valid, _, tx, ty, _, _ = obs["target"]
    if valid < 0.5:
        return np.array([SPEED_MPS, 0.0, ALTITUDE_M], dtype=np.float32)
    d = np.array([x - tx, y - ty])
    r = max(float(np.hypot(*d)), 1e-6)
    radial, tangent = d / r, np.array([-d[1], d[0]]) / r  # counter-clockwise orbit
    R2, r2 = standoff_m**2, r**2
    v = -(r2 - R2) / (r2 + R2) * radial + 2.0 * r * standoff_m / (r2 + R2) * tangent
    error = np.angle(np.exp(1j * (np.arctan2(v[1], v[0]) - yaw)))
    return np.array([SPEED_MPS, np.clip(TURN_GAIN * error, -max_rate, max_rate), ALTITUDE_M], dtype=np.float32)


def episode(env: gym.Env, seed: int, policy) -> tuple[float, int, str]:
    """Return, steps and how the episode ended."""
    obs, _ = env.reset(seed=seed)
    total, steps = 0.0, 0
    while True:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        total += reward
        steps += 1
        if terminated or truncated:
            end = "collision" if info["collided"] else "lost track" if info["lost"] else "time"
            return total, steps, end


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--world", default="road_standoff")
    ap.add_argument("--duration", type=float, default=20.0, help="simulated seconds per episode")
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    env = gym.make("skytrack/Tracking-v0", world=args.world, duration=args.duration)
    env.action_space.seed(args.seed)
    core = env.unwrapped.core
    standoff = core.standoff_m[env.unwrapped.uav]
    max_rate = float(env.action_space.high[1])
    policies = {"random": lambda obs: env.action_space.sample(),
                "scripted": lambda obs: scripted(obs, standoff, max_rate)}
    print(f"{args.world}, {args.duration:g} s, seed {args.seed}, learner {env.unwrapped.uav_id} "
          f"(standoff {standoff:g} m)")
    for name, policy in policies.items():
        ret, steps, end = episode(env, args.seed, policy)
        print(f"{name:>8}: return {ret:8.2f} over {steps} steps (mean {ret / steps:6.3f}), ended by {end}")
    env.close()


if __name__ == "__main__":
    main()
