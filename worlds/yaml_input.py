"""Reading world files and ``--set`` values under limits, so that no input makes the loader hang, exhaust memory or
fail with anything but :class:`worlds.errors.WorldError`.

A world file is UTF-8 text of at most :data:`MAX_WORLD_BYTES`. Its YAML is read with PyYAML's safe loader, without
tags (``!!python/...`` builds Python objects in unsafe loaders; ``!!timestamp x`` breaks PyYAML's own constructors).
While the node graph is composed the values are counted as if every alias were copied out — the form the loader works
on (:func:`unshared`) — and reading stops at the first value past :data:`MAX_NODES` or the first mapping or list
deeper than :data:`MAX_DEPTH`, before anything is built from the file. A 400-byte "billion laughs" file (aliases of
aliases of lists) is a few hundred composed nodes but hundreds of millions of values once expanded; it is refused at
its fifth line. A recursive alias (``&a [*a]``) is refused too.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

__all__ = ["MAX_DEPTH", "MAX_NODES", "MAX_WORLD_BYTES", "YamlInputError", "check_shape", "parse_yaml",
           "read_world_text", "unshared"]

MAX_WORLD_BYTES = 1_000_000
"""bytes: the largest world file read. Shipped worlds are 2-12 kB; road maps and town layouts come from their own
files (``roads.osm.path``) or generators (``roads.town``), so a hand-written world needs nothing near this. PyYAML
reads about 1 MB/s, so the limit also bounds the time the loader takes."""

MAX_DEPTH = 32
"""Deepest nesting of mappings and lists (counting the top-level mapping as 1). Shipped worlds nest 8 deep; the
schema's deepest key path (a sensor's confusion matrix row) is 9."""

MAX_NODES = 20_000
"""Most values (mappings, lists and scalars) of a world after its YAML aliases are expanded. Shipped worlds hold
100-700. PyYAML composes about 20 000 values a second, so the limit bounds the time the loader takes, whatever the
file holds."""


class YamlInputError(ValueError):
    """Input that cannot be read as a world's YAML; ``problem`` says why, ``line`` (1-based) where, when known."""

    def __init__(self, problem: str, line: int | None = None) -> None:
        super().__init__(problem)
        self.problem = problem
        self.line = line


def read_world_text(path: Path) -> str:
    """The text of the world file ``path``: UTF-8 (with or without a byte-order mark), at most
    :data:`MAX_WORLD_BYTES`.

    Raises
    ------
    YamlInputError
        Saying what was expected and what the file is instead: too large, binary (NUL bytes), UTF-16/32, or not
        UTF-8 (with the line and the byte).
    OSError
        When the file cannot be read at all.
    """
    with path.open("rb") as f:
        data = f.read(MAX_WORLD_BYTES + 1)
    if len(data) > MAX_WORLD_BYTES:
        size = path.stat().st_size
        raise YamlInputError(f"a world file of at most {MAX_WORLD_BYTES} bytes (this one is {size} bytes; maps and "
                             "towns come from roads.osm or roads.town)")
    for bom, name in ((b"\xff\xfe\x00\x00", "UTF-32"), (b"\x00\x00\xfe\xff", "UTF-32"),
                      (b"\xff\xfe", "UTF-16"), (b"\xfe\xff", "UTF-16")):
        if data.startswith(bom):
            raise YamlInputError(f"UTF-8 text (this file starts with a {name} byte-order mark: save it as UTF-8)")
    if b"\x00" in data:
        line = data.count(b"\n", 0, data.index(b"\x00")) + 1
        raise YamlInputError("UTF-8 text (this file holds NUL bytes: it is binary, or UTF-16/32 text without a "
                             "byte-order mark)", line)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise YamlInputError(f"UTF-8 text (byte 0x{data[exc.start]:02x} on line {line} is not UTF-8: Latin-1 or "
                             "another legacy encoding? save the file as UTF-8)", line) from None


