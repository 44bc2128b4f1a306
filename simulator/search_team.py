"""Paper 004's search team in the run loop: scans, set fusion over the links, sequential decisions, the guarantee.

The UAVs whose estimator is the set-membership tracker and whose fusion method is ``sets`` (or ``none``) step as one
team when their agents are due (they share one rate, :mod:`worlds.checks`):

1. each UAV's :class:`~autonomy.estimation.setmem.tracker.SetMembershipTracker` applies the scans that have arrived:
   the observed regions handed over by :meth:`SearchTeamRun.on_scan` as the sensors measure, and the box detections
   from the agent's queue;
2. the UAVs with fusion ``sets`` fuse over the links that are up (:meth:`simulator.assembly.Assembly.links_up`: under
   perfect comms the world's graph, cut by buildings with ``comms.block_by_buildings`` — the paper's line of sight;
   under a radio, one erasure draw per link), :func:`autonomy.fusion.set_team.fuse_team_sets`;
3. the UAVs decide one after another in :func:`~autonomy.guidance.search.planner.decision_order` over those links,
   each seeing the plans of the linked teammates that decided before it in this step (a
   :class:`~interfaces.state.TeammateState` with ``plan_p_W``, stamped now), as the paper's sequential MPC;
4. one row per UAV of the ``search`` stream: the normalised areas of ``X`` and ``X̄``, how many true targets lie in
   ``X ∪ X̄`` (the guarantee, checked against the physics truth), how many decoys lie in ``X``, the neighbours fused,
   whether the decision was safe (:class:`~autonomy.guidance.search.planner.SearchDecision`), the heading change
   ``u`` and the model's next position (``plan_x``, ``plan_y``: the chord's end), and ``deviation``, how far the UAV
   ended this step from where its last decision's chord put it (the physical UAV against the planner's model); every
   :data:`SNAPSHOT_EVERY` steps, each UAV's sets as one line of :data:`SETS_FILE`, rounded to 0.1 m (for plots
   and videos, not for the guarantee; read back by :func:`simulator.runrecord.load_search_sets`). A UAV whose sets
   are those of a UAV before it in the line, as after fusing with it, is written ``{"uav": k, "same_as": j}``.

:meth:`SearchTeamRun.summary` gives the run's figures for ``metrics.json``: the guarantee rate and its violations,
the team-mean areas at the end, the first step at which the team-mean ``φ(X̄)/φ(X_s)`` fell below
:data:`EMPTY_FRACTION`, the steps with a decoy inside some UAV's ``X``, the decisions taken without a safe
candidate, and the median, 95th percentile and largest ``deviation`` (m).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from autonomy.agent import AgentOutput
from autonomy.estimation.setmem.tracker import ObservedRegion
from autonomy.fusion.set_team import fuse_team_sets
from autonomy.guidance.search.planner import decision_order
from interfaces.state import TeammateState

__all__ = ["EMPTY_FRACTION", "SETS_FILE", "SNAPSHOT_EVERY", "SearchTeamRun"]

EMPTY_FRACTION = 0.01
"""``φ(X̄)/φ(X_s)`` below which the team's undetected set counts as empty (the reproduction's threshold)."""
SETS_FILE = "search_sets.jsonl.gz"
"""The set snapshots' file in the run directory: JSON lines, each a gzip member (≈ 5× smaller than the text)."""
SNAPSHOT_EVERY = 1
"""Team steps between snapshots of every UAV's sets in :data:`SETS_FILE` (for plots and videos; WKT at 0.1 m)."""


