"""Load a world file by name or path, apply ``--set`` overrides and validate it, before anything runs.

``load_world("road_standoff")`` finds ``worlds/road_standoff.yaml`` shipped with the package; any other argument is a
path.
Every problem — missing file, bad YAML, unknown key, wrong type, a number that is not finite or out of its physical
range, a rate that does not divide the physics rate (the car driver's own rate included), a route naming no road —
raises :class:`worlds.errors.WorldError` naming the file, the key path, the bad value and what was expected, before
anything is built.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from worlds.checks import check_world
from worlds.errors import WorldError, WorldIssue, format_path
from worlds.schema import World

__all__ = ["LoadedWorld", "load_world", "parse_override", "shipped_worlds", "world_path"]

_PATH_TOKEN = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


@dataclass(frozen=True)
class LoadedWorld:
    """A validated world and where it came from."""

    world: World
    path: Path
    raw: dict[str, Any]

    @property
    def name(self) -> str:
        return self.world.name


def shipped_dir() -> Path:
    return Path(str(resources.files("worlds")))


def shipped_worlds() -> dict[str, Path]:
    """Shipped world files by name (file stem)."""
    return {p.stem: p for p in sorted(shipped_dir().glob("*.yaml"))}


def world_path(source: str | Path) -> Path:
    """Resolve a world name (``road_standoff``) or a path to a file path (which may not exist)."""
    text = str(source)
    shipped = shipped_worlds()
    if text in shipped:
        return shipped[text]
    return Path(text)


def parse_key_path(key: str) -> list[str | int]:
    """``"uavs[1].sensors.0.rate_hz"`` -> ``["uavs", 1, "sensors", 0, "rate_hz"]``."""
    parts: list[str | int] = []
    pos = 0
    for m in _PATH_TOKEN.finditer(key):
        if key[pos:m.start()] not in ("", "."):
            raise ValueError(f"bad key path {key!r}")
        pos = m.end()
        name, index = m.groups()
        if index is not None:
            parts.append(int(index))
        elif name.isdigit():
            parts.append(int(name))
        else:
            parts.append(name)
    if not parts or pos != len(key):
        raise ValueError(f"bad key path {key!r}")
    return parts


def parse_override(text: str) -> tuple[list[str | int], Any]:
    """``"sim.duration_s=30"`` -> (["sim", "duration_s"], 30). The value is read as YAML (``[1, 2, 3]``, ``true``,
    ``null``)."""
    if "=" not in text:
        raise ValueError(f"override {text!r} must look like key.path=value")
    key, value = text.split("=", 1)
    return parse_key_path(key.strip()), yaml.safe_load(value) if value.strip() else ""


def _apply_override(raw: dict[str, Any], keys: list[str | int], value: Any) -> None:
    node: Any = raw
    for i, k in enumerate(keys[:-1]):
        nxt = keys[i + 1]
        if isinstance(k, int):
            if not isinstance(node, list) or k >= len(node):
                raise KeyError(format_path(tuple(keys[: i + 1])))
            node = node[k]
        else:
            if not isinstance(node, dict):
                raise KeyError(format_path(tuple(keys[: i + 1])))
            if k not in node or node[k] is None:
                node[k] = [] if isinstance(nxt, int) else {}
            node = node[k]
    last = keys[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or last > len(node):
            raise KeyError(format_path(tuple(keys)))
        if last == len(node):
            node.append(value)
        else:
            node[last] = value
    else:
        if not isinstance(node, dict):
            raise KeyError(format_path(tuple(keys)))
        node[last] = value


def _unshared(node: Any) -> Any:
    """A copy of parsed YAML in which no mapping or list is shared: each alias becomes a copy of its anchor's node
    (``copy.deepcopy`` would keep the sharing)."""
    if isinstance(node, dict):
        return {k: _unshared(v) for k, v in node.items()}
    if isinstance(node, list):
        return [_unshared(v) for v in node]
    return node


def _line_index(text: str) -> dict[tuple, int]:
    """Map key paths to 1-based line numbers by walking YAML's node tree (best effort)."""
    lines: dict[tuple, int] = {}
    try:
        root = yaml.compose(text)
    except yaml.YAMLError:
        return lines

    def walk(node: Any, loc: tuple) -> None:
        lines.setdefault(loc, node.start_mark.line + 1)
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                key = k.value
                lines[loc + (key,)] = k.start_mark.line + 1
                walk(v, loc + (key,))
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                walk(v, loc + (i,))

    if root is not None:
        walk(root, ())
    return lines


