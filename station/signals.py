"""SIGINT / SIGTERM during a run: record them, never let them cut the stop sequence short.

A run must answer any number of signals at any moment with command 0 and stop first,
every answered sample's row in the log, one line naming the signal and exit code
130 (SIGINT) or 143 (SIGTERM) (DESIGN.md "Run outcome"). An exception raised by a
signal handler at an arbitrary bytecode can land inside the stop sequence or the log's
close, so during the loop the handler only records the signal and the loop checks the
record once per sample (and the link while it waits); before the loop (opening the
port, HELLO) nothing can be lost, so the first signal raises :class:`StopSignal` there.

Long work outside the loop (a diagnosis, a survey, comparisons, a design) must stop within
a second too, also in its worker threads, where no handler runs: it calls
:func:`check_stop` between two pieces of work (once per simulation), which raises
:class:`StopSignal` in any thread once a signal has arrived, and says what it had when
stopped with :func:`noting` (the CLI prints that line, exit 130 / 143).

Python drops an exception raised where it cannot propagate (a destructor, an at-fork hook,
a weakref callback) after printing it as "Exception ignored in ...": the guard's
``sys.unraisablehook`` drops a :class:`StopSignal` there silently (the signal stays recorded:
the next :func:`check_stop` raises it, and the pools' waits call it every 0.1 s).

A call into compiled code must not have the stop raised inside it: the handler's exception
would surface in the middle of numba's dispatcher (loading a cached function unpickles it in
Python) as ``SystemError: CPUDispatcher(...) returned a result with an exception set``.
:func:`shielded` holds the stop for such a block (a simulation takes milliseconds) and
raises it as the block ends.
"""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

SIGNAL_REASONS = {signal.SIGINT: "sigint", signal.SIGTERM: "sigterm"}
"""Outcome reason per signal."""


class StopSignal(BaseException):
    """SIGINT or SIGTERM arrived before the loop started (nothing was running yet).

    A ``BaseException`` like ``KeyboardInterrupt``, so ``except Exception`` blocks do
    not swallow it. ``signum``: the signal; ``reason``: "sigint" or "sigterm".

    ``note``: what the stopped work had done and kept, in a few words (set by
    :func:`noting`; None: nothing was started).

    Parameters
    ----------
    signum : int
        The signal (``signal.SIGINT`` or ``signal.SIGTERM``).
    """

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum
        self.reason = SIGNAL_REASONS[signum]
        self.note: str | None = None

    @property
    def exit_code(self) -> int:
        """130 for SIGINT, 143 for SIGTERM (128 + the signal number)."""
        return 128 + int(self.signum)


class StopSignals:
    """Context manager that owns SIGINT and SIGTERM for a run (main thread only).

    The first signal raises :class:`StopSignal` until :meth:`defer` is called; after
    that (and after the first raise) signals are only recorded: ``signum`` is the first
    one, ``count`` how many arrived. Elsewhere than in the main thread it installs
    nothing and only offers the same attributes (signals go to the main thread anyway).

    Guards nest: entering one while another is active returns the active one, so a
    run started by the CLI shares the CLI's guard and, once deferred, a late signal
    (the tail of a burst) can never raise while the report is printed.

    Parameters
    ----------
    ignore_after : bool, default False
        The CLI's process-level guard: on exit, ignore the signals instead of restoring
        the old handlers (the process is about to exit with the recorded code).
    """

    _active: StopSignals | None = None

    def __init__(self, ignore_after: bool = False) -> None:
        self.signum: int | None = None
        self.count = 0
        self.ignore_after = ignore_after
        self._raise = True
        self._old: dict[int, object] = {}
        self._old_hook = None
        self._depth = 0

    @property
    def reason(self) -> str | None:
        """"sigint" or "sigterm" for the first signal received, None when none came."""
        return None if self.signum is None else SIGNAL_REASONS[self.signum]

    @property
    def name(self) -> str | None:
        """"SIGINT" or "SIGTERM" (None when none came)."""
        return None if self.signum is None else signal.Signals(self.signum).name

    def defer(self) -> None:
        """From now on only record signals (the loop polls :attr:`signum`)."""
        self._raise = False

    def _handler(self, signum, frame) -> None:
        self.count += 1
        if self.signum is None:
            self.signum = signum
        if self._raise:
            self._raise = False
            raise StopSignal(signum)

    def __enter__(self) -> StopSignals:
        active = StopSignals._active
        if active is not None and active is not self:
            active._depth += 1
            return active
        self._depth += 1
        if self._depth == 1 and threading.current_thread() is threading.main_thread():
            for signum in SIGNAL_REASONS:
                try:
                    self._old[signum] = signal.signal(signum, self._handler)
                except (ValueError, OSError):
                    pass
            StopSignals._active = self
            self._old_hook, sys.unraisablehook = sys.unraisablehook, self._unraisable
        return self

    def _unraisable(self, unraisable) -> None:
        """``sys.unraisablehook``: a stop raised where Python cannot raise it is dropped (recorded
        already: :func:`check_stop` raises it next); anything else goes to the previous hook."""
        if isinstance(unraisable.exc_value, StopSignal):
            return
        (self._old_hook or sys.__unraisablehook__)(unraisable)

    def __exit__(self, *exc) -> None:
        active = StopSignals._active
        if active is not None and active is not self:
            active._depth -= 1  # a nested guard returned the active one
            return
        self._depth -= 1
        if self._depth > 0:
            return
        for signum, old in self._old.items():
            try:
                signal.signal(signum, signal.SIG_IGN if self.ignore_after else old)
            except (ValueError, OSError, TypeError):
                pass
        self._old.clear()
        if self._old_hook is not None:
            sys.unraisablehook, self._old_hook = self._old_hook, None
        if StopSignals._active is self:
            StopSignals._active = None


@contextmanager
def shielded() -> Iterator[None]:
    """Hold a signal's :class:`StopSignal` until the block ends (main thread; elsewhere and
    without an active guard, nothing to hold): for a call into compiled code, which must not
    see an exception raised by a signal handler in the middle of it.

    Raises
    ------
    StopSignal
        As the block ends, when a signal arrived during it (a signal that came earlier raised
        already, or is :func:`check_stop`'s).
    """
    active = StopSignals._active
    if active is None or not active._raise or threading.current_thread() is not threading.main_thread():
        yield
        return
    active._raise = False
    try:
        yield
    finally:
        if active.signum is None:
            active._raise = True
    if active.signum is not None:  # it arrived during the block: raise it now, outside the compiled code
        raise StopSignal(active.signum)


def check_stop() -> None:
    """Raise :class:`StopSignal` if SIGINT or SIGTERM has arrived (any thread; one attribute read).

    What long work outside the real-time loop calls between two pieces of work (e.g. once
    per simulation), so that it stops within a second, worker threads included (signal
    handlers run in the main thread only). Without an active :class:`StopSignals` guard
    (a notebook) it does nothing: there, Ctrl-C is Python's KeyboardInterrupt.

    Raises
    ------
    StopSignal
        A signal arrived (the first one's).
    """
    active = StopSignals._active
    if active is not None and active.signum is not None:
        raise StopSignal(active.signum)


@contextmanager
def noting(describe: Callable[[], str]) -> Iterator[None]:
    """Give a :class:`StopSignal` raised in the block its ``note``: what the work had when stopped.

    Parameters
    ----------
    describe : callable() -> str
        Called once, when a signal stops the block (e.g. ``"stopped after 3 of 7 logs;
        nothing written"``); a note set deeper inside wins.
    """
    try:
        yield
    except StopSignal as exc:
        if exc.note is None:
            exc.note = describe()
        raise
