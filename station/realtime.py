"""Real-time scheduling for the station's loop and the simulated device's clock.

A Python real-time loop shares the GIL with its helper threads (the log writer, sinks, a
simulated device's clock), so all of them are raised together; native thread pools are
left alone. No global state: a :class:`RealtimePriority` remembers what it changed.
"""

from __future__ import annotations

import os
import threading
import time


def _threads() -> list[int]:
    """Native ids of this process's Python threads (the loop, the log writer, sinks).

    Only Python threads: they are the ones that can hold the GIL. Native pools (e.g.
    OpenBLAS's workers, which busy-wait after a numpy call) must stay at normal
    priority, or they would starve the kernel's tty work at real-time priority.
    """
    return [t.native_id for t in threading.enumerate() if t.native_id is not None]


class RealtimePriority:
    """Raise the scheduling priority of this process's Python threads, then restore it.

    Not only the loop's thread: the log writer's thread holds the GIL while it formats
    rows, and if ordinary load could preempt it then, the loop would wait for the GIL
    behind that load (priority inversion). SCHED_FIFO 10 where the OS allows it, else
    nice −10 per thread (Linux applies ``setpriority`` to one thread id), else nothing.
    :meth:`restore` puts back each thread's own policy and nice value.
    """

    def __init__(self) -> None:
        self.level = "default"
        self._saved: list[tuple[int, int, int, int]] = []

    def raise_(self) -> str:
        """Raise; returns what was obtained ("SCHED_FIFO 10", "nice -10" or "default")."""
        try:
            self._saved = [(tid, os.sched_getscheduler(tid), os.sched_getparam(tid).sched_priority,
                            os.getpriority(os.PRIO_PROCESS, tid)) for tid in _threads()]
        except (AttributeError, OSError):
            return self.level  # no POSIX scheduling API here
        for policy, value in ((os.SCHED_FIFO, 10), (None, -10)):
            try:
                for tid, *_ in self._saved:
                    if policy is None:
                        os.setpriority(os.PRIO_PROCESS, tid, value)
                    else:
                        os.sched_setscheduler(tid, policy, os.sched_param(value))
                self.level = "SCHED_FIFO 10" if policy is not None else "nice -10"
                return self.level
            except (PermissionError, OSError):
                self.restore()
        return self.level

    def restore(self) -> None:
        """Put every raised thread back as it was; never raises."""
        for tid, policy, prio, nice in self._saved:
            try:
                os.sched_setscheduler(tid, policy, os.sched_param(prio))
                os.setpriority(os.PRIO_PROCESS, tid, nice)
            except (PermissionError, OSError):
                pass  # thread gone, or lowering nice back needs a privilege we lack
        self.level = "default"


def process_age() -> float | None:
    """Seconds since this process started (Linux ``/proc/self/stat`` against the boot clock,
    10 ms resolution), None where the OS does not tell: the start-up time of a command."""
    try:
        with open("/proc/self/stat") as fh:
            stat = fh.read()
        start_ticks = int(stat[stat.rindex(")") + 2:].split()[19])
        return time.clock_gettime(time.CLOCK_BOOTTIME) - start_ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, AttributeError):
        return None
