"""Samples that arrive in bursts: seen, measured and named with the fix.

A USB serial adapter does not pass each byte on at once: an FTDI chip sends its buffer
when it is full or when its latency timer (default 16 ms) expires, so a 500 Hz device's
samples reach the PC in bursts of about 8 every 16 ms. Each burst holds samples the
station can only skip (:mod:`station.link.session` answers the newest), and the run
stops on its miss budget - with one line that says why and what fixes it
(:func:`burst_line`), never a bare "lag".

:class:`BurstMeter` keeps the chunks that ended a wait: each time the station was
waiting for a sample (idle) and the port then handed over several at once. A stalled
PC (a busy CPU) gives one large chunk now and then, after which single samples come
again; a latency timer gives the same size at the same interval, chunk after chunk.
"""

from __future__ import annotations

import time
from collections import deque
from typing import NamedTuple

from station.rig import DT

KEPT = 8
"""Chunks kept (the newest ones)."""
RECENT_S = 0.25
"""Only chunks of the last this many seconds count, s."""


class Burst(NamedTuple):
    """A regular burst pattern of the link.

    Attributes
    ----------
    size : int
        Samples per burst (the median of the recent bursts).
    interval_s : float
        Time between bursts, s (the median; NaN with fewer than two).
    count : int
        Bursts seen in a row.
    """

    size: int
    interval_s: float
    count: int


class BurstMeter:
    """The chunks of samples that ended the station's waits, and whether they form bursts."""

    def __init__(self) -> None:
        self._chunks: deque = deque(maxlen=KEPT)  # (arrival time, samples)

    def clear(self) -> None:
        """Forget every chunk (a new run)."""
        self._chunks.clear()

    def record(self, samples: int, at: float | None = None) -> None:
        """One read that ended a wait brought ``samples`` new samples.

        Parameters
        ----------
        samples : int
            Whole samples in the chunk.
        at : float, optional
            Its arrival, ``time.perf_counter()`` seconds (default now).
        """
        if samples > 0:
            self._chunks.append((time.perf_counter() if at is None else at, int(samples)))

    def burst(self, now: float | None = None) -> Burst | None:
        """The burst pattern of the last chunks, or None when the samples do not come in bursts.

        Bursts: the last two chunks of the last :data:`RECENT_S` brought 3 or more samples
        each, or the last three brought 2 or more each, of nearly the same size (within
        one sample, or a quarter of the median), more than one tick apart.

        Parameters
        ----------
        now : float, optional
            ``time.perf_counter()`` seconds (default now).
        """
        now = time.perf_counter() if now is None else now
        recent = [(t, s) for t, s in self._chunks if now - t <= RECENT_S]
        run = []
        for t, s in reversed(recent):  # the newest chunks, while they are bursts
            if s < 2:
                break
            run.append((t, s))
        run.reverse()
        if not (len(run) >= 3 or (len(run) >= 2 and min(s for _, s in run) >= 3)):
            return None
        sizes = sorted(s for _, s in run)
        size = sizes[len(sizes) // 2]
        if sizes[-1] - sizes[0] > max(1, size // 4):
            return None
        gaps = sorted(b[0] - a[0] for a, b in zip(run, run[1:]))
        interval = gaps[len(gaps) // 2]
        if interval <= 1.5 * DT:
            return None
        return Burst(size, interval, len(run))


def burst_line(burst: Burst, url: str, latency: tuple[int, str] | None) -> str:
    """One line: the bursts, the port's latency timer and the command that fixes it.

    Parameters
    ----------
    burst : Burst
        What :meth:`BurstMeter.burst` found.
    url : str
        The port, for the message.
    latency : (int, str) or None
        The port's latency timer, ms, and its sysfs file (:func:`station.link.port.latency_timer`);
        None when the OS shows none (a pty, CDC ACM, another OS).

    Returns
    -------
    str
        E.g. ``samples from /dev/ttyUSB0 arrive in bursts of 8 every 16 ms: the USB serial
        adapter's latency timer is 16 ms; set it to 1 ms: echo 1 | sudo tee
        /sys/bus/usb-serial/devices/ttyUSB0/latency_timer (for good: a udev rule, README
        "Safety")``.
    """
    head = f"samples from {url} arrive in bursts of {burst.size} every {1000 * burst.interval_s:.0f} ms"
    if latency is not None:
        ms, path = latency
        return (f"{head}: the USB serial adapter's latency timer is {ms} ms; set it to 1 ms: "
                f"echo 1 | sudo tee {path} (for good: a udev rule, README \"Safety\")")
    return (f"{head}, as a USB serial adapter's latency timer makes them (the OS shows none for this port); "
            f"on an FTDI adapter set it to 1 ms: echo 1 | sudo tee /sys/bus/usb-serial/devices/ttyUSB0/latency_timer "
            f"(README \"Safety\")")
