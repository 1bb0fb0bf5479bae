"""Device link: open a device by URL and run one protocol session on it.

Any pyserial URL works: a port path (``/dev/ttyACM0``, a pty), ``socket://host:port``,
``loop://`` and our ``sim://`` (the simulated rig, :mod:`station.sim.protocol_sim`).
A session is the protocol's life cycle: identify the device, start a run, samples in,
commands out, stop. Every read has a timeout; a missing or busy port, or a device that
does not answer, is a :class:`~station.errors.StationError` with a one-line message
naming the port.

Fail-safe (the link's half of it; :mod:`station.loop` has the rest): one wall-clock
deadline per expected sample (pyserial's ``Timeout``), whatever arrives in between;
modular v1 sequence arithmetic (duplicates, stale, dropped) with a miss budget per 100
ticks; a plausibility bound on the encoder change per tick; the lag (samples already
waiting when a command is due); the device's tick rate. Each ends the run by raising a
:class:`LinkFault` whose ``reason`` is the outcome reason (DESIGN.md "Run outcome").

Both sessions give the loop the same :class:`Sample` ``(n, theta, accel, v_applied,
status)``: n is the tick number from 0 (v1 sequence numbers unwrapped), theta encoder
counts, accel ADC counts, v_applied DAC counts (None for the legacy device, which does
not report it), status the v1 status bits (0 for legacy).
"""

from __future__ import annotations

import dataclasses
import errno
import logging
import os
import re
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple
from urllib.parse import parse_qsl, urlencode, urlsplit

import serial
from serial.serialutil import Timeout

from station import DT
from station.errors import StationError
from station.protocol import legacy, v1

logger = logging.getLogger("station.link")
"""INFO: sessions opened, INFO received, runs started and stopped; DEBUG: every byte."""

SIM_HANDLERS = "station.sim"
DEFAULT_BAUD = {"v1": 921600, "legacy": legacy.BAUDRATE}
FIRST_SEQ_WINDOW = 16
"""v1: the first sample of a run must have seq <= this (the device restarts at 0 on START);
a larger one was in flight from an earlier run and is ignored."""
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


@dataclass(frozen=True)
class LinkLimits:
    """What the link tolerates before it stops the run (the fail-safe bounds).

    Attributes
    ----------
    timeout : float
        s: the next valid, new sample must arrive within this of the last one (of
        START for the first), whatever else arrives in between; else reason "timeout".
    max_lag : int
        Samples already waiting (port input buffer + decoded, unprocessed) when a
        command is about to be written; above it, reason "lag".
    max_miss : int
        Ticks among the last :data:`MISS_WINDOW` that were dropped, stale, duplicated
        or LATE; above it, reason "sequence".
    max_step : float
        Largest plausible encoder change per tick, counts; above it (a byte slip, a
        corrupted sample), reason "sequence". Default: the rig's top motor speed
        (act_K·|2πj + act_p|/act_p ≈ 0.067 rad/s per DAC count, at 255 counts ≈ 5.6
        counts per tick) with a margin of 7 for the beam's swing of the hub.
    check_rate : bool
        Check the device's tick rate (reason "rate"): samples more than 1.5× the
        nominal period apart on average over 0.5 s (time the station spent on a sample
        is not counted, so a lockstep device never trips it); a self-paced v1 device
        (INFO rate_hz ≠ 0) more than 20 % fast.
    """

    timeout: float = 0.1
    max_lag: int = 2
    max_miss: int = 10
    max_step: float = 40.0
    check_rate: bool = True


MISS_WINDOW = 100
"""Ticks over which --max-miss is counted."""
RATE_WINDOW_S = 0.5
"""Wall-clock window of the rate check, s."""
RATE_SLOW = 1.5
"""Average sample period above this many nominal periods is too slow."""
RATE_FAST = 1.2
"""A self-paced device sending more than this times the nominal count of samples is too fast."""
POLL_S = 0.01
"""Longest single blocking read, s: deadlines and signals are checked at least this often."""


