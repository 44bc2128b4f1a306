"""Fusing a UAV's own target estimate with the estimates its teammates shared (paper 002's state-vector fusion, or CI).

Shared estimates arrive late (radio latency, the sender's agent period): each is first predicted to the fusion time
with a
nearly-constant-velocity model, ``p += v·Δt``, ``P ← F P Fᵀ + Q(Δt)`` with white-acceleration density ``q``; estimates
older than ``max_age_s`` are dropped. The fused estimate is what guidance uses; the local filter is not reset with it
(no feedback), as in paper 002, so fusing repeatedly does not double-count a teammate's information in its own filter.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from autonomy.fusion.convex import covariance_intersection, state_vector_fusion
from interfaces.state import TargetEstimate, TrackPicture, TrackReport

__all__ = ["PredictedEstimates", "TrackFusionConfig", "TrackFusion", "fuse_estimates", "predict_estimate",
           "predict_estimates"]


@dataclass(frozen=True, kw_only=True)
class TrackFusionConfig:
    """Track-to-track fusion settings.

    Attributes
    ----------
    method : {"convex", "covariance_intersection"}
        Convex combination ignoring cross-covariance (paper 002), or covariance intersection (consistent for correlated
        tracks).
    max_age_s : float
        Shared estimates older than this are ignored (s), > 0.
    q : float
        White-acceleration spectral density used to age shared estimates (m²/s³), >= 0.
    switch_margin : float
        Among traffic: team probability by which another candidate must beat the own track taken for the team's
        target at the previous step to be taken instead, in [0, 1) (:class:`~.track_association.TeamTrackFusion`).
    """

    method: Literal["convex", "covariance_intersection"] = "convex"
    max_age_s: float = 2.0
    q: float = 1.0
    switch_margin: float = 0.0

    def __post_init__(self) -> None:
        if self.method not in ("convex", "covariance_intersection"):
            raise ValueError(f"TrackFusionConfig.method must be convex|covariance_intersection, got {self.method!r}")
        if not self.max_age_s > 0:
            raise ValueError(f"TrackFusionConfig.max_age_s must be > 0 s, got {self.max_age_s}")
        if not self.q >= 0:
            raise ValueError(f"TrackFusionConfig.q must be >= 0, got {self.q}")
        if not 0 <= self.switch_margin < 1:
            raise ValueError(f"TrackFusionConfig.switch_margin must be in [0, 1), got {self.switch_margin}")


def predict_estimate(est: TargetEstimate, t: float, q: float) -> TargetEstimate:
    """Constant-velocity prediction of a 2-D estimate (state order x, y, vx, vy) to time ``t`` (s)."""
    dt = t - est.t
    if dt == 0.0:
        return est
    n = est.p_W.size
    F = np.eye(2 * n)
    F[:n, n:] = dt * np.eye(n)
    P = None
    if est.P is not None:
        Q = np.zeros((2 * n, 2 * n))
        Q[:n, :n] = abs(dt) ** 3 / 3 * q * np.eye(n)
        Q[:n, n:] = Q[n:, :n] = dt ** 2 / 2 * q * np.eye(n)
        Q[n:, n:] = abs(dt) * q * np.eye(n)
        P = F @ est.P @ F.T + Q
    return TargetEstimate(t=t, p_W=est.p_W + dt * est.v_W, v_W=est.v_W, P=P)


def predict_estimates(ests: Sequence[TargetEstimate], t: float, q: float) -> list[TargetEstimate]:
    """:func:`predict_estimate` of every estimate (:class:`PredictedEstimates`, every one made)."""
    return list(PredictedEstimates(ests, t, q))


class PredictedEstimates(Sequence[TargetEstimate]):
    """:func:`predict_estimate` of every estimate of ``ests`` to ``t`` (s), for a team's track pictures of tens of
    tracks each: the horizontal positions (:attr:`xy`) and their covariances (:attr:`P_xy`) as arrays at once, for
    association, and an estimate made only when it is read (a fusion step uses a few of them).

    The 2-D estimates with a covariance and a time other than ``t`` are predicted together, their covariances in one
    stacked product: the same numbers as one at a time (the stacked matrix product multiplies slice by slice as the
    single one does, each Q is built in the same float operations, once per distinct Δt, and ``p + Δt·v`` is the same
    elementwise arithmetic); the others (none or one such estimate, no covariance, 3-D, already at ``t``) one at a time.
    """

    def __init__(self, ests: Sequence[TargetEstimate], t: float, q: float) -> None:
        self._ests, self._t = list(ests), t
        todo = [k for k, e in enumerate(self._ests) if t - e.t != 0.0 and e.P is not None and e.p_W.size == 2]
        if len(todo) < 2:
            todo = []
        self._row = {k: m for m, k in enumerate(todo)}
        self._made: dict[int, TargetEstimate] = {k: predict_estimate(e, t, q)
                                                 for k, e in enumerate(self._ests) if k not in self._row}
        self._p = self._P = np.zeros((0,))
        if todo:
            dts = [t - self._ests[k].t for k in todo]
            F = np.tile(np.eye(4), (len(todo), 1, 1))
            F[:, 0, 2] = F[:, 1, 3] = dts
            Q = np.zeros((len(todo), 4, 4))
            steps, at = np.unique(dts, return_inverse=True)  # a picture's tracks share a few update times
            terms = np.array([(abs(dt) ** 3 / 3 * q, dt ** 2 / 2 * q, abs(dt) * q) for dt in steps.tolist()])[at]
            Q[:, 0, 0] = Q[:, 1, 1] = terms[:, 0]
            Q[:, 0, 2] = Q[:, 1, 3] = Q[:, 2, 0] = Q[:, 3, 1] = terms[:, 1]
            Q[:, 2, 2] = Q[:, 3, 3] = terms[:, 2]
            self._P = F @ np.stack([self._ests[k].P for k in todo]) @ F.transpose(0, 2, 1) + Q
            self._p = (np.stack([self._ests[k].p_W for k in todo])
                       + np.array(dts)[:, None] * np.stack([self._ests[k].v_W for k in todo]))

    def __len__(self) -> int:
        return len(self._ests)

    def __getitem__(self, k: int) -> TargetEstimate:  # type: ignore[override]
        k = range(len(self._ests))[k]
        est = self._made.get(k)
        if est is None:
            m = self._row[k]
            est = self._made[k] = TargetEstimate(t=self._t, p_W=self._p[m], v_W=self._ests[k].v_W, P=self._P[m])
        return est

    @property
    def xy(self) -> np.ndarray:
        """(n, 2) predicted horizontal positions (m)."""
        out = np.zeros((len(self._ests), 2))
        if self._row:
            out[list(self._row)] = self._p[:, :2]
        for k in set(self._made) - set(self._row):
            out[k] = self._made[k].p_W[:2]
        return out

    @property
    def P_xy(self) -> np.ndarray:
        """(n, 2, 2) covariances of :attr:`xy` (m²); a ValueError if an estimate has no covariance."""
        out = np.zeros((len(self._ests), 2, 2))
        if self._row:
            out[list(self._row)] = self._P[:, :2, :2]
        for k in set(self._made) - set(self._row):
            P = self._made[k].P
            if P is None:
                raise ValueError(f"estimate {k} has no covariance to associate it by")
            out[k] = P[:2, :2]
        return out


def fuse_estimates(method: str, t: float, parts: Sequence[TargetEstimate]) -> TargetEstimate:
    """Estimates of one target at ``t`` (s), each with a covariance, fused: sequential convex (state-vector) fusion
    ignoring cross-covariance (paper 002), or covariance intersection."""
    if len(parts) == 1:
        return parts[0]
    xs = [np.concatenate([e.p_W, e.v_W]) for e in parts]
    Ps = [np.asarray(e.P) for e in parts]
    if method == "convex":
        x, P = xs[0], Ps[0]
        for xb, Pb in zip(xs[1:], Ps[1:], strict=True):
            f = state_vector_fusion(x, P, xb, Pb)
            x, P = f.x, f.P
    else:
        f = covariance_intersection(xs, Ps)
        x, P = f.x, f.P
    n = parts[0].p_W.size
    return TargetEstimate(t=t, p_W=x[:n], v_W=x[n:], P=P)


class TrackFusion:
    """Fuses the own estimate with teammates' shared estimates at a given time; among traffic, the teammates' tracks
    with one's own after associating them (:meth:`fuse_tracks`)."""

    def __init__(self, config: TrackFusionConfig) -> None:
        from autonomy.fusion.track_association import TeamTrackFusion

        self.config = config
        self.fusions = 0
        self.team = TeamTrackFusion(config.method, config.max_age_s, config.q, switch_margin=config.switch_margin)
        self.team_track_id: int | None = None  # one's own track the last fuse_tracks took for the team's target

    def fuse_tracks(self, t: float, local: TargetEstimate | None, own: Sequence[TrackReport], own_target: int | None,
                    pictures: Sequence[TrackPicture]) -> TargetEstimate | None:
        """The team's target estimate at ``t`` (s) from one's own tracks and the teammates' track pictures
        (:class:`~autonomy.fusion.track_association.TeamTrackFusion`); ``local`` without a team target."""
        result = self.team.fuse(t, local, own, own_target, pictures)
        self.team_track_id = result.own_track_id
        if result.fused_with:
            self.fusions += 1
        return result.estimate

    def fuse(self, t: float, own: TargetEstimate | None, shared: Sequence[TargetEstimate]) -> TargetEstimate | None:
        """The fused estimate at ``t`` (s); the own estimate alone (or the freshest shared one) when nothing else is
        usable."""
        cfg = self.config
        fresh = [predict_estimate(e, t, cfg.q) for e in shared
                 if e.P is not None and 0.0 <= t - e.t <= cfg.max_age_s]
        parts = ([predict_estimate(own, t, cfg.q)] if own is not None and own.P is not None else []) + fresh
        if not parts:
            return own
        if len(parts) == 1:
            return parts[0]
        self.fusions += 1
        return fuse_estimates(cfg.method, t, parts)
