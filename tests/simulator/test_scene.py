"""The PyBullet scene's physics settings."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from simulator.scene import Scene, SceneConfig
from vehicles.car.body import WHEEL_JOINTS, CarBody
from vehicles.car.params import load_car


def _drive(config: SceneConfig, seconds: float = 2.0, settle: float = 0.5) -> dict[str, np.ndarray | float]:
    """A sedan driven open-loop at 10 m/s on a steady gentle left turn: ``final`` position, ``path`` (positions once a
    second), ``steady`` (final speed, yaw rate) and ``per_wheel`` (mean contact points per wheel after ``settle`` s)."""
    scene = Scene.create(config)
    try:
        c = scene.client
        car = CarBody(c, load_car("sedan"), np.zeros(2), 0.0)
        car.apply(0.05, 10.0, braking=False)
        counts, path = [], []
        for k in range(int(seconds * config.physics_hz)):
            p.stepSimulation(physicsClientId=c)
            if k >= settle * config.physics_hz:
                counts.append(len(p.getContactPoints(bodyA=car.body_id, physicsClientId=c)) / len(WHEEL_JOINTS))
            if (k + 1) % config.physics_hz == 0:
                path.append(car.read()[0])
        final, _, v, w = car.read()
        return {"final": final, "path": np.array(path), "steady": np.array([np.linalg.norm(v), w[2]]),
                "per_wheel": float(np.mean(counts))}
    finally:
        scene.close()


def test_rolling_wheels_keep_few_contact_points_and_the_same_trajectory() -> None:
    """With the scene's 1 mm contact breaking threshold a rolling wheel carries about one manifold point (Bullet's
    0.02 m keeps two to four, each a set of solver rows), and the car drives the same path to the millimetre."""
    ours, bullet = _drive(SceneConfig()), _drive(SceneConfig(contact_breaking_threshold=0.02))
    assert ours["per_wheel"] <= 1.3  # measured 1.13
    assert bullet["per_wheel"] >= 2.0  # measured 2.43: the default this setting exists to avoid
    assert np.linalg.norm(ours["final"] - bullet["final"]) < 0.005
    assert np.linalg.norm(ours["final"][:2]) > 8.0  # it did drive (10.4 m from rest in 2 s)


def test_contact_breaking_threshold_must_be_positive() -> None:
    with pytest.raises(ValueError, match="contact_breaking_threshold"):
        SceneConfig(contact_breaking_threshold=0.0)


def test_the_scene_solver_iterations_leave_the_car_motion_converged() -> None:
    """The scene's 10 solver iterations against PyBullet's 50: same steady speed and yaw rate, a path within 0.2 m
    after 100 m (measured 0.14 m); with 2 iterations the car does not reach that (so the check can fail)."""
    ours, ref = _drive(SceneConfig(), seconds=10.0), _drive(SceneConfig(solver_iterations=50), seconds=10.0)
    assert SceneConfig().solver_iterations == 10
    np.testing.assert_allclose(ours["steady"], ref["steady"], rtol=1e-3)
    assert ref["steady"][1] > 0.15  # it did turn (0.179 rad/s)
    assert np.linalg.norm(ours["path"] - ref["path"], axis=1).max() < 0.2
    coarse = _drive(SceneConfig(solver_iterations=2), seconds=10.0)
    assert np.linalg.norm(coarse["path"] - ref["path"], axis=1).max() > 0.2


@pytest.mark.parametrize("bad", [0, 2.5])
def test_solver_iterations_must_be_a_positive_integer(bad) -> None:
    with pytest.raises(ValueError, match="solver_iterations"):
        SceneConfig(solver_iterations=bad)
