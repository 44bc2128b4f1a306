"""Metrics of a run, accumulated as it goes so a partial record has them too.

``metrics.json`` holds ``sim_time_s``, ``wall_time_s``, ``real_time_factor``, ``seed``, event counts, and

- ``uavs.<id>``: minimum separation to any other UAV (m), collisions, command saturations, guidance solver calls /
  failures / fallbacks / retries (and escalations, for tiered solvers) and solve time p50 / p95 (ms), standoff error
  (m) and, with several trackers, phase error (deg); with HCMCI fusion, ``consensus_linked_steps`` (team steps at
  which the UAV held a track and had at least one link up to another node with a track: steps it fused with the team,
  not only with itself);
- ``consensus`` (HCMCI worlds): ``team_steps`` and ``active_links_mean`` (links up between nodes that hold a track,
  averaged over the team steps);
- ``search`` (set-membership search teams, paper 004): the guarantee rate and violations (true targets outside
  ``X ∪ X̄``), the team-mean normalised areas at the end, the step at which ``X̄`` emptied, the steps with a decoy in
  ``X``, decisions without a safe candidate (:meth:`simulator.search_team.SearchTeamRun.summary`);
- ``targets.<vehicle id>.<uav id>``: position and velocity error of that UAV's own estimate against truth — mean
  Euclidean error and RMSE (m, m/s) over the agent steps with an estimate — and the fraction of steps with an estimate;
  ``<uav id>_fused`` the same for the estimate fused with the teammates' (when the UAV fuses; under HCMCI the UAV's
  own estimate is its consensus posterior); with each, over the same steps and against every ground vehicle, the
  identity metrics of :mod:`autonomy.metrics.identity` (the estimate is on the nearest vehicle within the match
  radius): ``identity_fraction`` (steps on the designated target), ``id_switches``, ``time_to_acquire_s``,
  ``losses``, ``time_to_reacquire_mean_s`` / ``_max_s`` and ``unrecovered_losses``;
- ``uavs.<id>.mot`` (UAVs whose estimator holds several tracks, :class:`autonomy.diagnostics.HoldsTracks`): the
  UAV's confirmed tracks at its agent steps against every ground vehicle on the road (a traffic source's free slots,
  parked out of sight, are no vehicles here nor in the identity metrics) (:mod:`autonomy.metrics.mot`): ``mota``,
  ``motp_m``, ``idf1``, ``num_switches``, ``mostly_tracked``, ``mostly_lost``, ``false_positives``, ``misses``,
  ``truth_instances``, ``matches``, ``gospa_mean_m``, with the ``steps`` scored and the ``match_radius_m``. A partial
  record may hold these from fewer steps than its other metrics (they are rescored as the steps grow fourfold);
  and ``uavs.<id>.target_track_changes``, how often the track the estimator takes for the target changed (each a
  ``target_track_changed`` event in ``events.jsonl``: which track to which, whether the old one still lives);
- ``base_station`` (UAVs fusing at a base station, paper 001): base steps, packets sent / delivered / lost / late /
  fused and the delivery ratio; per fusing UAV (``uavs.<id>``) the mean route probability β, mean hop count, packets
  sent and delivered, delivery ratio and the steps at which it relayed for another UAV; and the base's own estimate
  against truth at its steps (position and velocity error mean and RMSE, fraction of steps with an estimate), as for
  a UAV (:mod:`simulator.base_station`).
"""

from __future__ import annotations

import math
from collections import defaultdict
from typing import Any

import numpy as np

from autonomy.diagnostics import HoldsTracks, KeepsSolverStats, SolverSummary
from autonomy.metrics.identity import cars_on, identity_from_cars_on
from autonomy.metrics.mot import ClearMot, check_match_radius
from interfaces.state import TargetEstimate
from autonomy.team.base_station import BaseStationTeam
from autonomy.team.hcmci import HcmciConsensusTeam
from autonomy.team.set_fusion import SetFusionTeam
from simulator.base_station import BaseStation, BaseStationLink
from simulator.search_team import SearchTeamRun
from simulator.slots import AgentSlot
from simulator.tick import Assembly

__all__ = ["MetricsTracker", "RUN_MATCH_RADIUS_M"]

RUN_MATCH_RADIUS_M = 50.0
"""Distance (m) within which an estimate is on a car, for a run's identity and CLEAR-MOT metrics: about twice the
range noise of the shipped GMTI radars (20-30 m), so that an estimate on the right car is not counted as lost for its
noise, and about half the typical spacing of cars in the shipped towns (so a wrong car is not counted as right)."""

