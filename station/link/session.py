"""The fail-safe session supervisor: what both protocol sessions share.

:class:`Session` owns the run's book-keeping and every stop of the wire: one wall-clock
deadline per expected sample (pyserial's ``Timeout``), whatever arrives in between; the
miss budget per :data:`~station.link.faults.MISS_WINDOW` ticks; a plausibility bound on
the encoder change per tick; the device's tick rate; the lag (samples already waiting
when a command is due: :meth:`Session._command`, the one place a command goes out); and
every read and write of the port. The protocol sessions (:mod:`station.link.v1`,
:mod:`station.link.legacy`) decode their wire and call these.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable
from typing import NamedTuple

import serial
from serial.serialutil import Timeout

from station import DT
from station.link.faults import (MISS_WINDOW, RATE_FAST, RATE_SLOW, RATE_WINDOW_S, Interrupted, LagError, LinkFault,
                                 LinkLimits, LinkTimeout, RateError, SequenceError)
from station.protocol import v1

logger = logging.getLogger("station.link")
"""INFO: sessions opened, INFO received, runs started and stopped; DEBUG: every byte."""

ZERO_ACCEL_TICKS = 16
"""Readings averaged for the accelerometer's zero (protocol v1, START bit1)."""
HANDSHAKE_TIMEOUT = 1.0
"""Seconds to wait for the device's answer to HELLO / θ0 / STOPPED."""


class Sample(NamedTuple):
    """One sample as both sessions give it to the loop (a tuple with names).

    Attributes
    ----------
    n : int
        Tick number from 0 (v1 sequence numbers unwrapped).
    theta : int
        Encoder counts.
    accel : int
        ADC counts (legacy: minus the station's zero offset).
    v_applied : int or None
        DAC counts the device applied during tick n (None for legacy, which does not
        report it).
    status : int
        v1 status bits (0 for legacy).
    """

    n: int
    theta: int
    accel: int
    v_applied: int | None
    status: int


