"""The NMPC's parameter vector ``p``: its named slices, declared once, packed by the guidance and unpacked by the
problem.

    p = (x_0 (5), p_t (2), v_t (2),
         per teammate slot j:  active_j, cos φ_j, sin φ_j, q_j,1 … q_j,N (2 each: x, y),
         per keep-out slot b:  active_b, c_b (2), cos ψ_b, sin ψ_b, 1/α_b, 1/β_b)

x_0 is the initial state (x, y, heading, speed, heading rate), p_t and v_t the target's position and velocity, φ_j
the desired phase of this UAV minus that of teammate j and q_j,k its predicted positions; c_b, ψ_b, α_b, β_b the
centre, yaw and semi-axes of a keep-out ellipse (:meth:`autonomy.guidance.keepout.KeepOutEllipse.params`). Slots
left unused are packed inactive (``active = 0``) with harmless values (the teammate far away, the ellipse a unit
circle far away), so their constraint rows read 1 + s ≥ 0 and never bind.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import casadi as ca
import numpy as np

__all__ = ["KEEPOUT_WIDTH", "NX", "NU", "NmpcParameters", "ParameterLayout", "TeammateSlot"]

NX, NU = 5, 2  # state (x, y, heading, speed, heading rate) and control (speed, heading-rate commands)
KEEPOUT_WIDTH = 6  # cx, cy, cos ψ, sin ψ, 1/α, 1/β
_FAR = 1e6  # position of an unused slot's teammate or keep-out centre, m
_INACTIVE_TEAMMATE = (0.0, 1.0, 0.0)  # active, cos φ, sin φ
_INACTIVE_KEEPOUT = (0.0, _FAR, _FAR, 1.0, 0.0, 1.0, 1.0)


class TeammateSlot(NamedTuple):
    """One teammate slot of ``p`` (numbers or CasADi expressions): ``plan`` is (2, N), column k the position at
    step k + 1."""

    active: Any
    cos_phase: Any
    sin_phase: Any
    plan: Any


class NmpcParameters(NamedTuple):
    """``p`` unpacked by :meth:`ParameterLayout.unpack`: ``keepouts`` are the 7-vectors (active, cx, cy, cos ψ,
    sin ψ, 1/α, 1/β) of the keep-out slots."""

    x0: Any
    target_position: Any
    target_velocity: Any
    teammates: list[TeammateSlot]
    keepouts: list[Any]


@dataclass(frozen=True)
class ParameterLayout:
    """Where each quantity sits in ``p`` for horizon ``horizon``, ``n_teammates`` teammate slots and
    ``n_keepouts`` keep-out slots.

    Attributes
    ----------
    x0, target_position, target_velocity : slice
        The initial state, the target's position and its velocity.
    """

    horizon: int
    n_teammates: int
    n_keepouts: int

    x0 = slice(0, NX)
    target_position = slice(NX, NX + 2)
    target_velocity = slice(NX + 2, NX + 4)

    @property
    def teammate_width(self) -> int:
        """Entries per teammate slot: active, cos φ, sin φ and the 2N planned positions."""
        return 3 + 2 * self.horizon

    @property
    def keepout_width(self) -> int:
        """Entries per keep-out slot: active and the ellipse's six numbers."""
        return 1 + KEEPOUT_WIDTH

    @property
    def size(self) -> int:
        """Length of ``p``."""
        return NX + 4 + self.n_teammates * self.teammate_width + self.n_keepouts * self.keepout_width

    def teammate(self, j: int) -> slice:
        """Slot ``j`` of the teammates."""
        if not 0 <= j < self.n_teammates:
            raise IndexError(f"teammate slot {j} of {self.n_teammates}")
        start = NX + 4 + j * self.teammate_width
        return slice(start, start + self.teammate_width)

    def keepout(self, b: int) -> slice:
        """Slot ``b`` of the keep-outs."""
        if not 0 <= b < self.n_keepouts:
            raise IndexError(f"keep-out slot {b} of {self.n_keepouts}")
        start = NX + 4 + self.n_teammates * self.teammate_width + b * self.keepout_width
        return slice(start, start + self.keepout_width)

    def pack(self, *, x0: np.ndarray, target_position: np.ndarray, target_velocity: np.ndarray,
             teammates: Sequence[tuple[float, float, np.ndarray]] = (),
             keepouts: Sequence[np.ndarray] = ()) -> np.ndarray:
        """``p`` for the given quantities.

        Parameters
        ----------
        x0 : np.ndarray
            Initial state (5,).
        target_position, target_velocity : np.ndarray
            Target position (2,) m and velocity (2,) m/s.
        teammates : sequence of (cos φ, sin φ, plan)
            The active teammates, ``plan`` (N, 2) m their positions at steps 1..N; at most ``n_teammates``, the
            remaining slots are packed inactive.
        keepouts : sequence of np.ndarray
            The active keep-out ellipses (cx, cy, cos ψ, sin ψ, 1/α, 1/β); at most ``n_keepouts``.
        """
        if len(teammates) > self.n_teammates or len(keepouts) > self.n_keepouts:
            raise ValueError(f"{len(teammates)} teammates / {len(keepouts)} keep-outs for {self.n_teammates} / "
                             f"{self.n_keepouts} slots")
        p = np.empty(self.size)
        p[self.x0] = x0
        p[self.target_position] = target_position
        p[self.target_velocity] = target_velocity
        n = self.horizon
        for j in range(self.n_teammates):
            s = self.teammate(j)
            if j < len(teammates):
                cos_phase, sin_phase, plan = teammates[j]
                p[s.start:s.start + 3] = (1.0, cos_phase, sin_phase)
                p[s.start + 3:s.stop] = np.asarray(plan, dtype=float).reshape(n, 2).reshape(-1)
            else:
                p[s.start:s.start + 3] = _INACTIVE_TEAMMATE
                p[s.start + 3:s.stop] = _FAR
        for b in range(self.n_keepouts):
            s = self.keepout(b)
            if b < len(keepouts):
                p[s.start] = 1.0
                p[s.start + 1:s.stop] = keepouts[b]
            else:
                p[s] = _INACTIVE_KEEPOUT
        return p

    def unpack(self, p: Any) -> NmpcParameters:
        """The named parts of ``p``: a numpy vector or a CasADi symbol (the problem's own unpacking)."""
        n = self.horizon
        symbolic = isinstance(p, ca.SX | ca.MX | ca.DM)
        teammates = []
        for j in range(self.n_teammates):
            o = self.teammate(j).start
            flat = p[o + 3:o + 3 + 2 * n]
            plan = ca.reshape(flat, 2, n) if symbolic else np.asarray(flat).reshape(n, 2).T
            teammates.append(TeammateSlot(p[o], p[o + 1], p[o + 2], plan))
        keepouts = [p[self.keepout(b)] for b in range(self.n_keepouts)]
        return NmpcParameters(p[self.x0], p[self.target_position], p[self.target_velocity], teammates, keepouts)
