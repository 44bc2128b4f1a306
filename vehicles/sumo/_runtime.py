"""Where SUMO lives: the eclipse-sumo wheel's binaries and the in-process libsumo, imported lazily with an install hint.

Both come from the ``traffic`` extra (``pip install 'skytrack[traffic]'``: eclipse-sumo, libsumo). Nothing here is
imported at skytrack's import time, so a world without SUMO traffic never needs them.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import os
from pathlib import Path
from types import ModuleType

__all__ = ["INSTALL_HINT", "SumoUnavailable", "import_libsumo", "sumo_available", "sumo_binary"]

INSTALL_HINT = "pip install 'skytrack[traffic]'"


class SumoUnavailable(ImportError):
    """SUMO co-simulation was asked for but eclipse-sumo or libsumo is not installed."""


def _missing(what: str, exc: BaseException | None = None) -> SumoUnavailable:
    msg = f"SUMO traffic needs {what}, which is not installed; install it with: {INSTALL_HINT}"
    err = SumoUnavailable(msg)
    if exc is not None:
        err.__cause__ = exc
    return err


def sumo_home() -> Path:
    """The eclipse-sumo wheel's install directory (its ``bin/`` holds ``sumo`` and ``netconvert``).

    Raises :class:`SumoUnavailable` when the wheel is missing."""
    try:
        sumo = importlib.import_module("sumo")
    except ImportError as exc:
        raise _missing("the eclipse-sumo package", exc) from exc
    return Path(sumo.SUMO_HOME)


def sumo_binary(name: str) -> Path:
    """Path of one of eclipse-sumo's programs (``"netconvert"``, ``"sumo"``)."""
    path = sumo_home() / "bin" / name
    if not path.is_file():
        raise _missing(f"the program {name!r} of eclipse-sumo (looked for {path})")
    return path


def import_libsumo() -> ModuleType:
    """The libsumo module (SUMO as a library in this process), with ``SUMO_HOME`` set to eclipse-sumo's directory.

    libsumo prints a version warning about pyarrow on import when one is installed; skytrack does not use pyarrow
    with it, so that print is swallowed."""
    os.environ.setdefault("SUMO_HOME", str(sumo_home()))
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            return importlib.import_module("libsumo")
    except ImportError as exc:
        raise _missing("the libsumo package", exc) from exc


def sumo_available() -> bool:
    """True when eclipse-sumo (with ``netconvert``) and libsumo can both be used in this environment."""
    try:
        sumo_binary("netconvert")
        import_libsumo()
    except SumoUnavailable:
        return False
    return True
