"""Loading user classes named by import path (``package.module:Class``) in world files."""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["PluginError", "load_plugin"]


class PluginError(ValueError):
    """A plugin path that cannot be imported or does not name a usable class."""


def load_plugin(path: str, where: str, required: tuple[str, ...]) -> type:
    """Import ``package.module:Name`` and check it has the ``required`` methods.

    Parameters
    ----------
    path : str
        ``"package.module:Name"``.
    where : str
        Key path of the world-file entry, for the error message.
    required : tuple[str, ...]
        Method names the class must have.
    """
    module_name, _, attr = path.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise PluginError(f"{where}: cannot import module {module_name!r} of plugin {path!r}: {exc}") from None
    obj: Any = getattr(module, attr, None)
    if obj is None:
        raise PluginError(f"{where}: module {module_name!r} has no attribute {attr!r} (plugin {path!r})")
    missing = [m for m in required if not callable(getattr(obj, m, None))]
    if missing:
        raise PluginError(f"{where}: plugin {path!r} lacks method(s) {', '.join(missing)}")
    return obj
