"""Is this test machine holding its threads up? A watch for the timing tests.

A virtual machine's vCPUs can be frozen by the host for tenths of a second (measured on this
project's CI machines: about two freezes a second of 0.1-0.6 s, a busy loop included). A
real-time test on such a machine can fail with no fault in the station: a scripted device
that misses its 2 ms clock by 0.3 s *is* a silent device, and a stop 0.2 s after a fault can
be 0.5 s late on the wall clock. The timing tests therefore run again when, and only when,
the machine was seen frozen during a failed try (:func:`machine_stalled`, the condition of
``pytest.mark.flaky``); a failure on a machine that kept time stands.
"""

from __future__ import annotations

import threading
import time
from collections import deque

STALL_S = 0.02
"""A gap this long between two wake-ups of a thread that sleeps 2 ms: the machine froze."""


class StallWatch:
    """A daemon thread that wakes every 2 ms and keeps the (wall time, length) of each gap
    longer than :data:`STALL_S` (the last 10 000)."""

    def __init__(self) -> None:
        self.stalls: deque[tuple[float, float]] = deque(maxlen=10_000)
        self._thread = threading.Thread(target=self._run, name="stall-watch", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        last = time.perf_counter()
        while True:
            time.sleep(0.002)
            now = time.perf_counter()
            if now - last > STALL_S:
                self.stalls.append((time.time(), now - last))
            last = now

    def since(self, t0: float) -> list[tuple[float, float]]:
        """The stalls that ended after wall time ``t0``."""
        return [s for s in list(self.stalls) if s[0] >= t0]


_WATCH: StallWatch | None = None
_TEST_START = [0.0]


def watch() -> StallWatch:
    """The one stall watch of this process (started on first use)."""
    global _WATCH
    if _WATCH is None:
        _WATCH = StallWatch()
    return _WATCH


def try_started() -> None:
    """Mark the start of a try: :func:`machine_stalled` looks at what came after."""
    watch()
    _TEST_START[0] = time.time()


def machine_stalled(error=None) -> bool:
    """True when, since the current try started, the stall watch saw the machine frozen or a
    scripted device missed its own clock (tests/scripted_device.py): the try was no trial
    of the station's timing."""
    from tests.scripted_device import device_clock_stalled

    return bool(watch().since(_TEST_START[0])) or device_clock_stalled()



def timed_marks() -> list:
    """The marks of a test that times a real-time run: ``realtime`` (the README's test
    command runs it alone, after the rest), run again when the machine froze during a failed
    try (:func:`machine_stalled`, at most ten times), with the stall watch on."""
    import pytest

    return [pytest.mark.realtime, pytest.mark.flaky(reruns=10, condition=machine_stalled),
            pytest.mark.usefixtures("stall_watch")]


def timed(test):
    """Decorate one test with :func:`timed_marks` (a whole module: ``pytestmark = timed_marks()``)."""
    for mark in timed_marks():
        test = mark(test)
    return test
