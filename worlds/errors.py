"""Errors raised for bad world files: each names the file, the key path, the bad value and what was expected."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["WorldError", "WorldIssue", "format_path"]


def format_path(loc: tuple[str | int, ...]) -> str:
    """``("uavs", 1, "sensors", 0, "rate_hz")`` -> ``"uavs[1].sensors[0].rate_hz"``."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out or "<top level>"


@dataclass(frozen=True)
class WorldIssue:
    """One problem in a world file.

    Attributes
    ----------
    path : str
        Key path inside the file, e.g. ``uavs[1].sensors[0].rate_hz`` (``<top level>`` for the whole file).
    value : object
        The offending value as read (``None`` when the key is missing).
    expected : str
        What would have been accepted.
    line : int | None
        1-based line in the file where the key stands, when known.
    """

    path: str
    value: object
    expected: str
    line: int | None = None

    def render(self, file: str) -> str:
        where = f"{file}:{self.line}" if self.line else file
        value = _short(self.value)
        return f"{where}: {self.path} = {value}: expected {self.expected}"


def _short(value: object, limit: int = 80) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


MAX_SHOWN = 50
"""Most issues ``str(WorldError)`` lists, one per line; the rest are counted (``issues`` holds them all)."""


class WorldError(ValueError):
    """A world file that cannot be used; ``str()`` lists every issue, one per line (the first :data:`MAX_SHOWN`)."""

    def __init__(self, file: str, issues: list[WorldIssue]) -> None:
        self.file = file
        self.issues = list(issues)
        n = len(self.issues)
        lines = [f"invalid world {file} ({n} problem{'s' if n != 1 else ''}):"]
        lines += ["  " + issue.render(file) for issue in self.issues[:MAX_SHOWN]]
        if n > MAX_SHOWN:
            lines.append(f"  ... and {n - MAX_SHOWN} more problems")
        super().__init__("\n".join(lines))
