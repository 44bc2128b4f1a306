"""The base station as a run component (simulator/base_station.py), without physics: it fuses exactly the packets that
survive their routes, its routes and route probabilities are the channel's and the planner's, losses follow β, and a
packet older than the base's information is dropped as late."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from scipy import stats

from autonomy.estimation.models import ConstantVelocity
from autonomy.fusion.base_station import BaseStationFusion, InformationContribution
from autonomy.guidance.infoplan.routing import (chain_route_probabilities, link_probabilities,
                                                mst_route_probabilities, planning_hierarchy)
from autonomy.sensing.channel import Channel, ChannelConfig
from simulator.base_station import BaseStation

TICK_HZ = 240
ALTITUDE = 20.0  # every node at one height: the channel's 3-D distances are the planner's planar ones
CHANNEL = ChannelConfig(block_by_buildings=False, gamma=1250.0)  # Pr(d) = exp(−(d / 200 m)³)


class Rows:
    """A recorder that keeps the rows."""

    def __init__(self) -> None:
        self.rows: dict[str, list[dict]] = {}

    def append(self, stream: str, **row: object) -> None:
        self.rows.setdefault(stream, []).append(row)


@dataclass
class Reporter:
    contribution: InformationContribution | None = None


def _contribution(rng: np.random.Generator, t: float) -> InformationContribution:
    """Position information of a range-azimuth scan: rank 2 in the CV layout (x, vx, y, vy)."""
    J = np.zeros((2, 4))
    J[0, 0] = J[1, 2] = 1.0
    A = rng.normal(size=(2, 2))
    info = J.T @ (A @ A.T + 0.1 * np.eye(2)) @ J
    return InformationContribution(info_matrix=info, info_vector=info @ rng.normal(size=4) * 10, t_meas=t)


def _station(n: int, chain: bool = False, latency_s: float = 0.0, seed: int = 3) -> tuple[BaseStation, Rows]:
    rows = Rows()
    channel = Channel(ChannelConfig(block_by_buildings=False, gamma=1250.0, latency_s=latency_s), TICK_HZ,
                      np.random.default_rng(seed))
    station = BaseStation(position_W=np.array([0.0, 0.0, ALTITUDE]), uav_ids=[f"u{k}" for k in range(n)],
                          reporters={k: Reporter() for k in range(n)},
                          fusion=BaseStationFusion(ConstantVelocity(q=0.05)), channel=channel, recorder=rows,
                          chain=chain)
    return station, rows


def _fly(station: BaseStation, steps: int, rng: np.random.Generator, spread: float = 250.0
         ) -> list[tuple[np.ndarray, list[InformationContribution]]]:
    """``steps`` one-second steps with the UAVs at random places; returns each step's positions and packets."""
    n = len(station.uav_ids)
    out = []
    for k in range(1, steps + 1):
        t = float(k)
        xy = rng.uniform(-spread, spread, size=(n, 2))
        packets = []
        for i in range(n):
            c = _contribution(rng, t)
            station.reporters[i].contribution = c
            packets.append(c)
        station.step(k * TICK_HZ, t, {f"u{i}": np.r_[xy[i], ALTITUDE] for i in range(n)}, list(range(n)))
        out.append((xy, packets))
    return out