@dataclass
class SearchTeamRun:
    """The search team of one run (module docstring).

    Attributes
    ----------
    members : list[int]
        UAV indices of the team (set-membership trackers).
    fusing : set[int]
        Members whose fusion method is ``sets``.
    target_rows, decoy_rows : list[int]
        Rows of the assembly's target truth that are true targets / decoys.
    """

    members: list[int]
    fusing: set[int]
    target_rows: list[int]
    decoy_rows: list[int]
    steps: int = 0
    checks: int = 0
    violations: int = 0
    decoy_steps: int = 0
    unsafe: int = 0
    xbar_empty_step: int | None = None
    last_areas: tuple[float, float] | None = None
    deviations: list[float] = field(default_factory=list)
    _trackers: dict[int, Any] = field(default_factory=dict)
    _planned: dict[int, np.ndarray] = field(default_factory=dict)

    def attach(self, slots: Sequence[Any]) -> None:
        """Take each member's tracker from its agent slot."""
        self._trackers = {a.uav: a.agent.estimator for a in slots if a.uav in self.members}

    def on_scan(self, uav: int, t: float, latency_s: float, output: Any) -> None:
        """Hand the region a member's box sensor observed at ``t`` (s; ``output.extras["observed_region"]``), arriving
        ``latency_s`` later, to its tracker."""
        region = output.extras.get("observed_region")
        if region is None or uav not in self._trackers:
            return
        self._trackers[uav].observe(ObservedRegion(t_meas=t, t_arrival=t + latency_s, region=region))

    def step(self, asm: Any, t: float, tick: int, slots: Sequence[Any]) -> dict[int, AgentOutput]:
        """Estimation, fusion and sequential decisions of the members due at ``tick``; their agent outputs by UAV."""
        if not slots:
            return {}
        uavs = [a.uav for a in slots]
        used = {}
        for a in slots:
            ready = a.agent.take_ready(t)
            a.agent.estimator.step(t, ready)
            used[a.uav] = len(ready)
        links = asm.links_up(uavs, tick)
        fuse = np.array([u in self.fusing for u in uavs])
        links &= fuse[:, None] & fuse[None, :]
        fused = fuse_team_sets([a.agent.estimator.estimator for a in slots], links)
        for a in slots:  # a fusion at the scans' time is brought to the step's
            a.agent.estimator.estimator.predict(t)
        out: dict[int, AgentOutput] = {}
        plans: dict[int, TeammateState] = {}
        for k in decision_order(links):
            a = slots[k]
            own = asm.own_state(a.uav, t)
            mates = [plans[uavs[j]] for j in np.flatnonzero(links[k]) if uavs[j] in plans]
            out[a.uav] = a.agent.act(t, own, mates, None, used[a.uav])
            path = a.agent.guidance.planned_path()
            if path is not None:
                plans[a.uav] = TeammateState(id=a.uav, t=t, p_W=own.p_W, v_W=own.v_W, yaw=own.yaw, plan_p_W=path,
                                             plan_dt=a.agent.guidance.planner.config.dt)
        self._record(asm, tick, t, slots, fused, links)
        return out

    def _record(self, asm: Any, tick: int, t: float, slots: Sequence[Any], fused: np.ndarray,
                links: np.ndarray) -> None:
        truth = asm.target_truth()
        p_targets = truth.p_W[self.target_rows, :2]
        p_decoys = truth.p_W[self.decoy_rows, :2]
        areas, decoy_seen = [], False
        for k, a in enumerate(slots):
            est = a.agent.estimator.estimator
            sets = est.estimate
            tol = est.config.containment_tol
            inside = sets.contains(p_targets, tol) if len(p_targets) else np.zeros(0, bool)
            decoys = sets.in_X(p_decoys, tol) if len(p_decoys) else np.zeros(0, bool)
            decision = getattr(a.agent.guidance, "last_decision", None)
            aX, aXb = est.normalized_areas()
            areas.append((aX, aXb))
            self.checks += inside.size
            self.violations += int(inside.size - inside.sum())
            decoy_seen |= bool(decoys.any())
            safe = True if decision is None else bool(decision.safe)
            self.unsafe += not safe
            p_now = asm.own_state(a.uav, t).p_W[:2]
            deviation = np.nan
            if a.uav in self._planned:
                deviation = float(np.hypot(*(p_now - self._planned[a.uav])))
                self.deviations.append(deviation)
            plan = np.full(2, np.nan) if decision is None else decision.path.p_xy[0]
            self._planned[a.uav] = plan
            asm.recorder.append("search", tick=tick, t=t, uav=a.uav, area_X=aX, area_Xbar=aXb,
                                targets_inside=int(inside.sum()), targets=int(inside.size),
                                decoys_in_X=int(decoys.sum()), fused_with=int(fused[k]), links=int(links[k].sum()),
                                safe=safe, clearance=np.nan if decision is None else float(decision.clearance),
                                u=np.nan if decision is None else float(decision.u), plan_x=plan[0], plan_y=plan[1],
                                deviation=deviation,
                                vertices_X=_vertices(sets.X), vertices_Xbar=_vertices(sets.Xbar))
        self.steps += 1
        if self.steps % SNAPSHOT_EVERY == 0:
            asm.recorder.append_line(SETS_FILE, {"tick": tick, "t": t, "uavs": _snapshot(slots)})
        self.decoy_steps += decoy_seen
        mean = np.mean(areas, axis=0)
        self.last_areas = (float(mean[0]), float(mean[1]))
        if self.xbar_empty_step is None and mean[1] < EMPTY_FRACTION:
            self.xbar_empty_step = self.steps

    def summary(self) -> dict[str, Any]:
        """The team's figures for ``metrics.json`` (module docstring)."""
        return {"steps": self.steps, "guarantee_checks": self.checks, "guarantee_violations": self.violations,
                "guarantee_rate": 1.0 - self.violations / self.checks if self.checks else None,
                "area_X_final": None if self.last_areas is None else self.last_areas[0],
                "area_Xbar_final": None if self.last_areas is None else self.last_areas[1],
                "xbar_empty_step": self.xbar_empty_step, "decoy_steps": self.decoy_steps,
                "unsafe_decisions": self.unsafe,
                "chord_deviation_p50_m": _percentile(self.deviations, 50),
                "chord_deviation_p95_m": _percentile(self.deviations, 95),
                "chord_deviation_max_m": _percentile(self.deviations, 100),
                "late_scans": int(sum(tr.late_scans for tr in self._trackers.values()))}


def _percentile(values: list[float], q: float) -> float | None:
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(np.percentile(v, q)) if v.size else None


def _snapshot(slots: Sequence[Any]) -> list[dict[str, Any]]:
    """A line's ``uavs`` entries: each UAV's sets as WKT, or ``same_as`` the first UAV before it with the same text."""
    out: list[dict[str, Any]] = []
    seen: dict[tuple[str, str], int] = {}
    for a in slots:
        sets = a.agent.estimator.estimator.estimate
        key = (_wkt(sets.X), _wkt(sets.Xbar))
        if key in seen:
            out.append({"uav": a.uav, "same_as": seen[key]})
        else:
            seen[key] = a.uav
            out.append({"uav": a.uav, "X": key[0], "Xbar": key[1]})
    return out


def _wkt(geom: Any) -> str:
    import shapely

    return shapely.to_wkt(geom, rounding_precision=1, trim=True)


def _vertices(geom: Any) -> int:
    from autonomy.estimation.setmem import polygons as pg

    return int(pg.n_vertices(geom))
