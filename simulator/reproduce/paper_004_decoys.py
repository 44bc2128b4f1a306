"""Where the decoys' measurement boxes go: which part of ``X`` was born of a decoy, and whether a later view erases it.

A decoy that some UAV sees from inside its visibility cone yields a measurement box ``y ⊖ [w]``; the part of the box
inside the observed region enters that UAV's ``X`` (eq. 13), and fusion spreads it to the neighbours. The paper's
claim is about these *decoy-born* subsets: they are taken for targets, and "these subsets are reduced during the
simulations thanks to new observations from different points of view" (Fig. 4: a false target taken at k = 132 is
eliminated at k = 137 by another UAV's view). Counting a decoy as "in X" whenever it lies inside some UAV's ``X``
cannot judge that: with ``X`` covering half the area, a decoy lies in it by chance.

Per decoy ``l`` the tracker keeps the team's decoy-born region ``D_l`` after every step (after fusion):

    D_l <- ((D_l ⊕ B(v_max T)) ∪ N_l) ∩ (∪_i X_i),

``N_l`` the step's boxes born of decoy ``l`` (clipped to the observing UAV's observed region). ``D_l`` contains every
point of the UAVs' ``X`` that descends from a decoy's box (the estimator only dilates by ``v_max T``, intersects and
subtracts), so it is an *outer* bound of the decoy-born part: when it becomes empty, every subset the decoy put into
``X`` has been erased by some view. It can also hold a true target's set that drifted next to it (then it is not
erased), so the erasure counts below are a lower bound.

An *episode* of decoy ``l`` starts when ``D_l`` becomes non-empty and ends (erased) when it is empty again. Episodes
still open at the end of the mission are *censored*; those starting within :data:`CENSOR_STEPS` of the end are left
out of the judged ones (a view cannot be expected before they could be flown over).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import shapely

from autonomy.estimation.setmem import polygons as pg

__all__ = ["CENSOR_STEPS", "DecoyEpisodes", "DecoyProvenance"]

CENSOR_STEPS = 30
"""Episodes starting in the last this many steps are not judged (a 500 m area is crossed in 30 s at 60 km/h)."""
MIN_AREA = 1e-6  # m², below which a decoy-born region counts as erased


@dataclass(frozen=True, kw_only=True)
class DecoyEpisodes:
    """One mission's decoy-born episodes.

    Attributes
    ----------
    started : int
        Episodes (a decoy-born box entered some UAV's ``X``).
    judged : int
        Episodes that started at least :data:`CENSOR_STEPS` before the end.
    erased : int
        Judged episodes whose decoy-born region was erased before the end.
    durations : tuple[int, ...]
        Steps from birth to erasure of the erased judged episodes.
    boxes : int
        Decoy-born boxes (detections of a decoy), over all UAVs and steps.
    entered : int
        Of these, the boxes that put some area into a UAV's ``X`` (a box over ground already proven free of targets
        is discarded by the correction itself: the decoy is told apart by the prediction, eq. 8).
    """

    started: int
    judged: int
    erased: int
    durations: tuple[int, ...] = ()
    boxes: int = 0
    entered: int = 0


@dataclass
class DecoyProvenance:
    """The tracker (module docstring); call :meth:`observe` after every step of a
    :class:`~simulator.kinematic.search_mission.SearchMission` (its ``on_step`` hook)."""

    steps: int
    radius: float
    regions: dict[int, object] = field(default_factory=dict)
    born: dict[int, int] = field(default_factory=dict)
    episodes: list[tuple[int, int | None]] = field(default_factory=list)
    boxes: int = 0
    entered: int = 0

    def observe(self, mission: object) -> None:
        """Advance every decoy's region by one step of ``mission`` (its ``k``, ``last_scans``, ``estimators``)."""
        k = int(mission.k)
        is_target = mission.movers.is_target
        decoys = [int(j) for j in np.flatnonzero(~is_target)]
        new: dict[int, list] = {j: [] for j in decoys}
        for out in mission.last_scans:
            region = out.extras["observed_region"]
            for det, tid in zip(out.detections, out.truth_ids, strict=True):
                if int(tid) in new:
                    lo, hi = det.z[:2] - det.bound[:2], det.z[:2] + det.bound[:2]
                    new[int(tid)].append(pg.intersection_all([shapely.box(*lo, *hi), region]))
                    self.boxes += 1
        Xs = [e.estimate.X for e in mission.estimators]
        for j in decoys:
            for B in new[j]:
                if any(pg.area(pg.intersection_all([B, X])) > MIN_AREA for X in Xs if not X.is_empty):
                    self.entered += 1
        for j in decoys:
            D = self.regions.get(j, pg.EMPTY)
            parts = ([pg.dilate(D, self.radius)] if not D.is_empty else []) + new[j]
            if not parts:
                continue
            D = pg.union_all(parts)
            D = pg.union_all([pg.intersection_all([D, X]) for X in Xs if not X.is_empty])
            alive = pg.area(D) > MIN_AREA
            if alive and j not in self.born:
                self.born[j] = k
            elif not alive and j in self.born:
                self.episodes.append((self.born.pop(j), k))
            self.regions[j] = D if alive else pg.EMPTY

    def result(self) -> DecoyEpisodes:
        """The episodes after the last step (open ones censored at the end)."""
        eps = self.episodes + [(b, None) for b in self.born.values()]
        judged = [(b, e) for b, e in eps if b <= self.steps - CENSOR_STEPS]
        erased = [(b, e) for b, e in judged if e is not None]
        return DecoyEpisodes(started=len(eps), judged=len(judged), erased=len(erased),
                             durations=tuple(int(e - b) for b, e in erased), boxes=self.boxes,
                             entered=self.entered)
