"""The PyBullet scene's physics settings."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from simulator.scene import Scene, SceneConfig
from vehicles.car.body import WHEEL_JOINTS, CarBody
from vehicles.car.params import load_car


def _drive(config: SceneConfig, seconds: float = 2.0, settle: float = 0.5) -> tuple[np.ndarray, float]:
    """A sedan driven at 10 m/s on a gentle left turn: (final position, mean contact points per wheel once rolling,
    after ``settle`` s)."""
    scene = Scene.create(config)
    try:
        c = scene.client
        car = CarBody(c, load_car("sedan"), np.zeros(2), 0.0)
        car.apply(0.05, 10.0, braking=False)
        counts = []
        for k in range(int(seconds * config.physics_hz)):
            p.stepSimulation(physicsClientId=c)
            if k >= settle * config.physics_hz:
                counts.append(len(p.getContactPoints(bodyA=car.body_id, physicsClientId=c)) / len(WHEEL_JOINTS))
        return car.read()[0], float(np.mean(counts))
    finally:
        scene.close()


def test_rolling_wheels_keep_few_contact_points_and_the_same_trajectory() -> None:
    """With the scene's 1 mm contact breaking threshold a rolling wheel carries about one manifold point (Bullet's
    0.02 m keeps two to four, each a set of solver rows), and the car drives the same path to the millimetre."""
    p_ours, per_wheel_ours = _drive(SceneConfig())
    p_bullet, per_wheel_bullet = _drive(SceneConfig(contact_breaking_threshold=0.02))
    assert per_wheel_ours <= 1.3  # measured 1.13
    assert per_wheel_bullet >= 2.0  # measured 2.43: the default this setting exists to avoid
    assert np.linalg.norm(p_ours - p_bullet) < 0.005
    assert np.linalg.norm(p_ours[:2]) > 8.0  # it did drive (10.4 m from rest in 2 s)


def test_contact_breaking_threshold_must_be_positive() -> None:
    with pytest.raises(ValueError, match="contact_breaking_threshold"):
        SceneConfig(contact_breaking_threshold=0.0)
