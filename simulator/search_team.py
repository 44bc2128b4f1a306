"""Paper 004's search team in a run: the record of each step against the physics truth, and the run's figures.

The team itself (scans, set fusion over the links, sequential decisions) is a team protocol,
:class:`autonomy.team.set_fusion.SetFusionTeam`; :class:`SearchTeamRun` is its observer. At each team step it writes
one row per UAV of the ``search`` stream: the normalised areas of ``X`` and ``X̄``, how many true targets lie in
``X ∪ X̄`` (the guarantee, checked against the physics truth), how many decoys lie in ``X``, the neighbours fused,
whether the decision was safe (:class:`~autonomy.guidance.search.planner.SearchDecision`), the heading change ``u``
and the model's next position (``plan_x``, ``plan_y``: the chord's end), and ``deviation``, how far the UAV ended this
step from where its last decision's chord put it (the physical UAV against the planner's model); every
:data:`SNAPSHOT_EVERY` steps, each UAV's sets as one line of :data:`SETS_FILE`, rounded to 0.1 m (for plots and
videos, not for the guarantee; read back by :func:`simulator.runrecord.load_search_sets`). A UAV whose sets are those
of a UAV before it in the line, as after fusing with it, is written ``{"uav": k, "same_as": j}``.

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

from autonomy.diagnostics import DecidesSearch
from autonomy.team.base import TeamMember
from autonomy.team.set_fusion import SetFusionTeam
from simulator.record import RunRecorder
from simulator.truth import Truth

__all__ = ["EMPTY_FRACTION", "SETS_FILE", "SNAPSHOT_EVERY", "SearchTeamRun"]

EMPTY_FRACTION = 0.01
"""``φ(X̄)/φ(X_s)`` below which the team's undetected set counts as empty (the reproduction's threshold)."""
SETS_FILE = "search_sets.jsonl.gz"
"""The set snapshots' file in the run directory: JSON lines, each a gzip member (≈ 5× smaller than the text)."""
SNAPSHOT_EVERY = 1
"""Team steps between snapshots of every UAV's sets in :data:`SETS_FILE` (for plots and videos; WKT at 0.1 m)."""


@dataclass
class SearchTeamRun:
    """The record of the search team of one run (module docstring); a
    :class:`~autonomy.team.set_fusion.SetTeamObserver`.

    Attributes
    ----------
    team : SetFusionTeam
        The team protocol it observes.
    truth : Truth
        The run's ground truth.
    recorder : RunRecorder
        The run's record.
    target_rows, decoy_rows : list[int]
        Rows of the target truth that are true targets / decoys.
    """

    team: SetFusionTeam
    truth: Truth
    recorder: RunRecorder
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
    _planned: dict[int, np.ndarray] = field(default_factory=dict)

    def on_team_step(self, tick: int, t: float, members: Sequence[TeamMember], fused: np.ndarray,
                     links: np.ndarray) -> None:
        """Record a team step (module docstring)."""
        truth = self.truth.targets()
        p_targets = truth.p_W[self.target_rows, :2]
        p_decoys = truth.p_W[self.decoy_rows, :2]
        areas, decoy_seen = [], False
        for k, m in enumerate(members):
            est = self.team.trackers[m.uav].estimator
            sets = est.estimate
            tol = est.config.containment_tol
            inside = sets.contains(p_targets, tol) if len(p_targets) else np.zeros(0, bool)
            decoys = sets.in_X(p_decoys, tol) if len(p_decoys) else np.zeros(0, bool)
            law = m.agent.guidance
            decision = law.last_decision if isinstance(law, DecidesSearch) else None
            aX, aXb = est.normalized_areas()
            areas.append((aX, aXb))
            self.checks += inside.size
            self.violations += int(inside.size - inside.sum())
            decoy_seen |= bool(decoys.any())
            safe = True if decision is None else bool(decision.safe)
            self.unsafe += not safe
            p_now = self.truth.own_state(m.uav, t).p_W[:2]
            deviation = np.nan
            if m.uav in self._planned:
                deviation = float(np.hypot(*(p_now - self._planned[m.uav])))
                self.deviations.append(deviation)
            plan = np.full(2, np.nan) if decision is None else decision.path.p_xy[0]
            self._planned[m.uav] = plan
            self.recorder.append("search", tick=tick, t=t, uav=m.uav, area_X=aX, area_Xbar=aXb,
                                 targets_inside=int(inside.sum()), targets=int(inside.size),
                                 decoys_in_X=int(decoys.sum()), fused_with=int(fused[k]), links=int(links[k].sum()),
                                 safe=safe, clearance=np.nan if decision is None else float(decision.clearance),
                                 u=np.nan if decision is None else float(decision.u), plan_x=plan[0], plan_y=plan[1],
                                 deviation=deviation,
                                 vertices_X=_vertices(sets.X), vertices_Xbar=_vertices(sets.Xbar))
        self.steps += 1
        if self.steps % SNAPSHOT_EVERY == 0:
            self.recorder.append_line(SETS_FILE, {"tick": tick, "t": t, "uavs": _snapshot(
                [(m.uav, self.team.trackers[m.uav].estimator.estimate) for m in members])})
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
                "late_scans": self.team.late_scans()}


def _percentile(values: list[float], q: float) -> float | None:
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(np.percentile(v, q)) if v.size else None


def _snapshot(sets_by_uav: Sequence[tuple[int, Any]]) -> list[dict[str, Any]]:
    """A line's ``uavs`` entries from (UAV, its sets) pairs: each UAV's sets as WKT, or ``same_as`` the first UAV
    before it with the same text."""
    out: list[dict[str, Any]] = []
    seen: dict[tuple[str, str], int] = {}
    for uav, sets in sets_by_uav:
        key = (_wkt(sets.X), _wkt(sets.Xbar))
        if key in seen:
            out.append({"uav": uav, "same_as": seen[key]})
        else:
            seen[key] = uav
            out.append({"uav": uav, "X": key[0], "Xbar": key[1]})
    return out


def _wkt(geom: Any) -> str:
    import shapely

    return shapely.to_wkt(geom, rounding_precision=1, trim=True)


def _vertices(geom: Any) -> int:
    from autonomy.estimation.setmem import polygons as pg

    return int(pg.n_vertices(geom))
