"""Fixtures for vehicle tests: a headless PyBullet client set up the way the run loop expects."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np
import pybullet as p
import pytest

PHYSICS_HZ = 240


@contextmanager
def bullet_session() -> Iterator[int]:
    """A DIRECT-mode client with gravity -9.81 m/s^2 along z and a 1/240 s fixed step; no ground plane."""
    cid = p.connect(p.DIRECT)
    try:
        p.setGravity(0.0, 0.0, -9.81, physicsClientId=cid)
        p.setPhysicsEngineParameter(fixedTimeStep=1.0 / PHYSICS_HZ, physicsClientId=cid)
        yield cid
    finally:
        p.disconnect(physicsClientId=cid)


@pytest.fixture
def bullet_client() -> Iterator[int]:
    """A fresh client per test (see :func:`bullet_session`)."""
    with bullet_session() as cid:
        yield cid


@pytest.fixture
def new_bullet_session() -> Callable:
    """The :func:`bullet_session` context manager, for tests that need a fresh client per example."""
    return bullet_session


@pytest.fixture
def run_fleet() -> Callable:
    """``run(fleet, n_ticks, start_tick=1, on_tick=None)``: the run loop (actuate, step, after_step) for n ticks.

    ``on_tick(tick)`` is called after each ``after_step``; the function returns the next tick number.
    """

    def run(fleet, n_ticks: int, start_tick: int = 1, on_tick: Callable[[int], None] | None = None) -> int:
        cid = fleet.client_id
        for tick in range(start_tick, start_tick + n_ticks):
            fleet.apply_actuation()
            p.stepSimulation(physicsClientId=cid)
            fleet.after_step(tick)
            if on_tick is not None:
                on_tick(tick)
        return start_tick + n_ticks

    return run


@pytest.fixture
def rng() -> np.random.Generator:
    """Fixed-seed generator."""
    return np.random.default_rng(20261122)
