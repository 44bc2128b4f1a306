"""Ctrl-C and SIGTERM during a run end it as ``interrupted``, never as a failure.

Python raises ``KeyboardInterrupt`` from a signal handler at whatever point the interpreter is: inside a compiled
CasADi solve (which polls for signals) it surfaces as ``SystemError: <built-in function _function_buffer_eval>
returned a result with an exception set``, or a library's ``except Exception`` may swallow it. So while the tick loop
runs, :class:`DeferredInterrupts` only notes the signal, and the loop raises ``KeyboardInterrupt`` at its safe point,
between two ticks (:meth:`DeferredInterrupts.check`). A second signal before that point raises at once (a stuck
step can still be stopped). :func:`caused_by_interrupt` recognises an interrupt that came out of C code anyway
(e.g. during the solvers' build, before the loop).
"""

from __future__ import annotations

import signal
from types import FrameType, TracebackType
from typing import Any

__all__ = ["DeferredInterrupts", "caused_by_interrupt"]

SIGNALS = (signal.SIGINT, signal.SIGTERM)


def caused_by_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` is, or was caused by (``__cause__`` / ``__context__``), a ``KeyboardInterrupt``."""
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ if e.__cause__ is not None else e.__context__
    return False


class DeferredInterrupts:
    """Context manager deferring SIGINT and SIGTERM to :meth:`check`.

    Only a signal whose handler raises in Python (SIGINT's default ``KeyboardInterrupt``, or a handler the program
    installed, like the ``skytrack`` command's for SIGTERM) is deferred; one left to the operating system (SIGTERM's
    default: the process ends) stays as it was. Outside the main thread, where handlers cannot be set, nothing is
    deferred.

    Attributes
    ----------
    pending : int | None
        The signal received and not yet raised.
    """

    def __init__(self) -> None:
        self.pending: int | None = None
        self._saved: dict[int, Any] = {}

    def __enter__(self) -> DeferredInterrupts:
        for sig in SIGNALS:
            old = signal.getsignal(sig)
            if not callable(old):
                continue
            try:
                signal.signal(sig, self._note)
            except ValueError:  # not the main thread
                return self
            self._saved[sig] = old
        return self

    def _note(self, signum: int, frame: FrameType | None) -> None:
        if self.pending is not None:  # a second signal: the first one has not reached a safe point yet
            self.pending = None
            raise KeyboardInterrupt(f"signal {signal.Signals(signum).name} (twice)")
        self.pending = signum

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if a signal arrived since the last check (once: it is then no longer
        pending)."""
        signum, self.pending = self.pending, None
        if signum is not None:
            raise KeyboardInterrupt(f"signal {signal.Signals(signum).name}")

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        for sig, old in self._saved.items():
            signal.signal(sig, old)
        self._saved.clear()
        if exc_type is None:
            self.check()
