"""A team of single-target trackers fused by HCMCI consensus at one step (paper 000's estimation layer).

At a step every node's tracker absorbs its detections with :meth:`SingleTargetTracker.step_information`, giving its
prior at the step time and the information of the scan it took then; the nodes that hold a track run
:func:`autonomy.fusion.consensus.hcmci` over the links that are up (Metropolis weights on that graph, ``L`` rounds,
gain ``b``), and each of them takes its consensus posterior. Nodes without a track take no part: they have nothing to
average, and a trackless node in the graph would only dilute its neighbours' information.

The links come from the caller (the radio's state at this step); this module only restricts them to the nodes that
take part, and, when the nodes track many cars (each node's track is the one it takes for the target), to the pairs of
nodes whose priors are one car: ``dᵀ (P_i + P_j)⁻¹ d`` of the difference of their prior means under the χ² quantile
``association_gate`` (:func:`associated_links`), so the team never averages two different cars.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import gammaincinv

from autonomy.estimation.base import TIME_TOLERANCE
from autonomy.estimation.scif import SqrtInformation
from autonomy.estimation.tracker import SingleTargetTracker, TrackInformation
from autonomy.fusion.consensus import hcmci
from interfaces.state import TargetEstimate

__all__ = ["HcmciConfig", "HcmciTeam", "TeamStep", "associated_links", "consensus_adjacency", "fuse_team",
           "pair_adjacency"]


ASSOCIATION_PROBABILITY = 0.999
"""Probability of the χ² gate under which two nodes' target tracks are taken for one car (nodes tracking many cars)."""


@dataclass(frozen=True, kw_only=True)
class HcmciConfig:
    """HCMCI settings shared by the team.

    Attributes
    ----------
    rounds : int
        Consensus iterations L per step, >= 1.
    gain : float or "safe"
        Gain b on the averaged measurement information: a number > 0 (b = N recovers centralised fusion once
        consensus has converged) or ``"safe"`` (b_j = 1 / max_m (A^L)_jm: no measurement counted more than once; see
        :mod:`autonomy.fusion.consensus`).
    """

    rounds: int = 3
    gain: float | str = "safe"

    def __post_init__(self) -> None:
        if isinstance(self.rounds, bool) or int(self.rounds) != self.rounds or self.rounds < 1:
            raise ValueError(f"HcmciConfig.rounds must be an integer >= 1, got {self.rounds!r}")
        if isinstance(self.gain, str):
            if self.gain != "safe":
                raise ValueError(f"HcmciConfig.gain must be 'safe' or a number > 0, got {self.gain!r}")
        elif not (np.isfinite(self.gain) and self.gain > 0):
            raise ValueError(f"HcmciConfig.gain must be 'safe' or a number > 0, got {self.gain!r}")


@dataclass(frozen=True)
class TeamStep:
    """Result of one team fusion over N nodes.

    Attributes
    ----------
    posteriors : tuple of SqrtInformation or None
        Each node's consensus posterior ``(S_h, ĥ)``; None for nodes that took no part (no track).
    adjacency : np.ndarray
        (N, N) bool, the links the consensus ran over.
    """

    posteriors: tuple[SqrtInformation | None, ...]
    adjacency: np.ndarray

    @property
    def active_links(self) -> int:
        """Number of undirected links used."""
        return int(np.triu(self.adjacency, k=1).sum())


def pair_adjacency(n: int, pairs: Sequence[tuple[int, int]]) -> np.ndarray:
    """(n, n) symmetric bool adjacency with the undirected links ``pairs`` (0-based node indices)."""
    A = np.zeros((n, n), dtype=bool)
    for a, b in pairs:
        if a == b or not (0 <= a < n and 0 <= b < n):
            raise ValueError(f"link ({a}, {b}) must join two different nodes among 0 .. {n - 1}")
        A[a, b] = A[b, a] = True
    return A


def consensus_adjacency(links_up: np.ndarray, takes_part: Sequence[bool]) -> np.ndarray:
    """``links_up`` restricted to links between nodes that take part (no self-links)."""
    A = np.asarray(links_up, dtype=bool)
    part = np.asarray(takes_part, dtype=bool)
    if A.ndim != 2 or A.shape != (part.size, part.size):
        raise ValueError(f"links_up must be ({part.size}, {part.size}), got {A.shape}")
    if not np.array_equal(A, A.T):
        raise ValueError("links_up must be symmetric (undirected links)")
    out = A & part[:, None] & part[None, :]
    np.fill_diagonal(out, False)
    return out


