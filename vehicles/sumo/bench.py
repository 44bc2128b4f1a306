"""What SUMO co-simulation costs: CPU time per simulated second, SUMO alone and mirrored onto skytrack's slots.

Three figures, each a real-time factor (simulated seconds per CPU second, ``time.process_time``, median of
``repeats`` runs) of ``n_vehicles`` trips on a ``grid_n`` x ``grid_n`` grid of ``spacing`` m blocks:

- ``sumo_alone``: the same SUMO simulation stepping at ``rate_hz`` with the trip pool refilled, nothing read back;
- ``mirrored``: :class:`~vehicles.sumo.source.SumoTraffic` driven as the run loop drives it, ``advance`` at every
  physics tick (SUMO stepping at ``rate_hz``, every vehicle's state read into its slot);
- ``mirrored_synced``: the same with every slot's body placed in the scene at each SUMO step
  (:meth:`~vehicles.sumo.source.SumoTraffic.sync_scene`, as a sensor scanning at ``rate_hz`` would ask).

Run it with ``python -m vehicles.sumo.bench``.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass

import numpy as np
import pybullet as p

from vehicles.car.traffic_source import OtherCars
from vehicles.sumo.source import make_sumo_traffic
from worlds.roads.network import RoadNetwork

__all__ = ["SumoBenchResult", "grid_network", "run_bench"]


@dataclass(frozen=True)
class SumoBenchResult:
    """Real-time factors (x) of the three set-ups (see the module docstring) and the vehicles on the road."""

    sumo_alone: float
    mirrored: float
    mirrored_synced: float
    vehicles_on_road: int


def grid_network(n: int, spacing: float) -> RoadNetwork:
    """An ``n`` x ``n`` grid of two-way one-lane streets, ``spacing`` m apart."""
    nodes = {f"{i}_{j}": [i * spacing, j * spacing] for i in range(n) for j in range(n)}
    streets = [{"id": f"h{i}_{j}", "nodes": [f"{i}_{j}", f"{i + 1}_{j}"]} for i in range(n - 1) for j in range(n)]
    streets += [{"id": f"v{i}_{j}", "nodes": [f"{i}_{j}", f"{i}_{j + 1}"]} for i in range(n) for j in range(n - 1)]
    return RoadNetwork.from_spec({"nodes": nodes, "streets": streets})


def _sumo_alone(net: RoadNetwork, n_vehicles: int, rate_hz: float, physics_hz: int, seconds: float, warmup: float,
                seed: int, work_dir: str) -> float:
    """The same SUMO set-up as :func:`_mirrored` (network, vehicle type, options, trips), stepped with nothing read
    back: the subscriptions are dropped and arrivals only refill the trip pool."""
    cid = p.connect(p.DIRECT)
    tr = make_sumo_traffic(net, n_vehicles=n_vehicles, n_slots=n_vehicles, rate_hz=rate_hz, physics_hz=physics_hz,
                           client_id=cid, rng=np.random.default_rng(seed), work_dir=work_dir)
    lib, trips = tr._lib, tr._trips
    try:
        for vid in lib.vehicle.getIDList():
            lib.vehicle.unsubscribe(vid)

        def step() -> None:
            lib.simulation.step()
            trips.add(sum(trips.owns(v) for v in lib.simulation.getArrivedIDList()))

        for _ in range(int(round(warmup * rate_hz))):
            step()
        t0 = time.process_time()
        for _ in range(int(round(seconds * rate_hz))):
            step()
        return seconds / (time.process_time() - t0)
    finally:
        tr.close()
        p.disconnect(physicsClientId=cid)


def _mirrored(net: RoadNetwork, n_vehicles: int, rate_hz: float, physics_hz: int, seconds: float, warmup: float,
              seed: int, work_dir: str, sync: bool) -> tuple[float, int]:
    cid = p.connect(p.DIRECT)
    tr = make_sumo_traffic(net, n_vehicles=n_vehicles, n_slots=n_vehicles, rate_hz=rate_hz, physics_hz=physics_hz,
                           client_id=cid, rng=np.random.default_rng(seed), work_dir=work_dir)
    try:
        period, none = tr.config.period, OtherCars.none()
        n_warm, n_run = int(round(warmup * physics_hz)), int(round(seconds * physics_hz))
        for tick in range(1, n_warm + 1):
            tr.advance(tick, none)
        t0 = time.process_time()
        for tick in range(n_warm + 1, n_warm + n_run + 1):
            tr.advance(tick, none)
            if sync and tick % period == 0:
                tr.sync_scene(tick)
        rtf = seconds / (time.process_time() - t0)
        return rtf, tr.vehicles_on_road
    finally:
        tr.close()
        p.disconnect(physicsClientId=cid)


def run_bench(*, n_vehicles: int = 1000, grid_n: int = 12, spacing: float = 150.0, rate_hz: float = 10.0,
              physics_hz: int = 240, seconds: float = 30.0, warmup: float = 10.0, repeats: int = 3,
              work_dir: str | None = None) -> SumoBenchResult:
    """The three real-time factors, each the median of ``repeats`` runs (seeds 0, 1, ...)."""
    net = grid_network(grid_n, spacing)
    with tempfile.TemporaryDirectory() as tmp:
        wd = work_dir or tmp
        alone, mirrored, synced, on_road = [], [], [], 0
        for seed in range(repeats):
            alone.append(_sumo_alone(net, n_vehicles, rate_hz, physics_hz, seconds, warmup, seed, wd))
            rtf, on_road = _mirrored(net, n_vehicles, rate_hz, physics_hz, seconds, warmup, seed, wd, sync=False)
            mirrored.append(rtf)
            synced.append(_mirrored(net, n_vehicles, rate_hz, physics_hz, seconds, warmup, seed, wd, sync=True)[0])
    return SumoBenchResult(sumo_alone=float(np.median(alone)), mirrored=float(np.median(mirrored)),
                           mirrored_synced=float(np.median(synced)), vehicles_on_road=on_road)


if __name__ == "__main__":
    print(run_bench())
