"""A whole team's states at one time, checked once and stacked, and what a guidance law reads from any teammates.

Under perfect comms a simulator hands each of N agents the true states of its N − 1 teammates at every agent tick.
Built one :class:`~interfaces.state.TeammateState` at a time that is N (N − 1) checked objects a tick, and a law that
reads them one by one (phase keeping over the team) costs each UAV O(N) Python steps: a team's cost per UAV would
grow with the team. :class:`TeamStates` is built once per tick (one check per array), each agent gets a view
without itself, and :func:`teammates_xy` / :func:`teammate_slots` read its stacked arrays in one operation; for any
other sequence of teammates (a radio's inbox, a test's list) they fall back to the per-teammate arithmetic, bit for
bit the same.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from interfaces._checks import finite_number
from interfaces.state import TeammateState

__all__ = ["TeamStates", "teammate_slots", "teammates_xy"]


class TeamStates(tuple):
    """A tuple of :class:`TeammateState` (no plans, ``phase_slot`` None) with the team's arrays stacked.

    Attributes
    ----------
    p_W, v_W : np.ndarray
        (n, 3) read-only positions (m) and velocities (m/s); row k is ``self[k].p_W`` / ``self[k].v_W``.
    t : np.ndarray
        (n,) times of the states (s).
    ids : np.ndarray
        (n,) team indices (and phase slots) of the states.
    """

    p_W: np.ndarray
    v_W: np.ndarray
    t: np.ndarray
    ids: np.ndarray

    def __new__(cls, states: Sequence[TeammateState], p_W: np.ndarray, v_W: np.ndarray, t: np.ndarray,
                ids: np.ndarray) -> TeamStates:
        team = super().__new__(cls, states)
        team.p_W, team.v_W, team.t, team.ids = p_W, v_W, t, ids
        return team

    def __reduce__(self) -> tuple:
        """Pickle and copy with the stacked arrays (a tuple subclass's default would call ``__new__`` without them)."""
        return (TeamStates, (tuple(self), self.p_W, self.v_W, self.t, self.ids))

    @classmethod
    def of(cls, t: float, p_W: np.ndarray, v_W: np.ndarray, yaw: Sequence[float]) -> TeamStates:
        """The states of a whole team at ``t`` (s), member ``j`` with id ``j``: (N, 3) positions ``p_W`` (m), (N, 3)
        velocities ``v_W`` (m/s) and (N,) yaws (rad).

        Member j equals ``TeammateState(id=j, t=t, p_W=p_W[j], v_W=v_W[j], yaw=yaw[j])`` field for field, but the
        arrays are checked once for the team, not four fields per member. Raises ``ValueError`` naming the field, as
        the constructor does.
        """
        t = finite_number("TeammateState", "t", t)
        P = _rows("p_W", p_W)
        V = _rows("v_W", v_W)
        psi = np.array(yaw, dtype=float).reshape(-1)
        n = P.shape[0]
        if V.shape[0] != n or psi.shape[0] != n:
            raise ValueError(f"TeamStates.of needs one p_W, v_W and yaw per member, got {n}, {V.shape[0]} and "
                             f"{psi.shape[0]}")
        if not np.isfinite(psi).all():
            raise ValueError(f"TeammateState.yaw must be a finite number, got {yaw!r}")
        states = []
        for j in range(n):
            state = object.__new__(TeammateState)  # the fields as __post_init__ leaves them, not checked one by one
            state.__dict__.update(id=j, t=t, p_W=P[j], v_W=V[j], yaw=float(psi[j]), phase_slot=None, plan_p_W=None,
                                  plan_dt=1.0)
            states.append(state)
        times = np.full(n, t)
        times.setflags(write=False)
        ids = np.arange(n)
        ids.setflags(write=False)
        return cls(states, P, V, times, ids)

    def without(self, k: int) -> TeamStates:
        """The team less its ``k``-th member (what that member knows of its teammates): the same state objects."""
        keep = np.arange(len(self) - 1)
        keep[k:] += 1
        return TeamStates(self[:k] + self[k + 1:], self.p_W[keep], self.v_W[keep], self.t[keep], self.ids[keep])


def _rows(name: str, value: np.ndarray) -> np.ndarray:
    """``value`` as a read-only (N, 3) float copy (its rows are the members' read-only vectors); raises
    ``ValueError`` naming the field otherwise."""
    arr = np.array(value, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3 or not np.isfinite(arr).all():
        raise ValueError(f"TeammateState.{name} must be a finite array of length 3 per member, got shape {arr.shape}")
    arr.setflags(write=False)
    return arr


def teammates_xy(teammates: Sequence[TeammateState], t: float) -> np.ndarray:
    """(len(teammates), 2) horizontal positions (m) of ``teammates`` at ``t`` (s); row k equals
    ``teammates[k].predict_xy([t])[0]`` bit for bit.

    Teammates without a plan are extrapolated together, p + (t − t_k) v (the arithmetic of
    :meth:`TeammateState.predict_xy`), straight from the arrays of a :class:`TeamStates`; those with a plan are
    interpolated one by one.
    """
    if isinstance(teammates, TeamStates):
        return teammates.p_W[:, :2] + (t - teammates.t)[:, None] * teammates.v_W[:, :2]
    n = len(teammates)
    out = np.empty((n, 2))
    plain = [k for k, tm in enumerate(teammates) if tm.plan_p_W is None]
    if plain:
        P = np.array([teammates[k].p_W[:2] for k in plain])
        V = np.array([teammates[k].v_W[:2] for k in plain])
        dt = t - np.array([teammates[k].t for k in plain])
        out[plain] = P + dt[:, None] * V
    at = np.array([t], dtype=float)
    for k, tm in enumerate(teammates):
        if tm.plan_p_W is not None:
            out[k] = tm.predict_xy(at)[0]
    return out


def teammate_slots(teammates: Sequence[TeammateState]) -> np.ndarray:
    """(len(teammates),) phase slots of ``teammates`` (:attr:`TeammateState.slot`)."""
    if isinstance(teammates, TeamStates):
        return teammates.ids
    return np.array([tm.slot for tm in teammates], dtype=int)
