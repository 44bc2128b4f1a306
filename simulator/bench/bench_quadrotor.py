"""Quadrotor benchmarks: real-time factor of the per-rotor physics and flight controllers (no sensing, no autonomy).

Scenario per fleet size N: UAVs on a 6 m grid at 40 m; even-numbered ones hold position, odd-numbered ones fly a
unicycle circle (10 m/s, 0.3 rad/s). The floor is what PyBullet itself costs for the same N bare bodies with one
force and one torque call per body per tick, measured in the same process right before; the I/O floor adds the two
calls per body and tick that read the state back (pose, velocity), which any controller flying the bodies needs.

Real-time factors are simulated seconds per wall second. On a shared machine the wall time includes waiting for a
core, so the same runs are also reported per second of this process's CPU time (``..._cpu_rtf_...``), which is close
to what an idle machine shows.
"""

from __future__ import annotations

import statistics
import time

import numpy as np
import pybullet as p

from interfaces.setpoints import UnicycleSetpoint
from simulator.bench.registry import BenchRecord, benchmark
from vehicles.quadrotor.airframes import load_airframe
from vehicles.quadrotor.fleet import FleetOptions, QuadrotorFleet

PHYSICS_HZ = 240
SIM_SECONDS = 4.0
REPEATS = 5
FLEET_SIZES = (1, 4, 10, 50)
TARGETS = {1: 100.0, 4: None, 10: 40.0, 50: 10.0}


def _client() -> int:
    cid = p.connect(p.DIRECT)
    p.setGravity(0.0, 0.0, -9.81, physicsClientId=cid)
    p.setPhysicsEngineParameter(fixedTimeStep=1.0 / PHYSICS_HZ, physicsClientId=cid)
    return cid


def _grid(n: int) -> np.ndarray:
    side = int(np.ceil(np.sqrt(n)))
    return np.array([[6.0 * (i % side), 6.0 * (i // side), 40.0] for i in range(n)])


def _timed(loop) -> tuple[float, float]:
    """(wall RTF, CPU RTF) of ``loop()``, which simulates ``SIM_SECONDS``."""
    w0, c0 = time.perf_counter(), time.process_time()
    loop()
    return SIM_SECONDS / (time.perf_counter() - w0), SIM_SECONDS / max(time.process_time() - c0, 1e-9)


def _fleet_rtf(n: int) -> tuple[float, float]:
    cid = _client()
    try:
        fleet = QuadrotorFleet(cid, [load_airframe("survey_quad")] * n, _grid(n), np.zeros(n), PHYSICS_HZ,
                               FleetOptions(), np.random.default_rng(n))
        for i in range(1, n, 2):
            fleet.set_command(i, UnicycleSetpoint(speed=10.0, heading_rate=0.3, altitude=40.0))
        ticks = int(SIM_SECONDS * PHYSICS_HZ)

        def loop() -> None:
            for tick in range(1, ticks + 1):
                fleet.apply_actuation()
                p.stepSimulation(physicsClientId=cid)
                fleet.after_step(tick)

        return _timed(loop)
    finally:
        p.disconnect(cid)


def _floor_rtf(n: int, read_back: bool = False) -> tuple[float, float]:
    """Bare PyBullet: N boxes, per tick one applyExternalForce + one applyExternalTorque per body, then a step (and,
    with ``read_back``, one getBasePositionAndOrientation + one getBaseVelocity per body)."""
    cid = _client()
    try:
        a = load_airframe("survey_quad")
        col = p.createCollisionShape(p.GEOM_BOX, halfExtents=list(a.body_half_extents), physicsClientId=cid)
        ids = []
        for pos in _grid(n).tolist():
            b = p.createMultiBody(baseMass=a.mass, baseCollisionShapeIndex=col, basePosition=pos,
                                  physicsClientId=cid)
            p.changeDynamics(b, -1, localInertiaDiagonal=list(a.inertia), linearDamping=0.0, angularDamping=0.0,
                             physicsClientId=cid)
            ids.append(b)
        force, torque, origin = [0.0, 0.0, a.weight], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
        ticks = int(SIM_SECONDS * PHYSICS_HZ)

        def loop() -> None:
            for _ in range(ticks):
                for b in ids:
                    p.applyExternalForce(b, -1, force, origin, p.LINK_FRAME, physicsClientId=cid)
                    p.applyExternalTorque(b, -1, torque, p.WORLD_FRAME, physicsClientId=cid)
                p.stepSimulation(physicsClientId=cid)
                if read_back:
                    for b in ids:
                        p.getBasePositionAndOrientation(b, physicsClientId=cid)
                        p.getBaseVelocity(b, physicsClientId=cid)

        return _timed(loop)
    finally:
        p.disconnect(cid)


@benchmark("quadrotor_physics_rtf",
           produces=tuple(f"quad_physics_rtf_{n}uav" for n in FLEET_SIZES)
           + tuple(f"quad_physics_floor_rtf_{n}uav" for n in FLEET_SIZES)
           + tuple(f"quad_physics_io_floor_rtf_{n}uav" for n in FLEET_SIZES)
           + tuple(f"quad_physics_cpu_rtf_{n}uav" for n in FLEET_SIZES)
           + tuple(f"quad_physics_rtf_ratio_to_floor_{n}uav" for n in FLEET_SIZES))
def quadrotor_physics_rtf() -> list[BenchRecord]:
    """Real-time factor (simulated s per wall s) of N quadrotors, physics at 240 Hz and controllers at 240/48 Hz,
    median of REPEATS runs of SIM_SECONDS each, next to the bare-PyBullet floors for the same N (the ratio to the
    floor is the median of the per-repeat ratios, so machine load cancels)."""
    records: list[BenchRecord] = []
    for n in FLEET_SIZES:
        ours, floor, io_floor, ours_cpu = [], [], [], []
        for _ in range(REPEATS):  # interleaved so machine load affects all alike
            floor.append(_floor_rtf(n)[0])
            io_floor.append(_floor_rtf(n, read_back=True)[0])
            wall, cpu = _fleet_rtf(n)
            ours.append(wall)
            ours_cpu.append(cpu)
        records.append(BenchRecord(name=f"quad_physics_rtf_{n}uav", value=statistics.median(ours), unit="x",
                                   target=TARGETS[n], better="higher"))
        records.append(BenchRecord(name=f"quad_physics_floor_rtf_{n}uav", value=statistics.median(floor), unit="x",
                                   better="higher"))
        records.append(BenchRecord(name=f"quad_physics_io_floor_rtf_{n}uav", value=statistics.median(io_floor),
                                   unit="x", better="higher"))
        records.append(BenchRecord(name=f"quad_physics_cpu_rtf_{n}uav", value=statistics.median(ours_cpu), unit="x",
                                   better="higher"))
        records.append(BenchRecord(name=f"quad_physics_rtf_ratio_to_floor_{n}uav",
                                   value=statistics.median(o / f for o, f in zip(ours, floor, strict=True)), unit="x",
                                   better="higher"))
    return records
