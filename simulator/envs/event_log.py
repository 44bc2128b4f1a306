"""The record an environment episode keeps: no files, only the collisions the tick reports.

An episode runs the same tick as ``skytrack run`` (:meth:`simulator.tick.Assembly.step`), which writes its streams
and events through a :class:`~simulator.record.RunRecorder`. Thousands of training episodes must not each leave a run
directory behind, so this stands in for the recorder: rows are dropped, and of the events only the collisions are
kept, for the environment to end an episode on."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["Collision", "EventLog"]


@dataclass(frozen=True)
class Collision:
    """A contact of UAV ``uav`` (index) with ``other`` (``ground``, ``building``, ``uav <id>``, ``vehicle <id>``) that
    began at ``tick``."""

    tick: int
    uav: int
    other: str


@dataclass
class EventLog:
    """A :class:`~simulator.record.RunRecorder` that writes nothing and keeps the collision events."""

    collisions: list[Collision] = field(default_factory=list)
    event_counts: dict[str, int] = field(default_factory=dict)
    closed: bool = False

    def event(self, type: str, tick: int | None = None, t: float | None = None, /, **fields: Any) -> None:  # noqa: A002
        self.event_counts[type] = self.event_counts.get(type, 0) + 1
        if type == "collision":
            self.collisions.append(Collision(int(tick or 0), int(fields["uav"]), str(fields.get("other", ""))))

    def collided(self, uav: int, after_tick: int) -> bool:
        """Whether UAV ``uav`` began a contact after tick ``after_tick``."""
        return any(c.uav == uav and c.tick > after_tick for c in self.collisions)

    def append(self, stream: str, **row: Any) -> None:
        pass

    def append_rows(self, stream: str, columns: dict[str, Any]) -> None:
        pass

    def append_line(self, name: str, data: Any) -> None:
        pass

    def write_text(self, name: str, text: str, sync: bool = True) -> Path:
        return Path(name)

    def write_json(self, name: str, data: Any, sync: bool = True) -> Path:
        return Path(name)

    def flush(self, metrics: dict[str, Any] | None = None, sync: bool = True) -> None:
        pass

    def close(self) -> None:
        self.closed = True
