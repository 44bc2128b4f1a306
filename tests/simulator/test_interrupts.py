"""Signals during a run: deferred to the gap between two ticks, so a Ctrl-C inside compiled code is an interruption,
never a failure."""

from __future__ import annotations

import signal

import casadi as ca
import numpy as np
import pytest

from simulator.interrupts import DeferredInterrupts, caused_by_interrupt


@pytest.fixture(autouse=True)
def _sigint(sigint_raises):
    """Every test here starts with SIGINT raising (the conftest's ``sigint_raises``)."""


def _terminate(signum, frame):
    raise KeyboardInterrupt(f"signal {signum}")


@pytest.fixture
def sigterm_raises():
    """SIGTERM raising in Python, as the ``skytrack`` command sets it."""
    old = signal.signal(signal.SIGTERM, _terminate)
    yield
    signal.signal(signal.SIGTERM, old)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["sigint", "sigterm"])
def test_a_signal_is_noted_and_raised_at_the_check(sigterm_raises, sig):
    before = signal.getsignal(sig)
    with DeferredInterrupts() as guard:
        signal.raise_signal(sig)  # nothing raised here, where a solver might be running
        assert guard.pending == sig
        with pytest.raises(KeyboardInterrupt, match=f"signal {sig.name}"):
            guard.check()
    assert signal.getsignal(sig) is before


def test_no_signal_no_raise_and_a_signal_after_the_last_check_is_raised_on_leaving():
    with DeferredInterrupts() as guard:
        guard.check()
    assert guard.pending is None
    with pytest.raises(KeyboardInterrupt, match="signal SIGINT"):
        with DeferredInterrupts():
            signal.raise_signal(signal.SIGINT)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_second_signal_raises_at_once():
    with DeferredInterrupts():
        signal.raise_signal(signal.SIGINT)
        with pytest.raises(KeyboardInterrupt, match="twice"):
            signal.raise_signal(signal.SIGINT)


def test_a_signal_left_to_the_system_stays_so():
    old = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        with DeferredInterrupts():
            assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
            assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    finally:
        signal.signal(signal.SIGTERM, old)


def test_a_signal_inside_a_casadi_call_does_not_break_the_call():
    """A Python function CasADi calls from its C code receives the signal there: unguarded, the call fails; guarded,
    it returns its value and the interruption waits for the check."""

    class Poke(ca.Callback):
        def __init__(self):
            ca.Callback.__init__(self)
            self.construct("poke", {})

        def get_n_in(self):
            return 1

        def get_n_out(self):
            return 1

        def eval(self, arg):
            signal.raise_signal(signal.SIGINT)
            return [arg[0] * 2]

    poke = Poke()
    x = ca.MX.sym("x")
    f = ca.Function("f", [x], [poke(x) + 1])
    with pytest.raises(RuntimeError, match="KeyboardInterrupt"):  # what a solver's `except RuntimeError` swallows
        f(3.0)
    with DeferredInterrupts() as guard:
        assert float(f(3.0)) == 7.0
        assert guard.pending == signal.SIGINT
        with pytest.raises(KeyboardInterrupt):
            guard.check()


def test_an_interrupt_surfacing_from_c_code_is_recognised():
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as inner:  # what CPython makes of a C function returning with one set
            raise SystemError("<built-in function _function_buffer_eval> returned a result with an exception set") \
                from inner
    except SystemError as exc:
        assert caused_by_interrupt(exc)
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            np.float64("x")  # a ValueError raised while handling it: __context__
    except ValueError as exc:
        assert caused_by_interrupt(exc)
    assert not caused_by_interrupt(RuntimeError("solver failed"))