class LinkFault(StationError):
    """The link ended the run; ``reason`` is its outcome reason (DESIGN.md "Run outcome")."""

    reason = "link"


class LinkTimeout(LinkFault):
    """No valid, new sample arrived within the sample timeout: the device went silent
    (or sends only noise, repeats, or messages that are not samples)."""

    reason = "timeout"


class SequenceError(LinkFault):
    """Samples lost, duplicated, reordered or implausible beyond the allowed (legacy: n
    did not advance by one; the stream is out of step)."""

    reason = "sequence"


class LagError(LinkFault):
    """The station fell behind: more samples waiting than ``max_lag`` when a command was due."""

    reason = "lag"


class RateError(LinkFault):
    """A self-paced device ticks at the wrong rate."""

    reason = "rate"


class Interrupted(LinkFault):
    """A stop signal was recorded while waiting for a sample (see :mod:`station.signals`)."""

    reason = "sigint"


class DeviceStopped(StationError):
    """The device ended the run on its own (v1 STOPPED); ``stopped`` holds its counters.

    Parameters
    ----------
    message : str
        One line for the user.
    stopped : dict
        The STOPPED message's fields (reason, ticks, late, watchdog_trips, rx_errors).
    """

    def __init__(self, message: str, stopped: dict):
        super().__init__(message)
        self.stopped = stopped


def sim_url(url: str, protocol: str) -> str:
    """Add ``protocol=`` to a ``sim://`` URL that does not name one; other URLs pass unchanged.

    Parameters
    ----------
    url : str
        A port path or pyserial URL.
    protocol : str
        "v1" or "legacy".
    """
    parts = urlsplit(url)
    if parts.scheme != "sim":
        return url
    # the URL as given, repeats and blanks included: the handler refuses them, naming the option
    if any(name == "protocol" for name, _ in parse_qsl(parts.query, keep_blank_values=True)):
        return url
    return f"{url}{'&' if parts.query else '' if url.endswith('?') else '?'}{urlencode({'protocol': protocol})}"


def open_port(url: str, protocol: str = "v1", timeout: float = 0.1, baudrate: int | None = None,
              write_timeout: float | None = None) -> serial.SerialBase:
    """Open ``url`` with pyserial for one protocol.

    Parameters
    ----------
    url : str
        A port path or pyserial URL (``sim://``, ``socket://``, ``loop://``, ...).
    protocol : {"v1", "legacy"}
        Chooses the default baud rate (921600 / 115200) and, for ``sim://``, the
        simulated device's protocol.
    timeout : float
        Read timeout in s: the longest single blocking read (sessions use
        :data:`POLL_S` and keep their own deadline per sample).
    write_timeout : float, optional
        The longest a write may block, s (default ``timeout``).
    baudrate : int, optional
        Overrides the protocol's default.

    Raises
    ------
    StationError
        The port is missing, busy (locked by another process) or the URL is invalid;
        the message names the port.
    """
    if SIM_HANDLERS not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append(SIM_HANDLERS)  # pyserial's documented hook
    url = sim_url(url, protocol)
    kwargs = {"baudrate": baudrate or DEFAULT_BAUD[protocol], "timeout": timeout,
              "write_timeout": timeout if write_timeout is None else write_timeout}
    if "://" not in url:
        kwargs["exclusive"] = True  # a second station on the same rig is an error, not a fight
    try:
        return serial.serial_for_url(url, **kwargs)
    except (serial.SerialException, ValueError, OSError) as exc:
        # pyserial: "Could not exclusively lock port ..." (flock) or EBUSY from open()
        text = str(exc).replace("\n", " ")
        busy = "exclusively lock" in text or getattr(exc, "errno", None) == errno.EBUSY
        code = getattr(exc, "errno", None)
        if busy:
            reason = "port is busy (another program has it open)"
        elif isinstance(code, int) and code in errno.errorcode:
            reason = os.strerror(code)  # pyserial repeats the port in its text; say it once
        else:
            reason = re.sub(rf"(?i)^could not open port {re.escape(url)}:?\s*", "", text) or text
        hint = "; `station ports` lists the serial ports" if "://" not in url else ""
        raise StationError(f"cannot open port {url}: {reason}{hint}", key="port") from None