class Session:
    """One protocol session on an open port. Use :func:`station.link.open_session` to make one.

    Counters of the current run (restarted by ``start``): ``dropped``, ``stale``,
    ``duplicates``, ``late`` (device-reported), ``late_seen`` (commands written after
    the next sample had already arrived), ``rx_errors``, ``watchdog_trips`` (WATCHDOG
    status edges), ``max_lag_seen``.

    ``stop_requested``: a callable polled while waiting for a sample; when it returns
    a reason ("sigint" / "sigterm") the wait ends with :class:`Interrupted`.

    Parameters
    ----------
    port : serial.SerialBase
        The open port (:func:`station.link.open_port`).
    url : str
        What was opened, for messages.
    limits : LinkLimits
        The fail-safe bounds; ``limits.timeout`` is the sample timeout.
    """

    protocol = ""
    alignment = 1
    """Computational delay d of this protocol (DESIGN.md): v[k] is computed from sample k−1."""
    sample_bytes = 1
    """Bytes of one sample on the wire (the lag is counted in samples)."""

    def __init__(self, port: serial.SerialBase, url: str, limits: LinkLimits):
        self.port = port
        self.url = url
        self.limits = limits
        self.timeout = limits.timeout
        self.info: dict | None = None
        self.stop_requested: Callable[[], str | None] | None = None
        self.lockstep = False  # the device ticks on our commands (v1: INFO rate_hz = 0)
        self._debug = logger.isEnabledFor(logging.DEBUG)  # checked once: the hot path pays one test
        self._pending: deque = deque()
        self._deadline = Timeout(limits.timeout)
        self._reset_run()

    def _reset_run(self) -> None:
        self.dropped = self.stale = self.duplicates = 0
        self.late = self.late_seen = self.rx_errors = self.watchdog_trips = 0
        self.max_lag_seen = 0
        self._n = -1  # tick number of the last sample
        self._theta = None  # its encoder count (plausibility check)
        self._misses: deque = deque()  # tick numbers of recent misses (MISS_WINDOW)
        self._watchdog = False
        self._arrivals: deque = deque()  # (arrival time, time spent waiting for it) over RATE_WINDOW_S
        self._waited = 0.0
        self._t_first = self._t_ready = None

    # -- the port: every read and write ------------------------------------------------

    def _read_some(self) -> bytes:
        """Block for at most :data:`~station.link.faults.POLL_S` (the port's read timeout) for
        at least one byte; return it and whatever else is already waiting (b"" when nothing came)."""
        port = self.port
        try:
            chunk = port.read(1)
            if chunk:
                waiting = port.in_waiting
                if waiting:
                    chunk += port.read(waiting)
                if self._debug:
                    logger.debug("%s rx %s", self.url, chunk.hex(" "))
                return chunk
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"read from {self.url} failed: {exc}") from None
        return b""

    def _receive(self) -> None:
        """One :meth:`_read_some`, decoded onto the pending messages (the protocol's ``_decoder``)."""
        data = self._read_some()
        if data:
            self._pending.extend(self._decoder.feed(data))

    def _send(self, data: bytes, *what) -> None:
        """Write ``data``; a failed write is a :class:`LinkFault` naming the port.

        ``what``: the DEBUG line's format and arguments after "<url> tx " (default: the
        bytes in hex).
        """
        if self._debug:
            if what:
                logger.debug("%s tx " + what[0], self.url, *what[1:])
            else:
                logger.debug("%s tx %s", self.url, data.hex(" "))
        try:
            self.port.write(data)
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"write to {self.url} failed: {exc}") from None

    # -- waiting for a sample: one deadline ----------------------------------------------

    def _check_wait(self, waiting_for: str) -> None:
        """Raise when the sample deadline passed or a stop signal was recorded."""
        if self.stop_requested is not None:
            reason = self.stop_requested()
            if reason:
                exc = Interrupted(f"{reason.upper()} while waiting for a sample after tick {self._n}")
                exc.reason = reason
                raise exc
        if self._deadline.expired():
            raise LinkTimeout(f"device {self.url} went silent: no {waiting_for} for {self._deadline.duration:g} s "
                              f"after tick {self._n}")

    # -- a valid, new sample: plausibility, misses, rate ---------------------------------

    def _accept(self, n: int, theta: int, status: int, step: int = 1) -> None:
        """Book-keeping for a valid, new sample n: deadline, plausibility, misses, rate."""
        if self._theta is not None and abs(theta - self._theta) > self.limits.max_step * step:
            raise SequenceError(f"implausible sample from {self.url}: encoder jumped from {self._theta} to {theta} "
                                f"counts at tick {n} (more than --max-step {self.limits.max_step:g} per tick)")
        self._n, self._theta = n, theta
        self._deadline.restart(self.timeout)
        if status:
            if status & v1.LATE:
                self.late += 1
                self._miss(n)
            wd = bool(status & v1.WATCHDOG)
            if wd and not self._watchdog:
                self.watchdog_trips += 1
            self._watchdog = wd
        elif self._watchdog:
            self._watchdog = False
        if self.limits.check_rate:
            self._check_rate()

    def _miss(self, n: int, count: int = 1) -> None:
        """Count ``count`` missed ticks at tick n; raise when the window holds too many."""
        limit = self.limits.max_miss
        misses = self._misses
        misses.extend([n] * min(count, limit + 1))
        while misses and misses[0] <= n - MISS_WINDOW:
            misses.popleft()
        if len(misses) > limit:
            raise SequenceError(f"{self.url}: more than --max-miss {limit} of the last {MISS_WINDOW} ticks were "
                                f"dropped, stale, duplicated or late at tick {n} (dropped {self.dropped}, "
                                f"stale {self.stale}, duplicates {self.duplicates}, late {self.late})")

    def _check_rate(self) -> None:
        now = time.perf_counter()
        if self._t_first is None:
            self._t_first = now
            self._t_ready = now
            return
        # time spent waiting for this sample: since the last sample or since our command,
        # whichever is later (a lockstep device answers at once: it never looks slow)
        waited = now - self._t_ready
        self._t_ready = now
        arrivals = self._arrivals
        arrivals.append((now, waited))
        self._waited += waited
        while arrivals[0][0] <= now - RATE_WINDOW_S:
            self._waited -= arrivals.popleft()[1]
        if now - self._t_first < RATE_WINDOW_S:
            return
        count = len(arrivals)
        if self._waited > RATE_SLOW * DT * count and not self._samples_waiting():
            # (with samples waiting it is the station that was held up, not the device: that is lag)
            raise RateError(f"device {self.url} ticks too slowly: {count} samples in the last {RATE_WINDOW_S:g} s, "
                            f"one every {1000 * self._waited / count:.1f} ms on average (nominal {1000 * DT:g} ms) "
                            f"at tick {self._n}")
        if not self.lockstep and self.protocol == "v1" and count > RATE_FAST * RATE_WINDOW_S / DT:
            raise RateError(f"device {self.url} ticks too fast: {count} samples in the last {RATE_WINDOW_S:g} s "
                            f"(nominal {RATE_WINDOW_S / DT:.0f}) at tick {self._n}")

    # -- a command goes out: the lag -----------------------------------------------------

    def _samples_waiting(self) -> int:
        """Samples received but not processed: decoded ones plus whole ones in the port's buffer."""
        try:
            return len(self._pending) + self.port.in_waiting // self.sample_bytes
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"{self.url}: {exc}") from None

    def _check_lag(self, n: int) -> None:
        """Lag and station-seen lateness, measured just before the command for sample n goes out."""
        waiting = self._samples_waiting()
        if waiting:
            if not self.lockstep:
                self.late_seen += 1  # the next sample is already here: this command is late
            if waiting > self.max_lag_seen:
                self.max_lag_seen = waiting
            if waiting > self.limits.max_lag:
                raise LagError(f"the station fell behind {self.url}: {waiting} samples waiting at tick {n} "
                               f"(--max-lag {self.limits.max_lag}); no command computed from stale samples")

    def _command(self, n: int, data: bytes, *what) -> None:
        """Write the command answering sample n (``data``, ``what`` as :meth:`_send`): the lag
        is checked first (:class:`LagError`), and the rate check's clock restarts after it."""
        self._check_lag(n)
        self._send(data, *what)
        self._t_ready = time.perf_counter()

    # -- life cycle ----------------------------------------------------------------------

    def counters(self) -> dict:
        """The current run's counters (names of DESIGN.md "Run outcome")."""
        return {"late": self.late, "late_seen": self.late_seen, "dropped": self.dropped, "stale": self.stale,
                "duplicates": self.duplicates, "rx_errors": self.rx_errors, "watchdog_trips": self.watchdog_trips}

    def close(self) -> None:
        """Close the port (idempotent)."""
        try:
            self.port.close()
        except (serial.SerialException, OSError):
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