def _lookup_line(lines: dict[tuple, int], loc: tuple) -> int | None:
    loc = tuple(loc)
    while loc:
        if loc in lines:
            return lines[loc]
        loc = loc[:-1]
    return None


def _get(raw: Any, loc: tuple) -> Any:
    node = raw
    for k in loc:
        try:
            node = node[k]
        except (KeyError, IndexError, TypeError):
            return None
    return node


def _pydantic_issues(err: ValidationError, raw: dict, lines: dict[tuple, int]) -> list[WorldIssue]:
    issues = []
    for e in err.errors(include_url=False):
        loc = _strip_union_tags(tuple(e["loc"]))
        etype = e["type"]
        if etype == "extra_forbidden":
            expected = "no such key here (unknown keys are errors; check the spelling)"
        elif etype == "missing":
            expected = "a value (this key is required)"
        else:
            expected = _expected_text(e["msg"] or etype)
        value = e.get("input") if etype != "missing" else None
        if isinstance(value, dict) and etype != "extra_forbidden":
            value = _get(raw, loc)
        issues.append(WorldIssue(format_path(loc), value, expected, _lookup_line(lines, loc)))
    return issues


_UNION_TAGS = {"radar", "camera", "bearing", "box"}
"""Discriminator tags pydantic inserts after a sensor's list index: ``uavs.0.sensors.1.radar.rate_hz``."""


def _strip_union_tags(loc: tuple) -> tuple:
    """``loc`` without the sensor-union tags (only right after ``sensors[i]``: ``render.camera`` is a real key)."""
    out: list = []
    for part in loc:
        if part in _UNION_TAGS and len(out) >= 2 and isinstance(out[-1], int) and out[-2] == "sensors":
            continue
        out.append(part)
    return tuple(out)


def _expected_text(msg: str) -> str:
    """Turn pydantic's 'Input should be greater than 0' into 'a value greater than 0'."""
    msg = msg.removeprefix("Value error, ")
    if msg.startswith("Input should be "):
        rest = msg[len("Input should be "):]
        return rest if rest.startswith(("a ", "an ", "'")) else "a value " + rest
    return msg[0].lower() + msg[1:]


def load_world(source: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> LoadedWorld:
    """Read, override and validate a world.

    Parameters
    ----------
    source : str | Path
        A shipped world's name (see :func:`shipped_worlds`) or a path to a YAML file.
    overrides : list[str]
        ``key.path=value`` strings applied to the file's data before validation (values parsed as YAML).

    Raises
    ------
    WorldError
        On any problem, naming the file, the key path, the value and what was expected.
    """
    path = world_path(source)
    file = str(path)
    if not path.is_file():
        known = ", ".join(shipped_worlds()) or "none"
        raise WorldError(file, [WorldIssue("<file>", str(source),
                                           f"an existing world file or a shipped world name ({known})")])
    text = path.read_text(encoding="utf-8")
    try:
        raw = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = mark.line + 1 if mark is not None else None
        problem = getattr(exc, "problem", None) or str(exc)
        raise WorldError(file, [WorldIssue("<yaml>", problem, "valid YAML", line)]) from None
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise WorldError(file, [WorldIssue("<top level>", raw, "a mapping of sections (sim, uavs, ...)", 1)])
    raw = _unshared(raw)  # YAML aliases (&a ... *a) load as one shared object: an override must change one place
    lines = _line_index(text)
    issues: list[WorldIssue] = []
    for ov in overrides:
        try:
            keys, value = parse_override(ov)
            _apply_override(raw, keys, value)
        except (ValueError, KeyError) as exc:
            issues.append(WorldIssue(f"--set {ov}", ov, f"key.path=value naming an existing place ({exc})"))
    if issues:
        raise WorldError(file, issues)
    try:
        world = World.model_validate(raw)
    except ValidationError as exc:
        raise WorldError(file, _pydantic_issues(exc, raw, lines)) from None
    issues = [WorldIssue(i.path, i.value, i.expected, _lookup_line(lines, tuple(parse_key_path(i.path))))
              for i in check_world(world)]
    if issues:
        raise WorldError(file, issues)
    return LoadedWorld(world=world, path=path.resolve(), raw=raw)