class Session:
    """One protocol session on an open port. Use :func:`open_session` to make one.

    Counters of the current run (restarted by ``start``): ``dropped``, ``stale``,
    ``duplicates``, ``late`` (device-reported), ``late_seen`` (commands written after
    the next sample had already arrived), ``rx_errors``, ``watchdog_trips`` (WATCHDOG
    status edges), ``max_lag_seen``.

    ``stop_requested``: a callable polled while waiting for a sample; when it returns
    a reason ("sigint" / "sigterm") the wait ends with :class:`Interrupted`.

    Parameters
    ----------
    port : serial.SerialBase
        The open port (:func:`open_port`).
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

    # -- reading with one deadline ------------------------------------------------------

    def _read_some(self) -> bytes:
        """Block for at most :data:`POLL_S` (the port's read timeout) for at least one byte;
        return it and whatever else is already waiting (b"" when nothing came)."""
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

    def _samples_waiting(self) -> int:
        """Samples received but not processed: decoded ones plus whole ones in the port's buffer."""
        try:
            return len(self._pending) + self.port.in_waiting // self.sample_bytes
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"{self.url}: {exc}") from None

    def _before_command(self, n: int) -> None:
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

    def _after_command(self) -> None:
        self._t_ready = time.perf_counter()

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


class V1Session(Session):
    """Protocol v1 session (``shared/spec/protocol.md``).

    Parameters
    ----------
    port, url, limits
        As :class:`Session`.
    """

    protocol = "v1"
    sample_bytes = 16

    def __init__(self, port, url, limits):
        super().__init__(port, url, limits)
        self._decoder = v1.Decoder()
        self._last_seq = -1

    def _write(self, msg) -> None:
        if self._debug:
            logger.debug("%s tx %s", self.url, msg)
        try:
            self.port.write(v1.encode(msg))
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"write to {self.url} failed: {exc}") from None

    def _next_message(self, deadline: Timeout):
        """The next decoded message, or None when ``deadline`` expires first (whatever arrives)."""
        while not self._pending:
            if deadline.expired():
                return None
            data = self._read_some()
            if data:
                self._pending.extend(self._decoder.feed(data))
        return self._pending.popleft()

    def hello(self) -> dict:
        """Send HELLO and wait for INFO; returns INFO's fields as a dict.

        INFO rate_hz = 0 declares a lockstep device (no rate check then).

        Raises StationError when no INFO arrives within 1 s, whatever else arrives
        (not a v1 device?).
        """
        self.port.reset_input_buffer()
        try:  # an empty frame first (spec: ignored) ends whatever a wrong-protocol attempt left in
            self.port.write(b"\x00")  # the device's frame buffer, so it cannot swallow HELLO
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"write to {self.url} failed: {exc}") from None
        self._write(v1.Hello())
        deadline = Timeout(HANDSHAKE_TIMEOUT)
        while (msg := self._next_message(deadline)) is not None:
            if isinstance(msg, v1.Info):
                self.info = {"protocol": "v1", **dataclasses.asdict(msg)}
                self.lockstep = msg.rate_hz == 0
                logger.info("%s: INFO %s", self.url, self.info)
                return self.info
        raise StationError(f"no INFO from {self.url} within {HANDSHAKE_TIMEOUT} s: is it a protocol v1 device? "
                           "(try --protocol legacy)")

    def zero_accel(self) -> dict:
        """Nothing to do here: the device averages 16 readings on START (flag bit1)."""
        return {"by": "device at START", "ticks": ZERO_ACCEL_TICKS}

    def start(self, n_ticks: int) -> None:
        """START with encoder reset and accelerometer zeroing; the device runs n_ticks ticks.

        Whatever is still in the input (samples of an earlier run, e.g. after a USB
        replug) is discarded first. The first sample is due within the timeout plus the
        16 ticks of accelerometer zeroing.

        Parameters
        ----------
        n_ticks : int
            Ticks the run lasts.
        """
        self.port.reset_input_buffer()
        self._pending.clear()
        self._decoder = v1.Decoder()
        self._last_seq = -1
        self._reset_run()
        self._debug = logger.isEnabledFor(logging.DEBUG)
        logger.info("%s: START, %d ticks", self.url, n_ticks)
        self._write(v1.Start(v1.START_RESET_ENCODER | v1.START_ZERO_ACCEL, n_ticks))
        self._deadline = Timeout(self.timeout + ZERO_ACCEL_TICKS * DT)

    def read_sample(self) -> tuple:
        """Block for the next valid, new SAMPLE (hot path).

        Returns a :class:`Sample` ``(n, theta, accel, v_applied, status)``. Modular sequence arithmetic:
        a repeated seq is a duplicate, a seq behind the last one is stale (both
        discarded and counted), a gap of g counts g − 1 dropped.

        Raises
        ------
        LinkTimeout
            No valid, new sample within the timeout of the last one, whatever arrived.
        SequenceError
            Too many misses in the window, or an implausible encoder jump.
        RateError
            The device ticks at the wrong rate.
        Interrupted
            A stop signal was recorded while waiting.
        DeviceStopped
            The device sent STOPPED (n_ticks reached).
        LinkFault
            The port failed.
        """
        pending = self._pending
        while True:
            while pending:
                msg = pending.popleft()
                if type(msg) is v1.Sample:
                    last = self._last_seq
                    if last < 0:
                        if msg.seq > FIRST_SEQ_WINDOW:
                            self.stale += 1  # in flight from before START: this run counts from seq 0
                            continue
                        step = msg.seq + 1
                        n = msg.seq
                    else:
                        step = (msg.seq - last) & 0xFFFF
                        if step == 0:
                            self.duplicates += 1
                            self._miss(self._n)
                            continue
                        if step >= 0x8000:
                            self.stale += 1
                            self._miss(self._n)
                            continue
                        n = self._n + step
                    if step > 1:
                        self.dropped += step - 1
                        self._miss(n, step - 1)
                    self._accept(n, msg.theta, msg.status, step)
                    self._last_seq = msg.seq
                    self.rx_errors = self._decoder.rx_errors
                    return Sample(n, msg.theta, msg.accel, msg.v_applied, msg.status)
                if type(msg) is v1.Stopped:
                    self.rx_errors = self._decoder.rx_errors
                    raise DeviceStopped(f"device stopped (reason {msg.reason}) after {msg.ticks} ticks",
                                        dataclasses.asdict(msg))
            self._check_wait("new valid sample")
            data = self._read_some()
            if data:
                pending.extend(self._decoder.feed(data))

    def send_command(self, n: int, v: float) -> None:
        """Answer sample n with command v (DAC counts, rounded halves away from zero).

        Raises LagError first when more than ``max_lag`` samples are already waiting.

        Parameters
        ----------
        n : int
            The sample answered (its seq is n mod 2**16).
        v : float
            The command, DAC counts.
        """
        self._before_command(n)
        if self._debug:
            logger.debug("%s tx COMMAND seq %d v %r", self.url, n & 0xFFFF, v)
        try:
            self.port.write(v1.encode(v1.Command(n & 0xFFFF, v1.round_command(v))))
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"write to {self.url} failed: {exc}") from None
        self._after_command()

    def stop(self) -> dict | None:
        """Command 0 for the last sample, then STOP; wait for STOPPED. Returns its fields or None.

        STOP is sent even when the COMMAND could not be written (then the error is raised
        after it): STOP alone sets the device's output to 0.
        """
        failed = None
        if self._last_seq >= 0:
            try:
                self._write(v1.Command(self._last_seq, 0))
            except StationError as exc:
                failed = exc
        self._write(v1.Stop())
        if failed is not None:
            raise failed
        deadline = Timeout(HANDSHAKE_TIMEOUT)
        while (msg := self._next_message(deadline)) is not None:
            if isinstance(msg, v1.Stopped):
                return dataclasses.asdict(msg)
        return None


