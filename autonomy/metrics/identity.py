"""Whether a UAV's target estimate is on the designated target among traffic: identity metrics over its steps.

At step ``k`` the estimate is *on* car ``c_k`` = the ground vehicle nearest to it, when that one is within
``match_radius_m``; otherwise (or without an estimate) it is on none (``c_k = None``; a tie goes to the lower index).
With ``T`` steps at times ``t_0 < … < t_{T-1}`` and the designated target ``g``:

- ``identity_fraction`` = #{k : c_k = g} / T (steps without an estimate count in T);
- ``id_switches``: changes of car in the sequence ``c_k`` with the ``None`` steps removed (A, A, –, B, A → 2);
- ``time_to_acquire_s`` = t_a − t_0, ``a`` the first step on the target (NaN if never);
- ``losses``: steps ``k`` with ``c_{k-1} = g`` and ``c_k ≠ g``;
- ``time_to_reacquire_mean_s`` / ``_max_s``: over the losses after which the estimate is on the target again at a
  later step ``r``, the time t_r − t_k from the first step off the target to the first step back on it (NaN if none);
- ``unrecovered_losses``: losses not followed by any step on the target (0 or 1).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from autonomy.metrics.mot import DEFAULT_MATCH_RADIUS_M, check_match_radius

__all__ = ["IdentitySummary", "cars_on", "identity_from_cars_on", "identity_metrics"]

_NONE = -1


@dataclass(frozen=True, kw_only=True)
class IdentitySummary:
    """Identity metrics of a sequence of estimates (module docstring); NaN where undefined.

    Attributes
    ----------
    steps : int
        Steps scored, T.
    identity_fraction : float
        Fraction of the steps on the designated target (NaN without steps).
    id_switches : int
        Changes of the car the estimate is on, steps on no car skipped.
    time_to_acquire_s : float
        From the first step to the first step on the target (s).
    losses : int
        Times the estimate went from on the target to off it.
    time_to_reacquire_mean_s, time_to_reacquire_max_s : float
        Mean and largest time from a loss to the next step on the target, over the reacquired losses (s).
    unrecovered_losses : int
        Losses never reacquired.
    """

    steps: int
    identity_fraction: float
    id_switches: int
    time_to_acquire_s: float
    losses: int
    time_to_reacquire_mean_s: float
    time_to_reacquire_max_s: float
    unrecovered_losses: int

    def as_dict(self) -> dict[str, Any]:
        """The fields by name (for ``metrics.json``)."""
        return asdict(self)


def cars_on(estimates_xy: np.ndarray, truth_xy: np.ndarray, match_radius_m: float = DEFAULT_MATCH_RADIUS_M
            ) -> np.ndarray:
    """(T,) index of the car each estimate is on, −1 for none.

    Parameters
    ----------
    estimates_xy : np.ndarray
        (T, 2) estimated positions (m), NaN rows for steps without an estimate.
    truth_xy : np.ndarray
        (T, N, 2) true positions of every ground vehicle at those steps (m).
    match_radius_m : float
        Largest distance (m) at which the estimate is on a car, > 0.
    """
    r = check_match_radius(match_radius_m)
    est = np.asarray(estimates_xy, dtype=float).reshape(-1, 2)
    truth = np.asarray(truth_xy, dtype=float)
    if truth.ndim != 3 or truth.shape[0] != est.shape[0] or truth.shape[2] != 2:
        raise ValueError(f"truth_xy must be ({est.shape[0]}, N, 2) (m), got shape {truth.shape}")
    out = np.full(est.shape[0], _NONE, dtype=np.int64)
    if truth.shape[1] == 0:
        return out
    d = np.linalg.norm(truth - est[:, None, :], axis=-1)  # NaN rows where there is no estimate
    valid = ~np.isnan(est).any(axis=1)
    nearest = np.argmin(np.where(np.isnan(d), np.inf, d), axis=1)
    near_d = d[np.arange(est.shape[0]), nearest]
    hit = valid & (near_d <= r)
    out[hit] = nearest[hit]
    return out


def identity_metrics(t: np.ndarray, estimates: Sequence[np.ndarray | None], truth_xy: np.ndarray, target: int,
                     match_radius_m: float = DEFAULT_MATCH_RADIUS_M) -> IdentitySummary:
    """Identity metrics (module docstring) of ``estimates`` of the car ``target``.

    Parameters
    ----------
    t : np.ndarray
        (T,) increasing step times (s).
    estimates : sequence of np.ndarray or None
        T estimated horizontal positions (m; the first two entries are used), None at steps without an estimate.
    truth_xy : np.ndarray
        (T, N, 2) true positions of every ground vehicle at those steps (m).
    target : int
        Index of the designated target among the N vehicles.
    match_radius_m : float
        Largest distance (m) at which an estimate is on a car, > 0.
    """
    t = np.asarray(t, dtype=float).reshape(-1)
    if len(estimates) != t.size:
        raise ValueError(f"estimates must have one entry per step ({t.size}), got {len(estimates)}")
    if t.size > 1 and not np.all(np.diff(t) > 0):
        raise ValueError("t must increase strictly")
    truth = np.asarray(truth_xy, dtype=float)
    if truth.ndim != 3 or truth.shape[0] != t.size or truth.shape[1] == 0 or truth.shape[2] != 2:
        raise ValueError(f"truth_xy must be ({t.size}, N, 2) with N >= 1 (m), got shape {truth.shape}")
    if not (int(target) == target and 0 <= target < truth.shape[1]):
        raise ValueError(f"target must index one of the {truth.shape[1]} vehicles, got {target}")
    est = np.full((t.size, 2), np.nan)
    for k, e in enumerate(estimates):
        if e is not None:
            est[k] = np.asarray(e, dtype=float).reshape(-1)[:2]
    return identity_from_cars_on(t, cars_on(est, truth, match_radius_m), int(target))


def identity_from_cars_on(t: np.ndarray, on: np.ndarray, target: int) -> IdentitySummary:
    """Identity metrics from the (T,) index of the car the estimate is on at each step (−1 for none; :func:`cars_on`)
    at the (T,) increasing times ``t`` (s), for the designated car ``target``."""
    t, on = np.asarray(t, dtype=float).reshape(-1), np.asarray(on, dtype=np.int64).reshape(-1)
    if on.size != t.size:
        raise ValueError(f"on must have one entry per step ({t.size}), got {on.size}")
    n = t.size
    nan = float("nan")
    if n == 0:
        return IdentitySummary(steps=0, identity_fraction=nan, id_switches=0, time_to_acquire_s=nan, losses=0,
                               time_to_reacquire_mean_s=nan, time_to_reacquire_max_s=nan, unrecovered_losses=0)
    hit = on == target
    seen = on[on != _NONE]
    switches = int(np.count_nonzero(seen[1:] != seen[:-1]))
    hits = np.flatnonzero(hit)
    acquire = float(t[hits[0]] - t[0]) if hits.size else nan
    loss_steps = np.flatnonzero(hit[:-1] & ~hit[1:]) + 1
    regain: list[float] = []
    unrecovered = 0
    for k in loss_steps:
        later = hits[hits > k]
        if later.size:
            regain.append(float(t[later[0]] - t[k]))
        else:
            unrecovered += 1
    return IdentitySummary(steps=n, identity_fraction=float(hits.size / n), id_switches=switches,
                           time_to_acquire_s=acquire, losses=int(loss_steps.size),
                           time_to_reacquire_mean_s=float(np.mean(regain)) if regain else nan,
                           time_to_reacquire_max_s=float(np.max(regain)) if regain else nan,
                           unrecovered_losses=unrecovered)