class _LimitedLoader(yaml.SafeLoader):
    """PyYAML's safe loader, counting the values of the document as they are composed, each alias as the values of
    its anchor's node (its copy in :func:`unshared`), and stopping at the first node beyond the limits: the scanner
    reads lazily, so an oversized file is never read to its end."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._level = 0  # nesting level of the node being composed (the top-level mapping is level 1)
        self._values = 0  # values composed so far, aliases expanded
        self._sizes: dict[int, tuple[int, int]] = {}  # id(node) -> (values, depth) of a composed node

    def compose_node(self, parent: Any, index: Any) -> Any:
        event = self.peek_event()
        line = event.start_mark.line + 1
        if getattr(event, "tag", None) is not None:
            raise YamlInputError(f"no YAML tags (this value is tagged {event.tag!r}): world files hold plain "
                                 "mappings, lists, strings, numbers and booleans", line)
        alias = self.check_event(yaml.AliasEvent)
        self._level += 1
        try:
            if self.check_event(yaml.MappingStartEvent, yaml.SequenceStartEvent) and self._level > MAX_DEPTH:
                raise YamlInputError(f"nesting at most {MAX_DEPTH} deep (mappings and lists inside each other)",
                                     line)
            if not alias:
                self._count(1, line)
            node = super().compose_node(parent, index)
            if alias:
                if id(node) not in self._sizes:  # the anchor's node is still being composed
                    raise YamlInputError("no alias to a node that contains it (a recursive structure)", line)
                values, depth = self._sizes[id(node)]
                self._count(values, line)
                if self._level + depth - 1 > MAX_DEPTH:
                    raise YamlInputError(f"nesting at most {MAX_DEPTH} deep with aliases expanded (this alias "
                                         f"reaches {self._level + depth - 1})", line)
            else:
                self._measure(node)
            return node
        finally:
            self._level -= 1

    def _count(self, values: int, line: int) -> None:
        self._values += values
        if self._values > MAX_NODES:
            raise YamlInputError(f"at most {MAX_NODES} values (mappings, lists and scalars, aliases expanded): "
                                 f"here the count passes {MAX_NODES}", line)

    def _measure(self, node: yaml.Node) -> None:
        """Record the values and depth of a composed node (a scalar: 1 and 0), its aliases expanded."""
        if isinstance(node, yaml.MappingNode):
            children = [n for pair in node.value for n in pair]
        elif isinstance(node, yaml.SequenceNode):
            children = list(node.value)
        else:
            self._sizes[id(node)] = (1, 0)
            return
        values, depth = 1, 1
        for child in children:
            v, d = self._sizes[id(child)]
            values += v
            depth = max(depth, d + 1)
        self._sizes[id(node)] = (values, depth)


def parse_yaml(text: str) -> tuple[Any, yaml.Node | None]:
    """The data of one YAML document and its composed node graph (None for an empty document), read under the
    limits of this module.

    Raises
    ------
    YamlInputError
        For invalid YAML, a tagged value (``!!python/...``, ``!!timestamp ...``), a number it cannot read, or input
        beyond :data:`MAX_DEPTH` / :data:`MAX_NODES`.
    """
    loader = None
    try:
        loader = _LimitedLoader(text)  # the reader refuses control characters here
        node = loader.get_single_node()
        data = loader.construct_document(node) if node is not None else None
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        raise YamlInputError(f"valid YAML (character #x{exc.character:04x} on line {line} is a control character, "
                             "which YAML does not allow)", line) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc)
        raise YamlInputError(f"valid YAML ({problem})", mark.line + 1 if mark is not None else None) from None
    except (ValueError, OverflowError) as exc:
        if isinstance(exc, YamlInputError):
            raise
        raise YamlInputError(f"valid YAML values ({exc})") from None
    finally:
        if loader is not None:
            loader.dispose()
    return data, node


def unshared(node: Any) -> Any:
    """A copy of parsed YAML in which no mapping or list is shared: each alias becomes a copy of its anchor's node
    (``copy.deepcopy`` would keep the sharing). Bounded by :data:`MAX_NODES` for what :func:`parse_yaml` returns."""
    if isinstance(node, dict):
        return {k: unshared(v) for k, v in node.items()}
    if isinstance(node, list):
        return [unshared(v) for v in node]
    return node


def check_shape(data: Any) -> None:
    """Raise :class:`YamlInputError` when ``data`` (a world after its ``--set`` overrides) nests deeper than
    :data:`MAX_DEPTH` or holds more than :data:`MAX_NODES` values; iterative, so any input is measured safely."""
    stack: list[tuple[Any, int]] = [(data, 1)]
    values = 0
    while stack:
        node, depth = stack.pop()
        values += 1
        if values > MAX_NODES:
            raise YamlInputError(f"at most {MAX_NODES} values in the world with its overrides")
        if isinstance(node, dict | list):
            if depth > MAX_DEPTH:
                raise YamlInputError(f"nesting at most {MAX_DEPTH} deep in the world with its overrides")
            children = node.values() if isinstance(node, dict) else node
            stack.extend((child, depth + 1) for child in children)