class LegacySession(Session):
    """The rig's original PSoC protocol (``shared/spec/protocol.md``, "legacy").

    The device cannot declare lockstep, so only the slow-rate check applies, and it
    cannot report late commands: ``late`` counts what the station sees (``late_seen``).

    Parameters
    ----------
    port, url, limits
        As :class:`Session`.
    """

    protocol = "legacy"
    sample_bytes = 6

    def __init__(self, port, url, limits):
        super().__init__(port, url, limits)
        self._decoder = legacy.TickDecoder()
        self.accel_offset = 0  # subtracted from every accel sample (zero_accel)

    def _port_write(self, data: bytes) -> None:
        if self._debug:
            logger.debug("%s tx %s", self.url, data.hex(" "))
        try:
            self.port.write(data)
        except (serial.SerialException, OSError) as exc:
            raise LinkFault(f"write to {self.url} failed: {exc}") from None

    def _read_exact(self, size: int, timeout: float) -> bytes | None:
        deadline = Timeout(timeout)
        data = b""
        while len(data) < size:
            if deadline.expired():
                return None
            data += self._read_some()
        return data

    def hello(self) -> dict:
        """Ask for θ ('r'): the legacy firmware has no INFO; this proves it answers."""
        self.port.reset_input_buffer()
        self._port_write(legacy.READ)
        word = self._read_exact(2, HANDSHAKE_TIMEOUT)
        if word is None:
            raise StationError(f"no answer to 'r' from {self.url} within {HANDSHAKE_TIMEOUT} s: is it the legacy "
                               "firmware? (try --protocol v1)")
        self.info = {"protocol": "legacy", "theta": legacy.decode_word(word[:2])}
        return self.info

    def zero_accel(self) -> dict:
        """Measure the accelerometer's offset at rest, as the v1 firmware does on START.

        The old firmware cannot average before tick 0, so the station does what the
        rig's software did: a short pre-run at v = 0 (16 ticks, like v1's START bit1),
        stop, and subtract the rounded mean from every sample of the real run.
        Returns ``{"by": "station pre-run", "ticks": 16, "offset": counts}``.

        Raises
        ------
        StationError
            The device does not start or goes silent during the pre-run (nothing is
            left running: v = 0 and 's' are sent first).
        """
        self.accel_offset = 0
        try:
            self._begin()
            total = 0
            for _ in range(ZERO_ACCEL_TICKS):
                _n, _theta, a, _, _ = self.read_sample()
                total += a
                self._port_write(legacy.command_bytes(0))  # v = 0 throughout: no lag to guard
        finally:
            self.stop()
            self._drain()
        self.accel_offset = v1.round_command(total / ZERO_ACCEL_TICKS)
        return {"by": "station pre-run", "ticks": ZERO_ACCEL_TICKS, "offset": self.accel_offset}

    def _drain(self, quiet: float = 0.02, limit: float = 0.5) -> None:
        """Discard input until the line has been quiet for ``quiet`` s (ticks in flight after 's')."""
        end = Timeout(limit)
        while not end.expired():
            got = self._read_exact(1, quiet)
            if got is None:
                break
        self.port.reset_input_buffer()
        self._decoder = legacy.TickDecoder()
        self._pending.clear()

    def _begin(self) -> None:
        """v = 0, reset the encoder ('7'), start ('q'), read θ0 (legacy).

        The old firmware applies the last v it received from tick 0 on, whatever run it
        came from (a station that died leaves it set): v = 0 goes first, so tick 0
        outputs 0 as the log's row 0 says.
        """
        self._reset_run()
        self._debug = logger.isEnabledFor(logging.DEBUG)
        logger.info("%s: legacy start ('/' 0, '7', 'q')", self.url)
        self._port_write(legacy.command_bytes(0) + legacy.RESET + legacy.START)
        data = self._read_exact(2, HANDSHAKE_TIMEOUT)
        if data is None:
            raise StationError(f"no θ0 from {self.url} after 'q' within {HANDSHAKE_TIMEOUT} s")
        self._pending.clear()
        self._pending.extend(self._decoder.feed(data[2:]))
        self._theta = legacy.decode_word(data[:2])
        self._deadline = Timeout(self.timeout)

    def start(self, n_ticks: int) -> None:
        """Start the run (see :meth:`_begin`); n_ticks is checked, not sent (the device runs until 's').

        Parameters
        ----------
        n_ticks : int
            Ticks the run lasts.
        """
        if n_ticks > legacy.MAX_TICKS:
            raise StationError(f"the legacy protocol counts ticks in int16: at most {legacy.MAX_TICKS} ticks, asked {n_ticks}")
        self._begin()

    def read_sample(self) -> tuple:
        """Block for the next tick record; see :meth:`V1Session.read_sample`.

        Raises
        ------
        LinkTimeout
            No record within the sample timeout.
        SequenceError
            n did not advance by one (a lost or torn record: the stream is out of step),
            or the encoder jumped implausibly (a byte slip whose n happened to match).
        RateError, Interrupted, LinkFault
            As for v1.
        """
        pending = self._pending
        while not pending:
            self._check_wait("sample")
            data = self._read_some()
            if data:
                pending.extend(self._decoder.feed(data))
        tick = pending.popleft()
        if tick.n != self._n + 1:
            raise SequenceError(f"legacy device {self.url}: tick number jumped from {self._n} to {tick.n}; "
                                "stream out of step")
        self._accept(tick.n, tick.theta, 0)
        return Sample(tick.n, tick.theta, tick.accel - self.accel_offset, None, 0)

    def send_command(self, n: int, v: float) -> None:
        """Send '/' + v (truncated toward zero); n is implicit in this protocol.

        Raises LagError first when more than ``max_lag`` samples are already waiting.

        Parameters
        ----------
        n : int
            The sample answered (implicit in this protocol: not sent).
        v : float
            The command, DAC counts.
        """
        self._before_command(n)
        self._port_write(legacy.command_bytes(v))
        self._after_command()

    def counters(self) -> dict:
        """As :meth:`Session.counters`; ``late`` is what the station saw (the device cannot tell)."""
        return {**super().counters(), "late": self.late_seen}

    def stop(self) -> dict | None:
        """v = 0, then 's' (the old firmware has no watchdog: this must run on every exit path)."""
        self._port_write(legacy.command_bytes(0) + legacy.STOP)
        try:
            self.port.flush()
        except (serial.SerialException, OSError):
            pass
        return None


