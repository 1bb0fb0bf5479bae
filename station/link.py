"""Device link: open a device by URL and run one protocol session on it.

Any pyserial URL works: a port path (``/dev/ttyACM0``, a pty), ``socket://host:port``,
``loop://`` and our ``sim://`` (the simulated rig, :mod:`station.sim.protocol_sim`).
A session is the protocol's life cycle: identify the device, start a run, samples in,
commands out, stop. Every read has a timeout; a missing or busy port, or a device that
does not answer, is a :class:`~station.errors.StationError` with a one-line message
naming the port.

Both sessions give the loop the same sample tuple ``(n, theta, accel, v_applied,
status)``: n is the tick number from 0 (v1 sequence numbers unwrapped), theta encoder
counts, accel ADC counts, v_applied DAC counts (None for the legacy device, which does
not report it), status the v1 status bits (0 for legacy).
"""

from __future__ import annotations

import dataclasses
import errno
import time
from urllib.parse import parse_qsl, urlencode, urlsplit

import serial

from station.errors import StationError
from station.protocol import legacy, v1

SIM_HANDLERS = "station.sim"
DEFAULT_BAUD = {"v1": 921600, "legacy": legacy.BAUDRATE}
FIRST_SEQ_WINDOW = 16
"""v1: the first sample of a run must have seq <= this (the device restarts at 0 on START);
a larger one was in flight from an earlier run and is ignored."""
ZERO_ACCEL_TICKS = 16
"""Readings averaged for the accelerometer's zero (protocol v1, START bit1)."""
HANDSHAKE_TIMEOUT = 1.0
"""Seconds to wait for the device's answer to HELLO / θ0 / STOPPED."""


class LinkTimeout(StationError):
    """No sample arrived within the sample timeout: the device went silent."""


class SequenceError(StationError):
    """The legacy device's tick number n did not advance by one: the stream is out of step."""


class DeviceStopped(StationError):
    """The device ended the run on its own (v1 STOPPED); ``stopped`` holds its counters."""

    def __init__(self, message: str, stopped: dict):
        super().__init__(message)
        self.stopped = stopped


def sim_url(url: str, protocol: str) -> str:
    """Add ``protocol=`` to a ``sim://`` URL that does not name one; other URLs pass unchanged."""
    parts = urlsplit(url)
    if parts.scheme != "sim":
        return url
    query = dict(parse_qsl(parts.query))
    query.setdefault("protocol", protocol)
    return f"sim://{parts.netloc}{parts.path}?{urlencode(query)}"


