"""Radio channel: packet erasures, range, building blockage, latency, outages, and multi-hop routing to a base.

Link model (Rayleigh fast fading, Liu, Fu & Gao 2018): a packet over a link of length ``d`` arrives with

    Pr(d) = exp(-N gamma d**alpha / (C P))

with transmit power ``P`` and noise power ``N`` in mW (from dBm). The defaults (``P`` = 30 dBm, ``N`` = -70 dBm,
``gamma`` = 10, ``C`` = 1, ``alpha`` = 3, the paper's Table 1) give ``Pr(d) = exp(-(d / 1000 m)**3)``. On top,
``Pr = 0`` beyond ``max_range``, across a building (``SceneQuery.line_of_sight``) when ``block_by_buildings``,
between nodes that are not a pair of a fixed topology ``links``, and during a scheduled :class:`LinkOutage`.

Routing: the minimum spanning tree over the nodes with edge weights ``-ln Pr`` (the most reliable tree), rooted
at the base; a node's route is its tree path and its route probability ``beta`` the product of the hop
probabilities. Erasures are independent per hop; each hop adds ``latency_s``. The fixed relay chain (paper 001's
baseline, :func:`chain_routes`) routes each node through the one listed before it, whatever the link qualities.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import breadth_first_order, minimum_spanning_tree

from .messages import Envelope, Message
from .scene import SceneQuery

__all__ = ["Channel", "ChannelConfig", "ChannelStats", "LinkOutage", "RoutingTree", "chain_routes",
           "minimum_spanning_tree_routes", "outage_holds", "scheduled_links", "scheduled_row"]


@dataclass(frozen=True, kw_only=True)
class LinkOutage:
    """A link forced down for ``start_s <= t < end_s`` (both directions).

    Attributes
    ----------
    node_a, node_b : str
        The link's ends.
    start_s, end_s : float
        Outage window (s).
    """

    node_a: str
    node_b: str
    start_s: float
    end_s: float

    def __post_init__(self) -> None:
        if not (self.end_s > self.start_s):
            raise ValueError(f"LinkOutage.end_s ({self.end_s}) must be > start_s ({self.start_s})")
        if self.node_a == self.node_b:
            raise ValueError(f"LinkOutage needs two different nodes, got {self.node_a!r} twice")


@dataclass(frozen=True, kw_only=True)
class ChannelConfig:
    """Radio parameters.

    Attributes
    ----------
    transmit_power_dbm : float
        Transmit power ``P`` (dBm).
    noise_power_dbm : float
        Noise power ``N`` (dBm).
    gamma : float
        SNR threshold ``gamma`` of successful decoding (dimensionless, linear).
    c : float
        Link constant ``C`` (dimensionless).
    alpha : float
        Path-loss exponent.
    max_range : float | None
        Hard range limit (m); ``None`` for none.
    block_by_buildings : bool
        Whether buildings between two nodes cut their link.
    latency_s : float
        Delay per hop (s); must be a whole number of physics ticks.
    outages : tuple[LinkOutage, ...]
        Scheduled link outages.
    links : tuple[tuple[str, str], ...] | None
        Fixed topology: only these (undirected) node pairs have a link; ``None`` for every pair.
    """

    transmit_power_dbm: float = 30.0
    noise_power_dbm: float = -70.0
    gamma: float = 10.0
    c: float = 1.0
    alpha: float = 3.0
    max_range: float | None = None
    block_by_buildings: bool = True
    latency_s: float = 0.0
    outages: tuple[LinkOutage, ...] = field(default_factory=tuple)
    links: tuple[tuple[str, str], ...] | None = None

    def __post_init__(self) -> None:
        for name in ("gamma", "c", "alpha"):
            if not (getattr(self, name) > 0):
                raise ValueError(f"ChannelConfig.{name} must be > 0, got {getattr(self, name)}")
        if self.max_range is not None and not (self.max_range > 0):
            raise ValueError(f"ChannelConfig.max_range must be > 0 m or None, got {self.max_range}")
        if not (self.latency_s >= 0):
            raise ValueError(f"ChannelConfig.latency_s must be >= 0 s, got {self.latency_s}")
        object.__setattr__(self, "outages", tuple(self.outages))
        if self.links is not None:
            links = tuple((str(a), str(b)) for a, b in self.links)
            for a, b in links:
                if a == b:
                    raise ValueError(f"ChannelConfig.links: a link needs two different nodes, got {a!r} twice")
            object.__setattr__(self, "links", links)

    @property
    def fading_scale(self) -> float:
        """``k = N gamma / (C P)`` (m**-alpha), so ``Pr(d) = exp(-k d**alpha)``."""
        n_mw = 10.0 ** (self.noise_power_dbm / 10.0)
        p_mw = 10.0 ** (self.transmit_power_dbm / 10.0)
        return n_mw * self.gamma / (self.c * p_mw)

    def delivery_probability(self, d: np.ndarray | float) -> np.ndarray:
        """Fading-only packet delivery probability at distance ``d`` (m), range limit applied."""
        d = np.asarray(d, dtype=float)
        pr = np.exp(-self.fading_scale * d**self.alpha)
        if self.max_range is not None:
            pr = np.where(d <= self.max_range, pr, 0.0)
        return pr


@dataclass(frozen=True, kw_only=True)
class ChannelStats:
    """Message counts for the recorder (a snapshot).

    Attributes
    ----------
    sent : int
        Message copies handed to the channel (one per addressee for broadcasts).
    delivered : int
        Copies handed to their receiver.
    lost : int
        Copies erased (fading, range, blockage, outage, or any hop of a route).
    in_flight : int
        Copies that will arrive later.
    by_link : dict[tuple[str, str], tuple[int, int, int]]
        (sent, delivered, lost) per (sender, final receiver).
    """

    sent: int
    delivered: int
    lost: int
    in_flight: int
    by_link: dict[tuple[str, str], tuple[int, int, int]]


@dataclass(frozen=True, kw_only=True)
class RoutingTree:
    """Routes to a root over a spanning tree.

    Attributes
    ----------
    nodes : tuple[str, ...]
        Node names.
    root : str
        The base station.
    parent : dict[str, str | None]
        Next hop towards the root (``None`` for the root and for nodes cut off from it).
    link_probability : np.ndarray
        (N, N) per-link delivery probabilities the tree was built from.
    """

    nodes: tuple[str, ...]
    root: str
    parent: dict[str, str | None]
    link_probability: np.ndarray

    def path(self, node: str) -> tuple[str, ...]:
        """Nodes from ``node`` to the root, both included; empty if ``node`` is cut off."""
        out = [node]
        while out[-1] != self.root:
            nxt = self.parent[out[-1]]
            if nxt is None:
                return ()
            out.append(nxt)
        return tuple(out)

    def hops(self, node: str) -> int:
        """Hop count to the root (-1 if cut off)."""
        return len(self.path(node)) - 1

    def route_probability(self, node: str) -> float:
        """``beta``: product of the hop probabilities along the path (0 if cut off, 1 for the root)."""
        path = self.path(node)
        if not path:
            return 0.0
        idx = [self.nodes.index(n) for n in path]
        return float(np.prod([self.link_probability[i, j] for i, j in itertools.pairwise(idx)]))


def outage_holds(a: str, b: str, outages: Iterable[tuple[str, str, int, int]], tick: int) -> bool:
    """Whether one of ``outages`` ``(node_a, node_b, start_tick, end_tick)`` holds link ``a``-``b`` down at ``tick``
    (``start_tick <= tick < end_tick``, either direction)."""
    pair = frozenset((a, b))
    return any(pair == frozenset((x, y)) and start <= tick < end for x, y, start, end in outages)


def scheduled_links(nodes: Sequence[str], links: Iterable[tuple[str, str]] | None,
                    outages: Iterable[tuple[str, str, int, int]], tick: int) -> np.ndarray:
    """(N, N) symmetric bool: which pairs of ``nodes`` may talk at ``tick`` before any radio effect — the pairs of the
    fixed topology ``links`` (every pair when None) that no outage ``(node_a, node_b, start_tick, end_tick)`` holds
    down (:func:`outage_holds`). Diagonal False. Perfect comms use this as the link state; the radio multiplies it
    into its delivery probabilities."""
    nodes = tuple(nodes)
    pairs = None if links is None else {frozenset(p) for p in links}
    outages = tuple(outages)
    up = np.zeros((len(nodes), len(nodes)), dtype=bool)
    for i, j in itertools.combinations(range(len(nodes)), 2):
        listed = pairs is None or frozenset((nodes[i], nodes[j])) in pairs
        up[i, j] = up[j, i] = listed and not outage_holds(nodes[i], nodes[j], outages, tick)
    return up


def scheduled_row(sender: str, targets: Sequence[str], links: Iterable[tuple[str, str]] | None,
                  outages: Iterable[tuple[str, str, int, int]], tick: int) -> np.ndarray:
    """(len(targets),) bool: row ``sender`` of :func:`scheduled_links` over ``(sender, *targets)``, without the
    links among the targets (a direct send reads this row only; the whole matrix was N² outage checks per sender)."""
    pairs = None if links is None else {frozenset(p) for p in links}
    outages = tuple(outages)
    return np.array([(pairs is None or frozenset((sender, r)) in pairs) and not outage_holds(sender, r, outages, tick)
                     for r in targets], dtype=bool)


def _points(nodes: Sequence[str], positions: Mapping[str, np.ndarray]) -> np.ndarray:
    """(N, 3) positions (m) of ``nodes``, in their order."""
    return np.array([np.asarray(positions[n], dtype=float) for n in nodes]).reshape(len(nodes), 3)


def _tree_inputs(nodes: Sequence[str], link_probability: np.ndarray, root: str) -> tuple[tuple[str, ...],
                                                                                          np.ndarray]:
    """``nodes`` as a tuple and the (N, N) link probabilities as floats, checked against each other and ``root``."""
    nodes = tuple(nodes)
    P = np.asarray(link_probability, dtype=float)
    if P.shape != (len(nodes), len(nodes)):
        raise ValueError(f"link_probability must be ({len(nodes)}, {len(nodes)}), got {P.shape}")
    if root not in nodes:
        raise ValueError(f"root {root!r} is not among the nodes {nodes}")
    return nodes, P


def minimum_spanning_tree_routes(nodes: Sequence[str], link_probability: np.ndarray, root: str) -> RoutingTree:
    """Spanning tree minimising ``sum -ln Pr`` over its links, rooted at ``root``.

    A link with ``Pr = 0`` is absent; nodes in another component than the root get no route.
    """
    nodes, P = _tree_inputs(nodes, link_probability, root)
    with np.errstate(divide="ignore"):
        w = np.where(P > 0, -np.log(np.clip(P, 1e-300, 1.0)) + 1e-12, 0.0)  # csgraph treats 0 as no edge
    np.fill_diagonal(w, 0.0)
    w = np.maximum(w, w.T)
    mst = minimum_spanning_tree(csr_matrix(w))
    sym = mst + mst.T
    r = nodes.index(root)
    order, pred = breadth_first_order(sym, r, directed=False, return_predecessors=True)
    parent: dict[str, str | None] = {n: None for n in nodes}
    for k in order:
        if k != r and pred[k] >= 0:
            parent[nodes[k]] = nodes[pred[k]]
    return RoutingTree(nodes=nodes, root=root, parent=parent, link_probability=P)


def chain_routes(nodes: Sequence[str], link_probability: np.ndarray, root: str) -> RoutingTree:
    """The fixed relay chain: the nodes after ``root`` in the order of ``nodes`` each relay through the one before
    them, the first straight to ``root`` (A_k → A_{k−1} → … → A_1 → B). Every node keeps its route; a hop with
    ``Pr = 0`` makes its route probability 0."""
    nodes, P = _tree_inputs(nodes, link_probability, root)
    parent: dict[str, str | None] = {root: None}
    previous = root
    for n in nodes:
        if n != root:
            parent[n], previous = previous, n
    return RoutingTree(nodes=nodes, root=root, parent=parent, link_probability=P)


class Channel:
    """Lossy radio shared by a team (module docstring).

    Parameters
    ----------
    config : ChannelConfig
        Radio parameters.
    tick_hz : float
        Physics rate; latencies and outages are stored in ticks.
    rng : np.random.Generator
        Source of the erasures.
    scene : SceneQuery | None
        Used for building blockage (required when ``config.block_by_buildings``).
    """

    def __init__(
        self, config: ChannelConfig, tick_hz: float, rng: np.random.Generator, scene: SceneQuery | None = None
    ):
        if not (tick_hz > 0):
            raise ValueError(f"tick_hz must be > 0, got {tick_hz}")
        if config.block_by_buildings and scene is None:
            raise ValueError("ChannelConfig.block_by_buildings needs a scene")
        self.config = config
        self.tick_hz = float(tick_hz)
        self.rng = rng
        self.scene = scene
        lat = config.latency_s * tick_hz
        if abs(lat - round(lat)) > 1e-6:
            raise ValueError(
                f"ChannelConfig.latency_s = {config.latency_s} s is not a whole number of {tick_hz} Hz ticks"
            )
        self.latency_ticks = round(lat)
        self._outages = [
            (
                o.node_a,
                o.node_b,
                int(np.ceil(o.start_s * tick_hz - 1e-9)),
                int(np.ceil(o.end_s * tick_hz - 1e-9)),
            )
            for o in config.outages
        ]
        self._queue: dict[str, list[Envelope]] = {}  # per receiver, in the order sent
        self._rows_tick: int | None = None  # the tick of the delivery probabilities kept in _rows
        self._rows: dict[tuple, np.ndarray] = {}
        self._counts: dict[tuple[str, str], list[int]] = {}

    def link_down(self, a: str, b: str, tick: int) -> bool:
        """Whether a scheduled outage holds link ``a``-``b`` down at ``tick``."""
        return outage_holds(a, b, self._outages, tick)

    def link_matrix(self, nodes: Sequence[str], positions: Mapping[str, np.ndarray], tick: int) -> np.ndarray:
        """(N, N) symmetric delivery probabilities between ``nodes`` at ``tick`` (diagonal 1)."""
        nodes = tuple(nodes)
        return self.link_matrices(nodes, _points(nodes, positions)[None], [tick])[0]

    def link_matrices(self, nodes: Sequence[str], positions: np.ndarray, ticks: Sequence[int]) -> np.ndarray:
        """(T, N, N) :meth:`link_matrix` at each of ``ticks`` (T,) with the ``nodes``' positions (T, N, 3) m there:
        the fading, range and line of sight of every pair at every tick in one batch (one scene query for a whole
        recorded run: its plot and export), then each tick's link schedule."""
        nodes = tuple(nodes)
        pts = np.asarray(positions, dtype=float).reshape(len(ticks), len(nodes), 3)
        iu, ju = np.triu_indices(len(nodes), k=1)
        pr = self._pair_probabilities(pts[:, iu].reshape(-1, 3), pts[:, ju].reshape(-1, 3)).reshape(len(ticks), -1)
        out = np.tile(np.eye(len(nodes)), (len(ticks), 1, 1))
        for k, tick in enumerate(ticks):
            P = out[k]
            P[iu, ju] = P[ju, iu] = pr[k]
            P[~scheduled_links(nodes, self.config.links, self._outages, int(tick))] = 0.0
            np.fill_diagonal(P, 1.0)
        return out

    def _pair_probabilities(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(K,) delivery probabilities of the links from ``a[k]`` to ``b[k]`` (K, 3) m: fading, range and, with
        ``block_by_buildings``, line of sight (the link schedule and outages are the callers')."""
        P = self.config.delivery_probability(np.linalg.norm(a - b, axis=1))
        if self.config.block_by_buildings and len(a):
            P[~np.asarray(self.scene.line_of_sight(a, b), dtype=bool)] = 0.0
        return P

    def sample_links(self, nodes: Sequence[str], positions: Mapping[str, np.ndarray], tick: int) -> np.ndarray:
        """(N, N) symmetric bool: which links between ``nodes`` are up at ``tick``, one erasure draw per link with its
        delivery probability (diagonal False). For an exchange over the link state of one instant, e.g. a consensus
        step whose rounds all use the same links."""
        P = self.link_matrix(nodes, positions, tick)
        iu, ju = np.triu_indices(len(P), k=1)
        up = np.zeros(P.shape, dtype=bool)
        up[iu, ju] = self.rng.uniform(size=iu.size) < P[iu, ju]
        return up | up.T

    def routing_tree(
        self, nodes: Sequence[str], positions: Mapping[str, np.ndarray], root: str, tick: int, chain: bool = False
    ) -> RoutingTree:
        """Minimum spanning tree routes to ``root`` at ``tick``; with ``chain``, the fixed relay chain over ``nodes``
        in their order (:func:`chain_routes`) on the link probabilities of ``tick``."""
        P = self.link_matrix(nodes, positions, tick)
        return chain_routes(nodes, P, root) if chain else minimum_spanning_tree_routes(nodes, P, root)

    def _count(self, sender: str, receiver: str, k: int) -> None:
        self._counts.setdefault((sender, receiver), [0, 0, 0])[k] += 1

    def _transmit(self, msg: Message, path: tuple[str, ...], hop_probs: Sequence[float], tick: int) -> bool:
        receiver = path[-1]
        self._count(msg.sender, receiver, 0)
        ok = bool(np.all(self.rng.uniform(size=len(hop_probs)) < np.asarray(hop_probs)))
        if not ok:
            self._count(msg.sender, receiver, 2)
            return False
        t_tick = tick + self.latency_ticks * (len(path) - 1)
        self._queue.setdefault(receiver, []).append(
            Envelope(message=msg, receiver=receiver, tick_arrival=t_tick, t_arrival=t_tick / self.tick_hz, path=path)
        )
        return True

    def send(self, msg: Message, positions: Mapping[str, np.ndarray], tick: int) -> dict[str, bool]:
        """Send ``msg`` over direct links: to ``msg.receiver``, or to every other node of ``positions`` if None.

        Returns whether each addressee's copy survived (it arrives ``latency_s`` later).
        """
        targets = [msg.receiver] if msg.receiver is not None else [n for n in positions if n != msg.sender]
        P = self._links_from(msg.sender, targets, positions, tick)
        return {r: self._transmit(msg, (msg.sender, r), [P[k]], tick) for k, r in enumerate(targets)}

    def _links_from(self, sender: str, targets: Sequence[str], positions: Mapping[str, np.ndarray],
                    tick: int) -> np.ndarray:
        """(len(targets),) delivery probabilities from ``sender`` to each target at ``tick``: the sender's row of
        :meth:`link_matrix`, without the links among the targets that a direct send does not use (with three UAVs
        broadcasting, their line-of-sight rays were a third of those cast); kept for the tick, so a second message
        between the same nodes at the same positions casts no ray."""
        nodes = (sender, *targets)
        pts = _points(nodes, positions)
        key = (sender, tuple(targets), pts.tobytes())
        if self._rows_tick != tick:
            self._rows_tick, self._rows = tick, {}
        P = self._rows.get(key)
        if P is None:  # a UAV broadcasts its state and its estimate at one tick: the same links, rays cast once
            P = self._pair_probabilities(np.repeat(pts[:1], len(targets), axis=0), pts[1:])
            P[~scheduled_row(sender, targets, self.config.links, self._outages, tick)] = 0.0
            self._rows[key] = P
        return P.copy()

    def send_routed(self, msg: Message, tree: RoutingTree, tick: int) -> bool:
        """Send ``msg`` from its sender to the tree's root along the tree path (erasure per hop)."""
        path = tree.path(msg.sender)
        if not path:
            self._count(msg.sender, tree.root, 0)
            self._count(msg.sender, tree.root, 2)
            return False
        idx = [tree.nodes.index(n) for n in path]
        probs = [tree.link_probability[i, j] for i, j in itertools.pairwise(idx)]
        return self._transmit(msg, path, probs, tick)

    def receive(self, node: str, tick: int) -> list[Envelope]:
        """Messages for ``node`` that have arrived by ``tick``, oldest first; they leave the channel."""
        queued = self._queue.get(node, [])
        mine = [e for e in queued if e.tick_arrival <= tick]
        if mine:
            self._queue[node] = [e for e in queued if e.tick_arrival > tick]
            for e in mine:
                self._count(e.message.sender, node, 1)
        return sorted(mine, key=lambda e: e.tick_arrival)

    @property
    def stats(self) -> ChannelStats:
        sent = sum(c[0] for c in self._counts.values())
        delivered = sum(c[1] for c in self._counts.values())
        lost = sum(c[2] for c in self._counts.values())
        return ChannelStats(
            sent=sent,
            delivered=delivered,
            lost=lost,
            in_flight=sent - delivered - lost,
            by_link={k: (c[0], c[1], c[2]) for k, c in self._counts.items()},
        )