_SESSIONS = {"v1": V1Session, "legacy": LegacySession}


def open_session(url: str, protocol: str = "v1", timeout: float = 0.1, baudrate: int | None = None,
                 limits: LinkLimits | None = None) -> Session:
    """Open ``url`` and return a :class:`Session` of ``protocol`` ("v1" or "legacy").

    Parameters
    ----------
    url, protocol, baudrate
        As :func:`open_port`.
    timeout : float
        Sample timeout, s (``limits.timeout`` wins when ``limits`` is given).
    limits : LinkLimits, optional
        The fail-safe bounds; default ``LinkLimits(timeout)``.

    Returns
    -------
    Session
        A :class:`V1Session` or :class:`LegacySession`; a context manager that closes
        the port.

    Raises
    ------
    StationError
        An unknown protocol or a port that cannot be opened.
    """
    if protocol not in _SESSIONS:
        raise StationError(f"unknown protocol {protocol!r}: expected one of {', '.join(_SESSIONS)}")
    limits = limits or LinkLimits(timeout=timeout)
    url = sim_url(url, protocol)
    port = open_port(url, protocol, min(limits.timeout, POLL_S), baudrate, write_timeout=limits.timeout)
    logger.info("opened %s (%s, %s)", url, protocol, limits)
    return _SESSIONS[protocol](port, url, limits)
