"""Load a world file by name or path, apply ``--set`` overrides and validate it, before anything runs.

``load_world("road_standoff")`` finds ``worlds/road_standoff.yaml`` shipped with the package; any other argument is a
path.
Every problem — missing file, bad YAML, unknown key, wrong type, a number that is not finite or out of its physical
range, a rate that does not divide the physics rate (the car driver's own rate included), a route naming no road —
raises :class:`worlds.errors.WorldError` naming the file, the key path, the bad value and what was expected, before
anything is built. So does hostile input: a file that is not UTF-8 text or larger than 1 MB, YAML nested too deep or
exploding through aliases, tags, a ``--set`` value that is not YAML (:mod:`worlds.yaml_input` bounds what is read,
so a load takes about a second at most).
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
from worlds.yaml_input import MAX_DEPTH, YamlInputError, check_shape, parse_yaml, read_world_text, unshared

__all__ = ["LoadedWorld", "OverrideError", "load_world", "parse_override", "shipped_worlds", "world_path"]

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


class OverrideError(ValueError):
    """A ``--set`` line that cannot be applied; ``expected`` says what would have been accepted."""

    def __init__(self, expected: str) -> None:
        super().__init__(expected)
        self.expected = expected


def parse_override(text: str) -> tuple[list[str | int], Any]:
    """``"sim.duration_s=30"`` -> (["sim", "duration_s"], 30). The value is read as YAML (``[1, 2, 3]``, ``true``,
    ``null``) under the limits of the world files' YAML (:func:`worlds.yaml_input.parse_yaml`).

    Raises
    ------
    OverrideError
        (a ``ValueError``) when the line is no ``key.path=value``, the key path is malformed or deeper than
        :data:`worlds.yaml_input.MAX_DEPTH`, or the value is not valid YAML (a tag such as ``!!python/...``
        included).
    """
    if "=" not in text:
        raise OverrideError(f"key.path=value naming an existing place (override {text!r} must look like "
                            "key.path=value)")
    key, value = text.split("=", 1)
    try:
        keys = parse_key_path(key.strip())
    except ValueError as exc:
        raise OverrideError(f"key.path=value naming an existing place ({exc})") from None
    if len(keys) > MAX_DEPTH:
        raise OverrideError(f"a key path of at most {MAX_DEPTH} parts (this one has {len(keys)})")
    if not value.strip():
        return keys, ""
    try:
        data, _ = parse_yaml(value)
    except YamlInputError as exc:
        raise OverrideError(f"a YAML value after '=': {exc.problem}") from None
    return keys, data


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


def _line_index(root: yaml.Node | None) -> dict[tuple, int]:
    """Map key paths to 1-based line numbers by walking YAML's node tree (best effort; the tree is bounded by
    :func:`worlds.yaml_input.parse_yaml`'s limits, aliases expanded)."""
    lines: dict[tuple, int] = {}

    def walk(node: Any, loc: tuple) -> None:
        lines.setdefault(loc, node.start_mark.line + 1)
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                key = k.value if isinstance(k, yaml.ScalarNode) else repr(k.value)
                lines[loc + (key,)] = k.start_mark.line + 1
                walk(v, loc + (key,))
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                walk(v, loc + (i,))

    if root is not None:
        walk(root, ())
    return lines


def _first_line(text: str, line: int | None) -> str:
    """The text of 1-based ``line`` (what the YAML problem is about), or the file's first line."""
    rows = text.splitlines()
    if not rows:
        return ""
    row = rows[line - 1] if line is not None and 1 <= line <= len(rows) else rows[0]
    return row.strip()


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
    try:
        text = read_world_text(path)
    except OSError as exc:
        raise WorldError(file, [WorldIssue("<file>", str(source), f"a readable world file ({exc})")]) from None
    except YamlInputError as exc:
        raise WorldError(file, [WorldIssue("<file>", str(source), exc.problem, exc.line)]) from None
    try:
        raw, root = parse_yaml(text)
    except YamlInputError as exc:
        raise WorldError(file, [WorldIssue("<yaml>", _first_line(text, exc.line), exc.problem, exc.line)]) from None
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise WorldError(file, [WorldIssue("<top level>", raw, "a mapping of sections (sim, uavs, ...)", 1)])
    raw = unshared(raw)  # YAML aliases (&a ... *a) load as one shared object: an override must change one place
    lines = _line_index(root)
    issues: list[WorldIssue] = []
    for ov in overrides:
        try:
            keys, value = parse_override(ov)
        except OverrideError as exc:
            issues.append(WorldIssue(f"--set {ov}", ov, exc.expected))
            continue
        try:
            _apply_override(raw, keys, value)
        except (ValueError, KeyError) as exc:
            issues.append(WorldIssue(f"--set {ov}", ov, f"key.path=value naming an existing place ({exc})"))
    if not issues and overrides:
        try:
            check_shape(raw)
        except YamlInputError as exc:
            issues.append(WorldIssue("--set", list(overrides), exc.problem))
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