def test_the_base_fuses_exactly_the_packets_that_survived_their_routes():
    station, rows = _station(3)
    flown = _fly(station, 40, np.random.default_rng(1))
    reference = BaseStationFusion(ConstantVelocity(q=0.05))
    routing = rows.rows["routing"]
    for k, (_, packets) in enumerate(flown):
        mine = routing[3 * k: 3 * k + 3]
        assert [r["uav"] for r in mine] == [0, 1, 2] and all(r["sent"] for r in mine)
        reference.fuse(packets, [bool(r["delivered"]) for r in mine])
    delivered = sum(r["delivered"] for r in routing)
    assert 0 < delivered < len(routing)  # some were lost
    # (a step whose packets were all lost is predicted over together with the next one: rounding differs)
    np.testing.assert_allclose(station.fusion.Y, reference.Y, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(station.fusion.y, reference.y, rtol=1e-12, atol=1e-9)
    base = rows.rows["base_station"]
    assert [r["received"] for r in base] == [sum(r["delivered"] for r in routing[3 * k: 3 * k + 3])
                                              for k in range(40)]
    assert base[-1]["received_total"] == delivered == station.summary()["packets_delivered"]
    assert base[-1]["lost_total"] == len(routing) - delivered == station.summary()["packets_lost"]
    assert station.estimate is not None and base[-1]["valid"]
    np.testing.assert_allclose([base[-1]["x"], base[-1]["y"]], station.fusion.x[[0, 2]])


@pytest.mark.parametrize("chain", [False, True], ids=["mst", "chain"])
def test_routes_and_route_probabilities_are_the_channels_and_the_planners(chain):
    station, rows = _station(4, chain=chain)
    flown = _fly(station, 25, np.random.default_rng(2))
    routing = rows.rows["routing"]
    for k, (xy, _) in enumerate(flown):
        P = link_probabilities(np.vstack([[0.0, 0.0], xy])[None], CHANNEL)
        beta = chain_route_probabilities(P)[0] if chain else mst_route_probabilities(P)[0][0]
        mine = routing[4 * k: 4 * k + 4]
        np.testing.assert_allclose([r["beta"] for r in mine], beta[1:], rtol=1e-9)
        if chain:
            assert [r["parent"] for r in mine] == [-1, 0, 1, 2] and [r["hops"] for r in mine] == [1, 2, 3, 4]
        else:
            _, parent = planning_hierarchy(np.zeros(2), xy, CHANNEL)
            assert [r["parent"] for r in mine] == parent.tolist()
            hops = mst_route_probabilities(P)[1][0, 1:]
            assert [r["hops"] for r in mine] == hops.tolist()
    summary = station.summary()["uavs"]
    for i in range(4):
        mine = [r for r in routing if r["uav"] == i]
        assert summary[f"u{i}"]["beta_mean"] == pytest.approx(np.mean([r["beta"] for r in mine]))
        relays = sum(any(r["parent"] == i for r in routing[4 * k: 4 * k + 4]) for k in range(25))
        assert summary[f"u{i}"]["relay_steps"] == relays


def test_packets_are_lost_at_the_rate_their_route_probabilities_predict():
    station, rows = _station(3, seed=9)
    _fly(station, 400, np.random.default_rng(4), spread=200.0)
    routing = rows.rows["routing"]
    beta = np.array([r["beta"] for r in routing])
    delivered = sum(r["delivered"] for r in routing)
    assert 0.2 < beta.mean() < 0.8  # a lossy network, so the count says something
    # the delivered count is a sum of independent Bernoulli(β): mean Σβ, variance Σβ(1 − β)
    z = (delivered - beta.sum()) / np.sqrt(np.sum(beta * (1 - beta)))
    assert abs(z) < stats.norm.ppf(1 - 0.001 / 2)
    # one draw per hop: the two-hop packets are not delivered at the rate of their first hop
    two = np.array([r["hops"] == 2 for r in routing])
    got = np.array([r["delivered"] for r in routing])
    z2 = (got[two].sum() - beta[two].sum()) / np.sqrt(np.sum(beta[two] * (1 - beta[two])))
    assert two.sum() > 100 and abs(z2) < stats.norm.ppf(1 - 0.001 / 2)


def test_a_packet_older_than_the_bases_information_is_dropped_as_late():
    # chain of three with 1 s per hop: the third UAV's packet of step k arrives at k + 3, after the first UAV's
    # packet of step k + 1 (at k + 2) has moved the base to k + 1: it cannot be added exactly
    station, rows = _station(3, chain=True, latency_s=1.0)
    rng = np.random.default_rng(5)
    for k in range(1, 31):
        for i in range(3):
            station.reporters[i].contribution = _contribution(rng, float(k))
        xy = {f"u{i}": np.array([5.0 + 5.0 * i, 0.0, ALTITUDE]) for i in range(3)}  # Pr ≈ 1 − 2·10⁻⁵ per hop
        station.step(k * TICK_HZ, float(k), xy, [0, 1, 2])
    s = station.summary()
    assert s["packets_delivered"] == s["packets_sent"] == 90
    late = sum(r["late"] for r in rows.rows["base_station"])
    assert late == s["packets_late"] == 30 - 3  # every third-UAV packet that arrived (the last three are on the way)
    # the first two UAVs' packets, but for those still on the way (the first's last one, the second's last two); the
    # second's arrive with the first's of the step after, and are added at their own time first
    assert s["packets_fused"] == 29 + 28