_MOT_RESCORE = 4.0
"""Partial metrics rescore a tracker's MOT block once its steps have grown fourfold. A scoring costs ≈ 25 ms plus
≈ 2 ms per step of 200 vehicles (motmetrics builds its event tables anew each time), so a run's partial flushes together
cost less than its final scoring (2.0 made them cost about twice it in a 30 s city run: 1.25 five times); a partial
file's MOT block may lag the rest by up to three quarters of the run, and says how many steps it scored."""


class _Errors:
    def __init__(self) -> None:
        self.pos: list[float] = []
        self.vel: list[float] = []
        self.steps = 0

    def summary(self) -> dict[str, float]:
        pos, vel = np.asarray(self.pos), np.asarray(self.vel)
        out: dict[str, float] = {"estimate_fraction": len(pos) / self.steps if self.steps else 0.0}
        if pos.size:
            out.update(position_error_mean_m=float(pos.mean()), position_rmse_m=float(np.sqrt(np.mean(pos ** 2))),
                       velocity_error_mean_mps=float(vel.mean()), velocity_rmse_mps=float(np.sqrt(np.mean(vel ** 2))))
        return out


class _Identity:
    """The steps of one estimate: times and the car it is on, the newest steps kept raw until scored."""

    def __init__(self) -> None:
        self.t: list[float] = []
        self.on: list[int] = []
        self.pending: list[tuple[float, np.ndarray | None, np.ndarray]] = []  # (t, xy or None, all vehicles' xy)

    def add(self, t: float, est: TargetEstimate | None, truth_xy: np.ndarray) -> None:
        self.pending.append((t, None if est is None else est.p_W[:2], truth_xy))

    def summary(self, target: int, match_radius_m: float) -> dict[str, Any]:
        if self.pending:
            est = np.array([np.full(2, np.nan) if e is None else e for _, e, _ in self.pending])
            truth = np.stack([x for _, _, x in self.pending])
            self.on.extend(cars_on(est, truth, match_radius_m).tolist())
            self.t.extend(t for t, _, _ in self.pending)
            self.pending = []
        if not self.t:
            return {}
        out = identity_from_cars_on(np.asarray(self.t), np.asarray(self.on), target).as_dict()
        out.pop("steps")
        return out


