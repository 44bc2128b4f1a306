"""Receding-horizon search over heading-rate sequences maximising the information expected at the base station.

Each UAV flies at constant speed v and holds one heading rate ω ∈ {−ω_max, …, ω_max} per step T_s, so over a step
(exact arcs)::

    χ⁺ = χ + ω T_s,   p⁺ = p + (v/ω) [sin χ⁺ − sin χ, cos χ − cos χ⁺]   (p⁺ = p + v T_s [cos χ, sin χ] for ω = 0)

A team plan is scored over the horizon l = 1 … T_p with the target predicted at constant velocity (Liu, Fu & Gao 2018,
eqs. 28–42)::

    trace:   J = Σ_l Σ_i w_i β_i(l) tr I_i(l)
    logdet:  J = Σ_l log det Y(l),   Y(l) = (F Y(l−1)⁻¹ Fᵀ + G Q Gᵀ)⁻¹ + Σ_i w_i β_i(l) I_i(l),   Y(0) = prior

β_i(l) is UAV i's route probability to the base at the planned positions (:mod:`.routing`), I_i(l) its radar
information (:mod:`.information`), w_i = 1 for every UAV in the team objective and only for the planning UAV in the
paper's per-UAV objective. Plans that bring two UAVs closer than d_safe lose ``separation_penalty`` per metre.

Why coordinate ascent for the team objective: the joint search grows as K^(T_p N) (343² ≈ 1.2·10⁵ team plans for two
UAVs, 4·10⁷ for three), while a sequential pass costs N K^(T_p) evaluations and never lowers the team objective. It
is the paper's own scheme (UAVs plan in hierarchy order given the others' plans) applied to the shared objective and
repeated until no plan changes; the tests compare it with the exhaustive joint search on small problems.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from autonomy.guidance.infoplan.config import InfoPlannerConfig
from autonomy.guidance.infoplan.information import cv_process_noise, cv_transition, radar_information
from autonomy.guidance.infoplan.routing import (chain_route_probabilities, link_probabilities,
                                                mst_route_probabilities, planning_hierarchy)

__all__ = ["TeamPlan", "TeamInfoPlanner", "arc_paths"]


def arc_paths(p_W: np.ndarray, chi: float, rates: np.ndarray, speed: float, dt: float) -> tuple[np.ndarray,
                                                                                                np.ndarray]:
    """Positions (C, T, 2) (m) and courses (C, T) (rad) after each step of the rate sequences ``rates`` (C, T)."""
    rates = np.atleast_2d(np.asarray(rates, dtype=float))
    C, T = rates.shape
    p = np.broadcast_to(np.asarray(p_W, float)[:2], (C, 2)).copy()
    c = np.full(C, float(chi))
    out_p, out_c = np.empty((C, T, 2)), np.empty((C, T))
    for k in range(T):
        w = rates[:, k]
        c1 = c + w * dt
        small = np.abs(w) < 1e-9
        ws = np.where(small, 1.0, w)
        dx = np.where(small, speed * dt * np.cos(c), speed / ws * (np.sin(c1) - np.sin(c)))
        dy = np.where(small, speed * dt * np.sin(c), speed / ws * (np.cos(c) - np.cos(c1)))
        p = p + np.stack([dx, dy], axis=1)
        c = c1
        out_p[:, k], out_c[:, k] = p, c
    return out_p, out_c


@dataclass(frozen=True, kw_only=True)
class TeamPlan:
    """Result of one planning step.

    Attributes
    ----------
    heading_rates : np.ndarray
        (N, T_p) planned heading rates (rad/s); row i, column 0 is UAV i's command now.
    p_W : np.ndarray
        (N, T_p, 2) planned positions at t + T_s (l + 1) (m).
    value : float
        Objective of the team plan under the team objective and the configured routing and criterion (scored on
        the mean of the UAVs' predicted tracks when each plans from its own estimate).
    beta : np.ndarray
        (N, T_p) route probabilities along the plan, under the configured routing (1 for ``"none"``).
    order : list[int]
        Planning hierarchy used (hop count over the current MST, then index).
    parent : np.ndarray
        (N,) next hop of each UAV in the current MST (UAV index, -1 base, -2 cut off).
    evaluations : int
        Team plans scored.
    """

    heading_rates: np.ndarray
    p_W: np.ndarray
    value: float
    beta: np.ndarray
    order: list[int]
    parent: np.ndarray
    evaluations: int


class TeamInfoPlanner:
    """Planner for the whole team (see the module docstring); deterministic, so every UAV can run it alike."""

    def __init__(self, config: InfoPlannerConfig) -> None:
        self.config = config
        cfg = config
        grid = cfg.heading_rates
        self._candidates = np.array(list(itertools.product(range(len(grid)), repeat=cfg.horizon)))
        self._rates = grid[self._candidates]
        self._F = cv_transition(cfg.dt)
        self._GQG = cv_process_noise(cfg.dt, cfg.target_accel_std)
        self._base = np.asarray(cfg.base_p_W, float)
        self._last: np.ndarray | None = None  # (N,) candidate index of the last plan, for warm starts
        # sequences that share their first t + 1 rates share their first t + 1 positions (the same arcs, the same
        # bits): per step, one candidate of each such group and every candidate's group (the product order)
        C, K = len(self._candidates), cfg.n_heading_rates
        self._groups = [(np.arange(0, C, K ** (cfg.horizon - 1 - t)), np.arange(C) // K ** (cfg.horizon - 1 - t))
                        for t in range(cfg.horizon)]

    @property
    def candidate_rates(self) -> np.ndarray:
        """(C, T_p) all heading-rate sequences searched (rad/s)."""
        return self._rates

    def _beta(self, paths: np.ndarray, vary: int | None = None,
              groups: list[tuple[np.ndarray, np.ndarray]] | None = None) -> np.ndarray:
        """(B, T, N) route probabilities of team paths (B, N, T, 2) under the configured routing.

        ``vary``: only that UAV's paths differ between the team plans (the sequential search), so the links among the
        others are computed once, and the varying UAV's row and column once per group of ``groups`` (per step: one
        plan of each group of plans that agree up to that step, and every plan's group): the same numbers."""
        B, N, T, _ = paths.shape
        if self.config.routing == "none":
            return np.ones((B, T, N))
        routes = chain_route_probabilities if self.config.routing == "chain" else (
            lambda P: mst_route_probabilities(P)[0])
        if vary is None or groups is None:
            nodes = np.concatenate([np.broadcast_to(self._base, (B, T, 1, 2)), paths.transpose(0, 2, 1, 3)], axis=2)
            P = link_probabilities(nodes, self.config.channel).reshape(B * T, N + 1, N + 1)
            return routes(P)[:, 1:].reshape(B, T, N)
        nodes0 = np.concatenate([self._base[None, None, :].repeat(T, axis=0), paths[0].transpose(1, 0, 2)],
                                axis=1)  # (T, M, 2)
        P0 = link_probabilities(nodes0, self.config.channel)
        m = vary + 1
        beta = np.empty((B, T, N))
        for t, (first, inverse) in enumerate(groups):
            P = np.broadcast_to(P0[t], (len(first), N + 1, N + 1)).copy()
            d = np.linalg.norm(paths[first, vary, t, None, :] - nodes0[t][None], axis=-1)  # (U, M)
            pr = self.config.channel.delivery_probability(d)
            P[:, m, :] = pr
            P[:, :, m] = pr
            P[:, m, m] = 1.0
            beta[:, t] = routes(P)[:, 1:][inverse]
        return beta

    def evaluate(self, paths: np.ndarray, p_target: np.ndarray, Y0: np.ndarray,
                 weights: np.ndarray | None = None, vary: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Objective (B,) and route probabilities (B, T, N) of team paths (B, N, T, 2).

        ``p_target`` (T, 2) is the predicted target track, ``Y0`` (4 × 4) the prior information now, ``weights`` (N,)
        the w_i of the module docstring (all ones by default). ``vary``: the one UAV whose paths differ between the
        team plans, if so (the sequential search), its paths being the candidates in the order of
        :attr:`candidate_rates`: what does not depend on it is computed once, and what depends on its path up to a
        step once per distinct prefix of its heading sequence (the same results, bit for bit).
        """
        cfg = self.config
        B, N, T, _ = paths.shape
        w = np.ones(N) if weights is None else np.asarray(weights, float)
        if vary is not None and B != len(self._candidates):
            raise ValueError(f"evaluate(vary=...) needs the {len(self._candidates)} candidate paths of that UAV in "
                             f"candidate order, got {B} team plans")
        groups = None if vary is None else self._groups
        beta = self._beta(paths, vary, groups)
        if groups is None:
            info = radar_information(p_target[None, None, :, :] - paths, cfg.sigma_range, cfg.sigma_bearing)
        else:
            info = np.broadcast_to(radar_information(p_target[None, None, :, :] - paths[:1], cfg.sigma_range,
                                                     cfg.sigma_bearing), (B, N, T, 2, 2)).copy()
            info[:, vary] = radar_information(p_target[None, :, :] - paths[:, vary], cfg.sigma_range,
                                              cfg.sigma_bearing)
        gain = np.einsum("btn,bntij->btij", beta * w, info)  # (B, T, 2, 2) expected information per step
        if cfg.criterion == "trace":
            value = np.trace(gain, axis1=-2, axis2=-1).sum(axis=1)
        elif groups is None:
            value = np.zeros(B)
            Y = np.broadcast_to(Y0, (B, 4, 4))
            for k in range(T):
                Y = np.linalg.inv(self._F @ np.linalg.inv(Y) @ self._F.T + self._GQG)
                Y = Y.copy()
                Y[:, :2, :2] += gain[:, k]
                value += np.linalg.slogdet(Y)[1]
        else:  # the same recursion, once per distinct path prefix
            value = np.zeros(B)
            Y, previous = np.asarray(Y0, float)[None], np.zeros(B, dtype=int)
            for k, (first, inverse) in enumerate(groups):
                Y = np.linalg.inv(self._F @ np.linalg.inv(Y[previous[first]]) @ self._F.T + self._GQG)
                Y = Y.copy()
                Y[:, :2, :2] += gain[first, k]
                value += np.linalg.slogdet(Y)[1][inverse]
                previous = inverse
        if N > 1 and cfg.d_safe > 0:
            i, j = np.triu_indices(N, k=1)
            if groups is None:
                d = np.linalg.norm(paths[:, i] - paths[:, j], axis=-1)
            else:  # only the pairs with the varying UAV differ between the plans
                d = np.broadcast_to(np.linalg.norm(paths[:1, i] - paths[:1, j], axis=-1), (B, len(i), T)).copy()
                pair = (i == vary) | (j == vary)
                d[:, pair] = np.linalg.norm(paths[:, i[pair]] - paths[:, j[pair]], axis=-1)
            value = value - cfg.separation_penalty * np.maximum(0.0, cfg.d_safe - d).sum(axis=(1, 2))
        return value, beta

    def plan(self, p_W: np.ndarray, chi: np.ndarray, p_target: np.ndarray, v_target: np.ndarray,
             Y0: np.ndarray | None = None) -> TeamPlan:
        """Plan the team's next T_p steps.

        Parameters
        ----------
        p_W : np.ndarray
            (N, 2) UAV horizontal positions (m).
        chi : np.ndarray
            (N,) UAV courses (rad).
        p_target, v_target : np.ndarray
            (2,) target position (m) and velocity (m/s) estimates now, shared by the team; or (N, 2), each UAV's own
            estimate (the paper's scheme: every UAV plans from its local filter and receives no fused estimate), in
            which case UAV i scores its candidates on its own predicted track (sequential search only).
        Y0 : np.ndarray | None
            (4, 4) prior information of the target, layout ``TARGET_CV``; the configured default when ``None``.
        """
        cfg = self.config
        p = np.asarray(p_W, float).reshape(-1, 2)
        N = p.shape[0]
        chi = np.asarray(chi, float).reshape(N)
        Y0 = cfg.default_prior_information() if Y0 is None else np.asarray(Y0, float)
        steps = cfg.dt * np.arange(1, cfg.horizon + 1)
        tgt = self._tracks(np.asarray(p_target, float), np.asarray(v_target, float), steps, N)
        cand = np.stack([arc_paths(p[i], chi[i], self._rates, cfg.speed, cfg.dt)[0] for i in range(N)])  # (N,C,T,2)
        order, parent = planning_hierarchy(self._base, p, cfg.channel)
        C = self._rates.shape[0]
        if cfg.search == "joint":
            if tgt.ndim == 3:
                raise ValueError("per-UAV target estimates need the sequential search (search='sequential')")
            if C**N > cfg.max_joint_candidates:
                raise ValueError(f"joint search over {C}^{N} team plans exceeds max_joint_candidates = "
                                 f"{cfg.max_joint_candidates}")
            idx = np.array(list(itertools.product(range(C), repeat=N)))
            team = cand[np.arange(N)[None, :], idx]
            value, _ = self.evaluate(team, tgt, Y0)
            choice = idx[int(np.argmax(value))]
            evaluations = len(idx)
        else:
            choice, evaluations = self._sequential(cand, tgt, Y0, order)
        self._last = choice
        team = cand[np.arange(N), choice][None]
        value, beta = self.evaluate(team, tgt if tgt.ndim == 2 else tgt.mean(axis=0), Y0)
        return TeamPlan(heading_rates=self._rates[choice], p_W=team[0], value=float(value[0]),
                        beta=beta[0].T, order=order, parent=parent, evaluations=evaluations)

    @staticmethod
    def _tracks(p_target: np.ndarray, v_target: np.ndarray, steps: np.ndarray, N: int) -> np.ndarray:
        """Predicted target track (T, 2) from one shared estimate, or (N, T, 2) from one estimate per UAV."""
        if p_target.ndim == 1:
            return p_target[:2] + np.outer(steps, v_target[:2])
        if p_target.shape[0] != N or v_target.shape[0] != N:
            raise ValueError(f"per-UAV target estimates need one row per UAV ({N}), got {p_target.shape[0]} "
                             f"positions and {v_target.shape[0]} velocities")
        return p_target[:, None, :2] + steps[None, :, None] * v_target[:, None, :2]

    def _warm_start(self, N: int) -> np.ndarray:
        """Candidate indices of the last plan shifted one step (last rate repeated); straight flight at first."""
        K, T = self.config.n_heading_rates, self.config.horizon
        straight = (K // 2) * np.ones(T, dtype=int)
        if self._last is None or len(self._last) != N:
            seqs = np.tile(straight, (N, 1))
        else:
            seqs = self._candidates[self._last]
            seqs = np.concatenate([seqs[:, 1:], seqs[:, -1:]], axis=1)
        return np.array([int(np.ravel_multi_index(tuple(s), (K,) * T)) for s in seqs])

    def _sequential(self, cand: np.ndarray, tgt: np.ndarray, Y0: np.ndarray, order: list[int]) -> tuple[
            np.ndarray, int]:
        cfg = self.config
        N, C = cand.shape[:2]
        choice = self._warm_start(N)
        evaluations = 0
        for _ in range(cfg.sweeps):
            changed = False
            for i in order:
                team = np.array(cand[np.arange(N), choice][None].repeat(C, axis=0))
                team[:, i] = cand[i]
                w = np.ones(N)
                if cfg.objective == "own":
                    w = np.zeros(N)
                    w[i] = 1.0
                value, _ = self.evaluate(team, tgt if tgt.ndim == 2 else tgt[i], Y0, w, vary=i)
                evaluations += C
                best = int(np.argmax(value))
                if value[best] > value[choice[i]] + 1e-12 * max(1.0, abs(value[choice[i]])):
                    choice[i] = best
                    changed = True
            if not changed:
                break
        return choice, evaluations