def associated_links(infos: Sequence[TrackInformation | None], links_up: np.ndarray, gate: float) -> np.ndarray:
    """``links_up`` less the links between nodes whose priors are not one car: the Mahalanobis distance of their
    prior means, ``dᵀ (P_i + P_j)⁻¹ d`` (cross-covariance ignored), above ``gate`` (a χ² quantile for the state
    size); nodes without a track keep their links (:func:`consensus_adjacency` drops them)."""
    A = np.array(links_up, dtype=bool)
    stats = {}
    for j, info in enumerate(infos):
        if info is not None:
            Y = info.prior.S @ info.prior.S.T
            stats[j] = (np.linalg.solve(Y, info.prior.h), np.linalg.inv(Y))
    for i, j in zip(*np.nonzero(np.triu(A, 1)), strict=True):
        if i in stats and j in stats:
            d = stats[i][0] - stats[j][0]
            if float(d @ np.linalg.solve(stats[i][1] + stats[j][1], d)) > gate:
                A[i, j] = A[j, i] = False
    return A


def fuse_team(infos: Sequence[TrackInformation | None], links_up: np.ndarray, config: HcmciConfig,
              association_gate: float | None = None) -> TeamStep:
    """HCMCI over the nodes with a track (``infos[j]`` not None) on the links of ``links_up`` among them (and, with
    ``association_gate``, only between nodes whose priors are one car: :func:`associated_links`).

    Raises ValueError unless those nodes' priors hold at one time and have one state size (one motion model).
    """
    if association_gate is not None:
        links_up = associated_links(infos, links_up, association_gate)
    A = consensus_adjacency(links_up, [x is not None for x in infos])
    nodes = [j for j, x in enumerate(infos) if x is not None]
    posteriors: list[SqrtInformation | None] = [None] * len(infos)
    if nodes:
        times = {infos[j].t for j in nodes}
        if max(times) - min(times) > TIME_TOLERANCE:
            raise ValueError(f"team members' priors must hold at one time, got {sorted(times)}")
        sizes = [infos[j].prior.h.size for j in nodes]
        if len(set(sizes)) > 1:
            raise ValueError(f"team members' priors must have one state size (one motion model), got sizes {sizes} "
                             f"for nodes {nodes}")
        sub = A[np.ix_(nodes, nodes)]
        fused = hcmci([infos[j].prior for j in nodes], [infos[j].contribution for j in nodes], sub, config.rounds,
                      config.gain)
        for j, post in zip(nodes, fused, strict=True):
            posteriors[j] = post
    return TeamStep(posteriors=tuple(posteriors), adjacency=A)


class HcmciTeam:
    """Runs the team step of the module docstring on trackers owned elsewhere (by the agents)."""

    def __init__(self, config: HcmciConfig) -> None:
        self.config = config
        self.steps = 0

    def step(self, t: float, trackers: Sequence[SingleTargetTracker], detections: Sequence[Sequence[object]],
             links_up: np.ndarray) -> tuple[list[TargetEstimate | None], TeamStep]:
        """One fused step at ``t`` (s): each tracker absorbs its ``detections`` (sorted by ``t_meas``), the nodes with
        a track fuse over ``links_up`` ((N, N) bool) and take their posteriors; returns each node's estimate at ``t``
        and the fusion record (the trackers' own estimates: :meth:`SingleTargetTracker.step_information` already
        dropped lost tracks and predicted the others to ``t``)."""
        if not (len(trackers) == len(detections) == np.shape(links_up)[0]):
            raise ValueError(f"trackers ({len(trackers)}), detections ({len(detections)}) and links_up "
                             f"({np.shape(links_up)}) must have one entry per node")
        many = any(hasattr(trk, "track_reports") for trk in trackers)  # each node's track: its choice of target
        if many:
            _pool_targets(t, trackers, np.asarray(links_up, dtype=bool))
        infos = [trk.step_information(t, dets) for trk, dets in zip(trackers, detections, strict=True)]
        size = next((x.prior.h.size for x in infos if x is not None), 1)
        gate = float(2.0 * gammaincinv(size / 2.0, ASSOCIATION_PROBABILITY)) if many else None
        result = fuse_team(infos, links_up, self.config, association_gate=gate)
        for trk, post in zip(trackers, result.posteriors, strict=True):
            if post is not None:
                trk.set_information(post)
        self.steps += 1
        return [trk.current_estimate() for trk in trackers], result


def _pool_targets(t: float, trackers: Sequence[object], links_up: np.ndarray) -> None:
    """Before a step of trackers that hold many cars: each node takes for the target the track the linear pool of
    its own and its linked neighbours' beliefs picks (their confirmed tracks of the last step, associated with its
    own; :class:`~autonomy.fusion.track_association.TeamTrackFusion`), so a node that has not yet told the target
    from a look-alike follows one that has, and their target tracks meet in the consensus."""
    from autonomy.fusion.track_association import TeamTrackFusion, track_picture

    pictures = [track_picture(trk, t) for trk in trackers]
    pool = TeamTrackFusion("covariance_intersection", max_age_s=np.inf, q=1.0)
    for j, trk in enumerate(trackers):
        mates = [pictures[k] for k in range(len(trackers))
                 if k != j and links_up[j, k] and pictures[k] is not None and pictures[k].tracks]
        if mates and pictures[j] is not None and hasattr(trk, "team_target"):
            trk.team_target = pool.fuse(t, None, pictures[j].tracks, pictures[j].target_track_id, mates).own_track_id
