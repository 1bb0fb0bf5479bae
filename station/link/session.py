"""The fail-safe session supervisor: what both protocol sessions share.

:class:`Session` owns the run's book-keeping and every stop of the wire: one wall-clock
deadline per expected sample (pyserial's ``Timeout``), whatever arrives in between; the
miss budget per :data:`~station.link.faults.MISS_WINDOW` ticks; a plausibility bound on
the encoder change per tick; the device's tick rate; the catch-up and the lag; and every
read and write of the port. The protocol sessions (:mod:`station.link.v1`,
:mod:`station.link.legacy`) decode their wire and call these.

Catch up, don't give up: when the station was held up and several samples are waiting,
:meth:`Session.poll_sample` hands the loop each one in turn (every sample is logged) and
marks all but the newest *skipped*: no command is computed from them, the device holds
its last output for those ticks (a v1 device reports them LATE). A command is computed
only from the newest sample waiting. The run stops with reason "lag" only when the
station cannot catch up: behind by more than ``--max-lag`` (:meth:`Session._command`,
the one place a command goes out, and each skip), or more held ticks than
``--max-miss`` in the window; when the samples come in bursts the message names the
latency timer and its fix (:mod:`station.link.bursts`).
"""

from __future__ import annotations

import logging
from time import perf_counter
from collections import deque
from collections.abc import Callable
from typing import NamedTuple

import serial
from serial.serialutil import Timeout

from station.rig import DT
from station.link.bursts import BurstMeter, burst_line
from station.link.faults import (MISS_WINDOW, POLL_S, RATE_FAST, RATE_SLOW, RATE_WINDOW_S, Interrupted, LagError, LinkFault,
                                 LinkLimits, LinkTimeout, RateError, SequenceError)
from station.link.port import latency_timer
from station.protocol import v1

logger = logging.getLogger("station.link")
"""INFO: sessions opened, INFO received, runs started and stopped; DEBUG: every byte."""

