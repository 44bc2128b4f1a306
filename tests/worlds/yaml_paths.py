"""Every key path of a parsed YAML document: the places the world-file fuzz tests mutate."""

from __future__ import annotations


def key_paths(node: object, loc: tuple = ()) -> list[tuple]:
    """The paths (tuples of keys and list indices) of every node under ``node``, ``node`` itself excluded."""
    out = [loc] if loc else []
    if isinstance(node, dict):
        for key, value in node.items():
            out += key_paths(value, loc + (key,))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            out += key_paths(value, loc + (i,))
    return out