class MetricsTracker:
    """Accumulates per-UAV and per-target metrics from an :class:`~simulator.tick.Assembly` tick by tick."""

    def __init__(self, seed: int, physics_hz: int, match_radius_m: float = RUN_MATCH_RADIUS_M) -> None:
        self.seed = seed
        self.physics_hz = physics_hz
        self.match_radius_m = check_match_radius(match_radius_m)
        self.identity: dict[int, _Identity] = defaultdict(_Identity)
        self.fused_identity: dict[int, _Identity] = defaultdict(_Identity)
        self.mot: dict[int, ClearMot] = {}
        self._mot_scored: dict[int, tuple[int, dict[str, Any]]] = {}  # uav -> (steps scored, block)
        self.asm: Assembly | None = None
        self.errors: dict[int, _Errors] = defaultdict(_Errors)
        self.fused_errors: dict[int, _Errors] = defaultdict(_Errors)
        self.base_errors = _Errors()
        self.min_sep: np.ndarray | None = None
        self.standoff_err: dict[int, list[float]] = defaultdict(list)
        self.phase_err: list[float] = []
        self.standoffs: dict[int, float] = {}
        self._every = 1  # ticks between observations that can have something to do: gcd of the agent and record rates

    def attach(self, asm: Assembly) -> None:
        self.asm = asm
        self._every = math.gcd(asm.record_div, *(a.divisor for a in asm.agents))
        self.mot = {a.uav: ClearMot(self.match_radius_m) for a in asm.agents
                    if isinstance(getattr(a.agent, "estimator", None), HoldsTracks)}
        n = len(asm.uav_ids)
        self.min_sep = np.full(n, np.inf)
        world = asm.world_spec
        for i, u in enumerate(world.uavs if world is not None else []):
            g = u.autonomy.guidance
            if g.type in ("vector_field", "nmpc"):
                self.standoffs[i] = g.standoff_m

    def observe(self, tick: int, asm: Assembly) -> None:
        if tick % self._every:  # no agent due and no record tick (most ticks)
            return
        due = [a.uav for a in asm.agents if tick % a.divisor == 0]
        all_xy = None
        if due and asm.cars is not None:
            st = asm.cars.state
            all_xy = st.p_W[:, :2].copy()
            active = getattr(st, "active", None)
            if active is not None:  # a traffic source's free slots (parked bodies) are no vehicles
                all_xy[~np.asarray(active, dtype=bool)] = np.inf
        if all_xy is not None and self.mot:
            self._observe_tracks(tick, asm, due, all_xy)
        if due and asm.target_index is not None and asm.cars is not None:
            st = asm.cars.state
            k = asm.target_index
            p_true, v_true = st.p_W[k, :2], st.v_W[k, :2]
            slots = _slots_by_uav(asm)
            t = tick / self.physics_hz
            for i in due:
                team = asm.team_of(i)
                if team is not None and not team.point_estimates:  # e.g. a searcher holds sets, not a point
                    continue
                local = asm.latest_local.get(i)
                self._error(self.errors[i], local, p_true, v_true)
                self.identity[i].add(t, local, all_xy)
                if slots[i].agent.fusion is not None:
                    fused = asm.latest_estimates.get(i)
                    self._error(self.fused_errors[i], fused, p_true, v_true)
                    self.fused_identity[i].add(t, fused, all_xy)
            base = _base_station(asm)
            if base is not None and base.last_tick == tick:
                self._error(self.base_errors, base.estimate, p_true, v_true)
            if self.standoffs and asm.quads is not None:
                q = asm.quads.state.p_W[:, :2]
                for i in due:
                    if i in self.standoffs:
                        self.standoff_err[i].append(abs(float(np.linalg.norm(q[i] - p_true)) - self.standoffs[i]))
                trackers = sorted(self.standoffs)
                if len(trackers) >= 2 and due[0] == min(due):
                    ang = np.sort(np.arctan2(q[trackers, 1] - p_true[1], q[trackers, 0] - p_true[0]))
                    gaps = np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi]))
                    self.phase_err.append(float(np.degrees(np.mean(np.abs(gaps - 2 * np.pi / len(trackers))))))
        if tick % asm.record_div == 0 and asm.quads is not None and len(asm.uav_ids) > 1:
            pos = asm.quads.state.p_W
            d = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=-1)
            np.fill_diagonal(d, np.inf)
            self.min_sep = np.minimum(self.min_sep, d.min(axis=1))

    def _observe_tracks(self, tick: int, asm: Assembly, due: list[int], all_xy: np.ndarray) -> None:
        """The confirmed tracks of each due multi-target estimator against every ground vehicle."""
        slots = _slots_by_uav(asm)
        truth_ids = np.flatnonzero(np.isfinite(all_xy[:, 0]))  # the vehicles on the road (free slots are inf)
        truth_xy = all_xy[truth_ids]
        for i in due:
            if i not in self.mot:
                continue
            reports = [r for r in slots[i].agent.estimator.track_reports() if r.confirmed]
            xy = np.array([r.estimate.p_W[:2] for r in reports]).reshape(-1, 2)
            self.mot[i].add(tick / self.physics_hz, truth_ids, truth_xy, [r.track_id for r in reports], xy)

    def _mot_block(self, i: int, complete: bool) -> dict[str, Any] | None:
        """UAV ``i``'s MOT scores; a partial call reuses the last ones until the steps grew by ``_MOT_RESCORE``."""
        mot = self.mot.get(i)
        if mot is None or mot.steps == 0:
            return None
        scored = self._mot_scored.get(i)
        if scored is None or (scored[0] != mot.steps and (complete or mot.steps >= _MOT_RESCORE * scored[0])):
            scored = (mot.steps, mot.summary().as_dict())
            self._mot_scored[i] = scored
        return dict(scored[1])

    @staticmethod
    def _error(err: _Errors, est: TargetEstimate | None, p_true: np.ndarray, v_true: np.ndarray) -> None:
        err.steps += 1
        if est is not None:
            err.pos.append(float(np.linalg.norm(est.p_W[:2] - p_true)))
            err.vel.append(float(np.linalg.norm(est.v_W[:2] - v_true)))

    def metrics(self, sim_time_s: float, wall_time_s: float, complete: bool) -> dict[str, Any]:
        asm = self.asm
        out: dict[str, Any] = {
            "complete": complete,
            "sim_time_s": float(sim_time_s),
            "wall_time_s": float(wall_time_s),
            "real_time_factor": float(sim_time_s / wall_time_s) if wall_time_s > 0 else float("nan"),
            "seed": self.seed,
        }
        if asm is None:
            return out
        out["events"] = dict(asm.recording.recorder.event_counts)
        out["target_index"] = asm.target_index
        uavs: dict[str, Any] = {}
        slots = _slots_by_uav(asm)
        for i, uid in enumerate(asm.uav_ids):
            slot = slots.get(i)
            counts = asm.recording.event_counts_by_uav
            m: dict[str, Any] = {
                "collisions": counts.get(("collision", i), 0),
                "command_saturations": counts.get(("command_saturated", i), 0),
            }
            if slot is not None and isinstance(getattr(slot.agent, "estimator", None), HoldsTracks):
                m["target_track_changes"] = counts.get(("target_track_changed", i), 0)
            if self.min_sep is not None and np.isfinite(self.min_sep[i]):
                m["min_separation_m"] = float(self.min_sep[i])
            law = slot.agent.guidance if slot is not None else None
            stats = law.stats if isinstance(law, KeepsSolverStats) else None
            if isinstance(stats, SolverSummary):
                s = stats.summary()
                m.update(solver_calls=s.get("solves", 0), solver_failures=s.get("failures", 0),
                         solver_fallbacks=s.get("fallbacks_shifted", 0) + s.get("fallbacks_vector_field", 0),
                         solver_retries=s.get("retries", 0),
                         solve_ms_p50=s.get("solve_ms_p50"), solve_ms_p95=s.get("solve_ms_p95"))
                if "escalations" in s:  # tiered solvers: hand-offs from the fast tier to the robust one
                    m["solver_escalations"] = s["escalations"]
                if "restart_probes" in s:  # NMPC restart probes: re-solves from the vector-field guess, and kept
                    m["solver_restart_probes"], m["solver_restarts"] = s["restart_probes"], s["restarts"]
            if self.standoff_err.get(i):
                m["standoff_error_mean_m"] = float(np.mean(self.standoff_err[i]))
            team = asm.team_of(i)
            if isinstance(team, HcmciConsensusTeam):
                m["consensus_linked_steps"] = team.linked_steps.get(i, 0)
            mot = self._mot_block(i, complete)
            if mot is not None:
                m["mot"] = mot
            uavs[uid] = m
        if self.phase_err:
            out["phase_error_mean_deg"] = float(np.mean(self.phase_err))
        out["uavs"] = uavs
        for team in asm.teams:
            if isinstance(team, HcmciConsensusTeam):
                out["consensus"] = team.summary()
            elif isinstance(team, SetFusionTeam) and isinstance(team.observer, SearchTeamRun):
                out["search"] = team.observer.summary()
        base = _base_station(asm)
        if base is not None:
            out["base_station"] = {**base.summary(), **self.base_errors.summary()}
        if asm.channel is not None:
            cs = asm.channel.stats
            out["comms"] = {"sent": cs.sent, "delivered": cs.delivered, "lost": cs.lost, "in_flight": cs.in_flight,
                            "delivery_ratio": cs.delivered / cs.sent if cs.sent else None}
        if asm.target_index is not None and self.errors:
            k, r = asm.target_index, self.match_radius_m
            tid = asm.car_ids[k]
            per_uav = {asm.uav_ids[i]: {**e.summary(), **self.identity[i].summary(k, r)}
                       for i, e in sorted(self.errors.items())}
            per_uav.update({f"{asm.uav_ids[i]}_fused": {**e.summary(), **self.fused_identity[i].summary(k, r)}
                            for i, e in sorted(self.fused_errors.items())})
            out["targets"] = {tid: per_uav}
        return _finite_or_none(out)


def _slots_by_uav(asm: Assembly) -> dict[int, AgentSlot]:
    """The assembly's agent slots by the index of the UAV they fly (``slot.uav``), not by list position."""
    return {a.uav: a for a in asm.agents}


def _base_station(asm: Assembly) -> BaseStation | None:
    """The run's base station, if UAVs report to one."""
    for team in asm.teams:
        if isinstance(team, BaseStationTeam) and isinstance(team.base, BaseStationLink):
            return team.base.station
    return None


def _finite_or_none(obj: Any) -> Any:
    """Replace NaN/inf by None so metrics.json is strict JSON."""
    if isinstance(obj, dict):
        return {k: _finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    return obj