ZERO_ACCEL_TICKS = 16
"""Readings averaged for the accelerometer's zero (protocol v1, START bit1)."""
IDLE_S = 0.25 * DT
"""A read that blocked this long found nothing waiting: the station was idle, the link late."""
HELD_UP_S = 0.02
"""A poll that overran the port's read timeout by more than this: the host was held up."""
HELD_SPAN_S = POLL_S + HELD_UP_S
"""A span between two polls (or a poll's own read) longer than this: the host was held up."""
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
    the next sample had already arrived), ``skipped`` (samples not answered: a newer one
    was waiting), ``held`` (ticks the station knows ran on a held command: skipped,
    late_seen or LATE, each tick once), ``rx_errors``, ``watchdog_trips`` (WATCHDOG
    status edges), ``max_lag_seen`` (the largest lag, s, see :meth:`_command`).

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

    # slots: over 30 instance attributes, CPython 3.11 gives up its fast attribute access
    # (shared-key dicts), and every tick reads a dozen of them (about a µs a tick)
    __slots__ = ("port", "url", "limits", "timeout", "info", "stop_requested", "lockstep", "_debug", "_pending",
                 "_deadline", "bursts", "_decoder", "dropped", "stale", "duplicates", "late", "late_seen", "rx_errors",
                 "watchdog_trips", "skipped", "held", "max_lag_seen", "_n", "_answered", "_ahead", "_n_handed",
                 "_drained", "_stop_seen", "_theta", "_misses", "_held_window", "_held_ticks", "_grace", "_watchdog",
                 "_arrivals", "_waited", "_t_first", "_t_ready", "held_up_s", "_t_listen", "_held_at_ready")
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
        self._listen(limits.timeout)
        self.bursts = BurstMeter()
        self._reset_run()

    def _reset_run(self) -> None:
        self.dropped = self.stale = self.duplicates = 0
        self.late = self.late_seen = self.rx_errors = self.watchdog_trips = 0
        self.skipped = self.held = 0
        self.max_lag_seen = 0.0
        self._n = -1  # tick number of the last sample accepted
        self._answered = -1  # tick number of the last sample answered (its command written)
        self._ahead: Sample | None = None  # a newer sample taken by poll_sample, not yet handed over
        self._n_handed = -1  # tick number of the sample in the loop's hand
        self._drained = False  # that sample's read emptied the port (poll_sample need not look again)
        self._stop_seen: list = []  # messages read while stopping (v1: until STOPPED)
        self._theta = None  # its encoder count (plausibility check)
        self._misses: deque = deque()  # ticks dropped, stale or duplicated in the window (MISS_WINDOW)
        self._held_window: deque = deque()  # ticks that ran on a held command in the window
        self._held_ticks: set = set()  # the same, to count each once
        self.held_up_s = 0.0  # time the host was frozen while waiting for samples (not the device's)
        self._grace = False  # the deadline passed once with bytes waiting (the station was held up)
        self._watchdog = False
        self._arrivals: deque = deque()  # (arrival time, time spent waiting for it) over RATE_WINDOW_S
        self._waited = 0.0
        self._t_first = self._t_ready = None
        self.bursts.clear()

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

    def _receive(self) -> int:
        """One :meth:`_read_some`, decoded onto the pending messages (the protocol's ``_decoder``);
        returns how many messages it completed."""
        data = self._read_some()
        if data:
            msgs = self._decoder.feed(data)
            self._pending.extend(msgs)
            return len(msgs)
        return 0

    def _receive_waiting(self) -> None:
        """Decode whatever has already arrived, without blocking."""
        try:
            waiting = self.port.in_waiting
            data = self.port.read(waiting) if waiting else b""
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"read from {self.url} failed: {exc}") from None
        if data:
            if self._debug:
                logger.debug("%s rx %s", self.url, data.hex(" "))
            self._pending.extend(self._decoder.feed(data))

    def _wait(self, waiting_for: str) -> None:
        """Nothing is pending: wait (at most :data:`~station.link.faults.POLL_S`) for more,
        checking the deadline and stop signals. A chunk that ends a real wait (the read
        blocked: nothing had been there) feeds the burst meter; one that was already
        waiting (the station was busy) does not."""
        t0 = perf_counter()
        if t0 - self._t_listen > HELD_SPAN_S:  # since the last poll or the deadline's start (hot path: one test)
            self._credit_held_up(t0 - self._t_listen)
        self._check_wait(waiting_for)
        got = self._receive()
        self._t_listen = now = perf_counter()
        if now - t0 > HELD_SPAN_S:
            self._credit_held_up(now - t0)
        if got and now - t0 > IDLE_S:
            self.bursts.record(got, now)

    def _credit_held_up(self, span: float) -> None:
        """The deadline counts time the station listened: a span between two polls longer than
        :data:`HELD_SPAN_S` (the caller's test, one comparison on the hot path) means the host
        was frozen (a stalled VM), when no device could be heard, and what it held past the
        port's read timeout is added to the deadline. A real device's samples are waiting
        after such a stall and end the wait; a silent one is still caught, that much later."""
        held = span - POLL_S
        self._deadline.target_time += held
        self.held_up_s += held

    def _listen(self, timeout: float) -> None:
        """A new sample deadline of ``timeout`` s, starting now."""
        self._deadline = Timeout(timeout)
        self._t_listen = perf_counter()

    def _send(self, data: bytes, what: tuple = ()) -> None:
        """Write ``data``; a failed write is a :class:`LinkFault` naming the port.

        ``what``: the DEBUG line's format and arguments after "<url> tx " (default: the
        bytes in hex). A tuple, not ``*what``: a variadic call costs ~0.1 µs a tick.
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
            if not self._grace and self._bytes_waiting():
                self._grace = True  # the station was held up past the deadline: first read what is here
                return
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
        self._t_listen = perf_counter()
        self._grace = False
        if status:
            if status & v1.LATE:
                self.late += 1
                self._hold(n)
            wd = bool(status & v1.WATCHDOG)
            if wd and not self._watchdog:
                self.watchdog_trips += 1
            self._watchdog = wd
        elif self._watchdog:
            self._watchdog = False
        if self.limits.check_rate and not self.lockstep:
            # a lockstep device ticks when asked: its waits are the host's, bounded by the timeout
            self._check_rate()

    def _miss(self, n: int, count: int = 1) -> None:
        """Count ``count`` ticks dropped, stale or duplicated at tick n; more than ``max_miss``
        in the window: :class:`SequenceError`."""
        limit = self.limits.max_miss
        misses = self._misses
        misses.extend([n] * min(count, limit + 1))
        while misses and misses[0] <= n - MISS_WINDOW:
            misses.popleft()
        if len(misses) > limit:
            raise SequenceError(f"{self.url}: more than --max-miss {limit} of the last {MISS_WINDOW} ticks were "
                                f"dropped, stale or duplicated at tick {n} (dropped {self.dropped}, "
                                f"stale {self.stale}, duplicates {self.duplicates})")

    def _hold(self, k: int) -> None:
        """Tick k ran on a held command (v1 LATE, a skipped sample, a late command), counted once
        per tick whoever saw it first. The window may hold one catch-up's worth (``max_lag``
        / 2 ms) and ``max_miss`` more; beyond that the station cannot keep up: :class:`LagError`."""
        held = self._held_ticks
        if k in held:
            return
        held.add(k)
        self.held += 1
        window = self._held_window
        window.append(k)
        while window and window[0] <= k - MISS_WINDOW:
            held.discard(window.popleft())
        catch_up = int(self.limits.max_lag / DT + 1e-9)
        if len(window) > self.limits.max_miss + catch_up:
            late = self.late if self.protocol == "v1" else self.held
            what = (f"{len(window)} of the last {MISS_WINDOW} ticks ran on a held command, more than one catch-up "
                    f"(--max-lag {1000 * self.limits.max_lag:g} ms: {catch_up} ticks) and --max-miss "
                    f"{self.limits.max_miss} more (skipped {self.skipped}, late {late})")
            if self.late > 2 * (self.skipped + self.late_seen):  # the device saw them late, the station did not
                raise LagError(f"commands reach {self.url} late: {what} at tick {k}, though the station answered "
                               f"every sample within {1000 * self.max_lag_seen:.1f} ms: the link or the device "
                               f"is held up")
            raise LagError(self._behind(k, what))

    def _behind(self, n: int, what: str) -> str:
        """The one line of a "lag" stop at tick n: the bursts and their fix when the link
        delivers in bursts, else what the station could not keep up with."""
        burst = self.bursts.burst()
        if burst is not None:
            return f"{burst_line(burst, self.url, latency_timer(self.url))}; stopped at tick {n}"
        return (f"the station cannot keep up with {self.url}: {what} at tick {n}; it was held up "
                f"(a busy CPU?); no command was computed from an older sample than the newest")

    def _check_rate(self) -> None:
        now = perf_counter()
        if self._t_first is None:
            self._t_first = now
            self._t_ready, self._held_at_ready = now, self.held_up_s
            return
        # time spent waiting for this sample: since the last sample or since our command,
        # whichever is later
        waited = now - self._t_ready - (self.held_up_s - self._held_at_ready)  # a frozen host is not the device
        self._t_ready, self._held_at_ready = now, self.held_up_s
        arrivals = self._arrivals
        arrivals.append((now, waited))
        self._waited += waited
        while arrivals[0][0] <= now - RATE_WINDOW_S:
            self._waited -= arrivals.popleft()[1]
        if now - self._t_first < RATE_WINDOW_S:
            return
        count = len(arrivals)
        if (self._waited > RATE_SLOW * DT * count and self._waited >= RATE_WINDOW_S / 4
                and not self._samples_waiting()):
            # Judged only when the station spent a quarter of the window waiting on the device: a
            # host held up (a stalled VM) leaves few samples and little waiting in the
            # window, no evidence about the device. With samples waiting it is the station
            # that was held up, not the device: that is lag.
            raise RateError(f"device {self.url} ticks too slowly: {count} samples in the last {RATE_WINDOW_S:g} s, "
                            f"one every {1000 * self._waited / count:.1f} ms on average (nominal {1000 * DT:g} ms) "
                            f"at tick {self._n}")
        if self.protocol == "v1" and count > RATE_FAST * RATE_WINDOW_S / DT:
            raise RateError(f"device {self.url} ticks too fast: {count} samples in the last {RATE_WINDOW_S:g} s "
                            f"(nominal {RATE_WINDOW_S / DT:.0f}) at tick {self._n}")

    # -- catching up, and a command goes out: the lag ----------------------------------

    def _bytes_waiting(self) -> int:
        try:
            return self.port.in_waiting
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"{self.url}: {exc}") from None

    def _samples_waiting(self) -> int:
        """Samples received but not processed: taken ahead, decoded, and whole ones in the port's buffer."""
        return (self._ahead is not None) + len(self._pending) + self._bytes_waiting() // self.sample_bytes

    def _next_pending(self):
        """The next valid, new sample among the pending messages (accepted), or None when
        they run out; the protocol sessions define it."""
        raise NotImplementedError

    def _lenient(self, msgs: list) -> list[Sample]:
        """The new samples among decoded messages, without any check that could raise (after a
        stop); the protocol sessions define it."""
        raise NotImplementedError

    def read_sample(self) -> Sample:
        """Block for the next valid, new sample (hot path); see the protocol session's
        ``_next_pending`` for what is checked.

        Returns
        -------
        Sample
            ``(n, theta, accel, v_applied, status)``.

        Raises
        ------
        LinkTimeout
            No valid, new sample within the timeout of the last one, whatever arrived.
        SequenceError
            Too many misses in the window, or an implausible encoder jump (legacy: n did
            not advance by one).
        LagError
            The station fell behind and cannot catch up.
        RateError
            The device ticks at the wrong rate.
        Interrupted
            A stop signal was recorded while waiting.
        DeviceStopped
            The device sent STOPPED (v1).
        LinkFault
            The port failed.
        """
        ahead = self._ahead
        if ahead is not None:
            self._ahead = None
            self._drained = False
            self._n_handed = ahead.n
            return ahead
        pending = self._pending
        drained = False
        while True:
            if pending:
                sample = self._next_pending()
                if sample is not None:
                    self._drained = drained
                    self._n_handed = sample.n
                    return sample
            self._wait("new valid sample")
            drained = True  # that read looked at the port and took everything waiting

    def poll_sample(self) -> Sample | None:
        """A newer sample than the one in hand if it has already arrived (never blocks), else None.

        When one is returned, the sample in hand is *skipped*: it will not be answered
        (counted in ``skipped``; its next tick runs on the held command, counted once in
        the miss window), and the lag is checked: the samples skipped in a row plus those
        still waiting must be within ``max_lag`` of the device's time. (A lockstep device
        holds nothing: neither is checked.) When the sample in hand came from a read that
        took everything the port held a moment ago, that read was the look: no second
        look at the port (one system call less inside the compute latency).

        Returns
        -------
        Sample or None
            As :meth:`read_sample`.

        Raises
        ------
        LagError
            Behind by more than ``max_lag``, or the miss budget is spent (the message names
            the bursts and the latency timer when the samples come in bursts).
        SequenceError, RateError, DeviceStopped, LinkFault
            As :meth:`read_sample`, for the newer sample.
        """
        if self._ahead is None:
            if not self._pending:
                if self._drained:  # read_sample's read just took all the port held: that was the look
                    self._drained = False
                    return None
                try:  # inline: this look at the port is inside the tick's compute latency
                    if self.port.in_waiting < self.sample_bytes:
                        return None
                except (serial.SerialException, OSError) as exc:
                    raise LinkFault(f"{self.url}: {exc}") from None
                self._receive_waiting()
            self._ahead = self._next_pending()
            if self._ahead is None:
                return None
        self._drained = False  # catching up: every later look goes to the port
        skipped = self._n_handed
        self.skipped += 1
        if self.lockstep:  # a device that waits for each command holds nothing
            sample, self._ahead = self._ahead, None
            self._n_handed = sample.n
            return sample
        self._hold(skipped + 1)
        behind = self._ahead.n + len(self._pending) + self._bytes_waiting() // self.sample_bytes - self._answered - 1
        if behind * DT > self.max_lag_seen:
            self.max_lag_seen = behind * DT
        if behind * DT > self.limits.max_lag:
            raise LagError(self._behind(skipped, f"{behind} samples ({1000 * behind * DT:.0f} ms of the device's "
                                                 f"time) to catch up, more than --max-lag "
                                                 f"{1000 * self.limits.max_lag:g} ms"))
        sample, self._ahead = self._ahead, None
        self._n_handed = sample.n
        return sample

    def _command(self, n: int, data: bytes, what: tuple = ()) -> None:
        """Write the command answering sample n (``data``, ``what`` as :meth:`_send`).

        First the lag, in the device's time (its samples, 2 ms each: the OS does not say
        when a byte arrived, and a lockstep device that waits for us is never behind): the
        samples skipped since the last answer and those that arrived while this command
        was computed; above ``max_lag`` a :class:`LagError` (nothing written). A sample
        already waiting makes this command late (``late_seen``; its tick runs on the held
        command). The rate check's clock restarts after the write.
        """
        if not self.lockstep:
            waiting = self._samples_waiting()
            behind = n - self._answered - 1 + waiting  # ≥ 0; 0 on a healthy link: nothing to check
            if behind:
                lag = behind * DT
                if lag > self.max_lag_seen:
                    self.max_lag_seen = lag
                if lag > self.limits.max_lag:
                    raise LagError(self._behind(n, f"the command for it would go out {1000 * lag:.0f} ms of the "
                                                   f"device's time behind, more than --max-lag "
                                                   f"{1000 * self.limits.max_lag:g} ms"))
                if waiting:
                    self.late_seen += 1  # the next sample is already here: this command is late
                    self._hold(n + 1)
        self._send(data, what)
        self._answered = n
        self._t_ready, self._held_at_ready = perf_counter(), self.held_up_s

    def unread_samples(self) -> list[Sample]:
        """Samples that arrived but never reached the loop (taken ahead, decoded, waiting in
        the port, or seen while stopping), in order; for the log after a stop. Never raises;
        no check stops anything here (the run has ended), but only new samples are given."""
        out = [] if self._ahead is None else [self._ahead]
        self._ahead = None
        try:
            self._receive_waiting()
        except LinkFault:
            pass
        out.extend(self._lenient(list(self._stop_seen) + list(self._pending)))
        self._pending.clear()
        self._stop_seen.clear()
        return out

    # -- life cycle ----------------------------------------------------------------------

    def counters(self) -> dict:
        """The current run's counters (names of DESIGN.md "Run outcome")."""
        return {"late": self.late, "late_seen": self.late_seen, "skipped": self.skipped, "dropped": self.dropped,
                "stale": self.stale, "duplicates": self.duplicates, "rx_errors": self.rx_errors,
                "watchdog_trips": self.watchdog_trips}

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