def open_port(url: str, protocol: str = "v1", timeout: float = 0.1, baudrate: int | None = None) -> serial.SerialBase:
    """Open ``url`` with pyserial for one protocol.

    Parameters
    ----------
    url : str
        A port path or pyserial URL (``sim://``, ``socket://``, ``loop://``, ...).
    protocol : {"v1", "legacy"}
        Chooses the default baud rate (921600 / 115200) and, for ``sim://``, the
        simulated device's protocol.
    timeout : float
        Read timeout in s: the longest wait for one sample.
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
    kwargs = {"baudrate": baudrate or DEFAULT_BAUD[protocol], "timeout": timeout, "write_timeout": timeout}
    if "://" not in url:
        kwargs["exclusive"] = True  # a second station on the same rig is an error, not a fight
    try:
        return serial.serial_for_url(url, **kwargs)
    except (serial.SerialException, ValueError, OSError) as exc:
        reason = str(exc).replace("\n", " ")
        # pyserial: "Could not exclusively lock port ..." (flock) or EBUSY from open()
        busy = "exclusively lock" in reason or getattr(exc, "errno", None) == errno.EBUSY
        raise StationError(f"cannot open port {url}: {'port is busy: ' if busy else ''}{reason}") from None


class Session:
    """One protocol session on an open port. Use :func:`open_session` to make one."""

    protocol = ""
    alignment = 1
    """Computational delay d of this protocol (DESIGN.md): v[k] is computed from sample k−1."""

    def __init__(self, port: serial.SerialBase, url: str, timeout: float):
        self.port = port
        self.url = url
        self.timeout = timeout
        self.dropped = 0
        self.rx_errors = 0
        self.late = 0  # late commands the device reported (the legacy device cannot)
        self.info: dict | None = None
        self._pending: list = []
        self._n = -1  # tick number of the last sample

    def _read_some(self, deadline: float) -> bytes:
        """Block for at least one byte or until ``deadline`` (perf_counter s); b"" on timeout."""
        port = self.port
        while True:
            chunk = port.read(1)
            if chunk:
                waiting = port.in_waiting
                return chunk + port.read(waiting) if waiting else chunk
            if time.perf_counter() >= deadline:
                return b""

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
    """Protocol v1 session (``shared/spec/protocol.md``)."""

    protocol = "v1"

    def __init__(self, port, url, timeout):
        super().__init__(port, url, timeout)
        self._decoder = v1.Decoder()
        self._last_seq = -1
        self.stale_samples = 0

    def _next_message(self, timeout: float):
        deadline = time.perf_counter() + timeout
        while not self._pending:
            data = self._read_some(deadline)
            if not data:
                return None
            self._pending.extend(self._decoder.feed(data))
        return self._pending.pop(0)

    def _write(self, msg) -> None:
        try:
            self.port.write(v1.encode(msg))
        except (serial.SerialException, OSError) as exc:
            raise StationError(f"write to {self.url} failed: {exc}") from None

    def hello(self) -> dict:
        """Send HELLO and wait for INFO; returns INFO's fields as a dict.

        Raises StationError when no INFO arrives within 1 s (not a v1 device?).
        """
        self.port.reset_input_buffer()
        self._write(v1.Hello())
        deadline = time.perf_counter() + HANDSHAKE_TIMEOUT
        while (left := deadline - time.perf_counter()) > 0:
            msg = self._next_message(left)
            if isinstance(msg, v1.Info):
                self.info = {"protocol": "v1", **dataclasses.asdict(msg)}
                return self.info
        raise StationError(f"no INFO from {self.url} within {HANDSHAKE_TIMEOUT} s: is it a protocol v1 device?")

    def zero_accel(self) -> dict:
        """Nothing to do here: the device averages 16 readings on START (flag bit1)."""
        return {"by": "device at START", "ticks": ZERO_ACCEL_TICKS}

    def start(self, n_ticks: int) -> None:
        """START with encoder reset and accelerometer zeroing; the device runs n_ticks ticks.

        Whatever is still in the input (samples of an earlier run, e.g. after a USB
        replug) is discarded first.
        """
        self.port.reset_input_buffer()
        self._pending.clear()
        self._decoder = v1.Decoder()
        self._last_seq, self._n = -1, -1
        self.stale_samples = 0
        self._write(v1.Start(v1.START_RESET_ENCODER | v1.START_ZERO_ACCEL, n_ticks))

    def read_sample(self) -> tuple:
        """Block for the next SAMPLE (hot path).

        Returns ``(n, theta, accel, v_applied, status)``. Sequence gaps are counted in
        ``dropped``; LATE samples in ``late``.

        Raises
        ------
        LinkTimeout
            No sample within the sample timeout.
        DeviceStopped
            The device sent STOPPED (n_ticks reached).
        """
        while True:
            msg = self._pending.pop(0) if self._pending else self._next_message(self.timeout)
            if msg is None:
                raise LinkTimeout(f"device {self.url} went silent: no sample for {self.timeout} s after tick {self._n}")
            if isinstance(msg, v1.Sample):
                if self._last_seq < 0 and msg.seq > FIRST_SEQ_WINDOW:
                    self.stale_samples += 1  # from before START: this run counts from seq 0
                    continue
                break
            if isinstance(msg, v1.Stopped):
                stopped = dataclasses.asdict(msg)
                raise DeviceStopped(f"device stopped (reason {msg.reason}) after {msg.ticks} ticks", stopped)
        if self._last_seq < 0:  # the first sample of the run: the device counts from 0
            n = msg.seq
            self.dropped += msg.seq
        else:
            step = (msg.seq - self._last_seq) & 0xFFFF
            self.dropped += step - 1
            n = self._n + step
        self._last_seq, self._n = msg.seq, n
        if msg.status & v1.LATE:
            self.late += 1
        self.rx_errors = self._decoder.rx_errors
        return (n, msg.theta, msg.accel, msg.v_applied, msg.status)

    def send_command(self, n: int, v: float) -> None:
        """Answer sample n with command v (DAC counts, rounded halves away from zero)."""
        self.port.write(v1.encode(v1.Command(n & 0xFFFF, v1.round_command(v))))

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
        deadline = time.perf_counter() + HANDSHAKE_TIMEOUT
        while (left := deadline - time.perf_counter()) > 0:
            msg = self._next_message(left)
            if isinstance(msg, v1.Stopped):
                return dataclasses.asdict(msg)
        return None


class LegacySession(Session):
    """The rig's original PSoC protocol (``shared/spec/protocol.md``, "legacy")."""

    protocol = "legacy"

    def __init__(self, port, url, timeout):
        super().__init__(port, url, timeout)
        self._decoder = legacy.TickDecoder()
        self.accel_offset = 0  # subtracted from every accel sample (zero_accel)

    def _read_exact(self, size: int, timeout: float) -> bytes | None:
        deadline = time.perf_counter() + timeout
        data = b""
        while len(data) < size:
            chunk = self._read_some(deadline)
            if not chunk:
                return None
            data += chunk
        return data

    def hello(self) -> dict:
        """Ask for θ ('r'): the legacy firmware has no INFO; this proves it answers."""
        self.port.reset_input_buffer()
        self.port.write(legacy.READ)
        word = self._read_exact(2, HANDSHAKE_TIMEOUT)
        if word is None:
            raise StationError(f"no answer to 'r' from {self.url} within {HANDSHAKE_TIMEOUT} s: is it the legacy firmware?")
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
                n, _theta, a, _, _ = self.read_sample()
                total += a
                self.send_command(n, 0.0)
        finally:
            self.stop()
            self._drain()
        mean = total / ZERO_ACCEL_TICKS
        self.accel_offset = int(mean + 0.5) if mean >= 0 else -int(-mean + 0.5)
        return {"by": "station pre-run", "ticks": ZERO_ACCEL_TICKS, "offset": self.accel_offset}

    def _drain(self, quiet: float = 0.02, limit: float = 0.5) -> None:
        """Discard input until the line has been quiet for ``quiet`` s (ticks in flight after 's')."""
        end = time.perf_counter() + limit
        while time.perf_counter() < end:
            if not self._read_some(time.perf_counter() + quiet):
                break
        self.port.reset_input_buffer()
        self._decoder = legacy.TickDecoder()
        self._pending = []

    def _begin(self) -> None:
        """v = 0, reset the encoder ('7'), start ('q'), read θ0.

        The old firmware applies the last v it received from tick 0 on, whatever run it
        came from (a station that died leaves it set): v = 0 goes first, so tick 0
        outputs 0 as the log's row 0 says.
        """
        self.port.write(legacy.command_bytes(0) + legacy.RESET + legacy.START)
        data = self._read_exact(2, HANDSHAKE_TIMEOUT)
        if data is None:
            raise StationError(f"no θ0 from {self.url} after 'q' within {HANDSHAKE_TIMEOUT} s")
        self._pending = self._decoder.feed(data[2:])
        self._n = -1

    def start(self, n_ticks: int) -> None:
        """Start the run (see :meth:`_begin`); n_ticks is checked, not sent (the device runs until 's')."""
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
            n did not advance by one (a lost or torn record: the stream is out of step).
        """
        deadline = time.perf_counter() + self.timeout
        while not self._pending:
            data = self._read_some(deadline)
            if not data:
                raise LinkTimeout(f"device {self.url} went silent: no sample for {self.timeout} s after tick {self._n}")
            self._pending = self._decoder.feed(data)
        tick = self._pending.pop(0)
        if tick.n != self._n + 1:
            raise SequenceError(f"legacy device {self.url}: tick number jumped from {self._n} to {tick.n}; stream out of step")
        self._n = tick.n
        return (tick.n, tick.theta, tick.accel - self.accel_offset, None, 0)

    def send_command(self, n: int, v: float) -> None:
        """Send '/' + v (truncated toward zero); n is implicit in this protocol."""
        self.port.write(legacy.command_bytes(v))

    def stop(self) -> dict | None:
        """v = 0, then 's' (the old firmware has no watchdog: this must run on every exit path)."""
        self.port.write(legacy.command_bytes(0) + legacy.STOP)
        try:
            self.port.flush()
        except (serial.SerialException, OSError):
            pass
        return None


_SESSIONS = {"v1": V1Session, "legacy": LegacySession}


def open_session(url: str, protocol: str = "v1", timeout: float = 0.1, baudrate: int | None = None) -> Session:
    """Open ``url`` and return a :class:`Session` of ``protocol`` ("v1" or "legacy").

    Raises StationError for an unknown protocol or a port that cannot be opened.
    """
    if protocol not in _SESSIONS:
        raise StationError(f"unknown protocol {protocol!r}: expected one of {', '.join(_SESSIONS)}")
    url = sim_url(url, protocol)
    return _SESSIONS[protocol](open_port(url, protocol, timeout, baudrate), url, timeout)
