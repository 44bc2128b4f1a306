"""Base-station reporting (paper 001): each member tracks alone with an information filter and reports its scans'
information to a base station, which fuses what arrives.

The members' estimators are :class:`autonomy.fusion.base_station.InformationReporter`; the base (routes, packets
over the radio, its information filter, its record) is engine-side and reaches the protocol as a
:class:`BaseLink`, stepped once all due members have acted.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol

from autonomy.fusion.base_station import InformationReporter
from autonomy.team.base import TeamContext, TeamMember, TeamProtocol

__all__ = ["BaseLink", "BaseStationTeam"]


class BaseLink(Protocol):
    """The base station as the team sees it."""

    def step(self, tick: int, t: float, due: Sequence[int]) -> None:
        """Route, send, fuse and record the contributions of the members ``due`` (UAV indices) at ``tick``."""
        ...


class BaseStationTeam(TeamProtocol):
    """Members reporting to a base station (module docstring).

    Parameters
    ----------
    reporters : mapping of int to InformationReporter
        Each member's estimator, by UAV index.
    """

    def __init__(self, reporters: Mapping[int, InformationReporter]) -> None:
        super().__init__(sorted(reporters))
        self.reporters = dict(reporters)
        self.base: BaseLink | None = None

    def end_step(self, members: Sequence[TeamMember], ctx: TeamContext) -> None:
        if members and self.base is not None:
            self.base.step(ctx.tick, ctx.t, [m.uav for m in members])
