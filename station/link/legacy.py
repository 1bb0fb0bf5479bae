"""Legacy session: the rig's original PSoC protocol (``shared/spec/protocol.md``, "legacy")
on the :class:`Session` supervisor."""

from __future__ import annotations

import logging

import serial
from serial.serialutil import Timeout

from station.errors import StationError
from station.link.faults import SequenceError
from station.link.session import HANDSHAKE_TIMEOUT, ZERO_ACCEL_TICKS, Sample, Session, logger
from station.protocol import check_ticks, legacy, v1


class LegacySession(Session):
    """The rig's original PSoC protocol (``shared/spec/protocol.md``, "legacy").

    The device cannot declare lockstep: only a simulated port in lockstep pacing says so
    itself (``paced_by_host``), and a real one gets the slow-rate check. It
    cannot report late commands: ``late`` counts the held ticks the station sees (its
    skipped samples and its commands written after the next sample had arrived).

    Parameters
    ----------
    port, url, limits
        As :class:`Session`.
    """

    __slots__ = ("accel_offset",)
    protocol = "legacy"
    sample_bytes = 6

    def __init__(self, port, url, limits):
        super().__init__(port, url, limits)
        self._decoder = legacy.TickDecoder()
        self.accel_offset = 0  # subtracted from every accel sample (zero_accel)

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
        self._send(legacy.READ)
        word = self._read_exact(2, HANDSHAKE_TIMEOUT)
        if word is None:
            raise StationError(f"no answer to 'r' from {self.url} within {HANDSHAKE_TIMEOUT} s: is it the legacy "
                               "firmware? (try --protocol v1)")
        self.info = {"protocol": "legacy", "theta": legacy.decode_word(word[:2])}
        self.lockstep = bool(getattr(self.port, "paced_by_host", False))
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
                self._send(legacy.command_bytes(0))  # v = 0 throughout: no lag to guard
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
        self._send(legacy.command_bytes(0) + legacy.RESET + legacy.START)
        data = self._read_exact(2, HANDSHAKE_TIMEOUT)
        if data is None:
            raise StationError(f"no θ0 from {self.url} after 'q' within {HANDSHAKE_TIMEOUT} s")
        self._pending.clear()
        self._pending.extend(self._decoder.feed(data[2:]))
        self._theta = legacy.decode_word(data[:2])
        self._listen(self.timeout)

    def start(self, n_ticks: int) -> None:
        """Start the run (see :meth:`_begin`); n_ticks is checked, not sent (the device runs until 's').

        Parameters
        ----------
        n_ticks : int
            Ticks the run lasts.

        Raises
        ------
        StationError
            More ticks than the protocol counts (:func:`station.protocol.check_ticks`).
        """
        check_ticks(self.protocol, n_ticks)
        self._begin()

    def _next_pending(self) -> Sample | None:
        """The next tick record among the pending ones (hot path), accepted; None when none.

        Raises
        ------
        SequenceError
            n did not advance by one (a lost or torn record: the stream is out of step),
            or the encoder jumped implausibly (a byte slip whose n happened to match).
        RateError, LagError
            As :meth:`Session.read_sample`.
        """
        if not self._pending:
            return None
        tick = self._pending.popleft()
        if tick.n != self._n + 1:
            raise SequenceError(f"legacy device {self.url}: tick number jumped from {self._n} to {tick.n}; "
                                "stream out of step")
        self._accept(tick.n, tick.theta, 0)
        return Sample(tick.n, tick.theta, tick.accel - self.accel_offset, None, 0)

    def _lenient(self, msgs: list) -> list[Sample]:
        out = []
        for tick in msgs:
            if tick.n != self._n + 1:
                break  # out of step: nothing after it can be trusted
            self._n = tick.n
            out.append(Sample(tick.n, tick.theta, tick.accel - self.accel_offset, None, 0))
        return out

    def send_command(self, n: int, v: float) -> None:
        """Send '/' + v (truncated toward zero); n is implicit in this protocol.

        Raises LagError first when the station is more than ``max_lag`` behind
        (:meth:`Session._command`).

        Parameters
        ----------
        n : int
            The sample answered (implicit in this protocol: not sent).
        v : float
            The command, DAC counts.
        """
        self._command(n, legacy.command_bytes(v))

    def counters(self) -> dict:
        """As :meth:`Session.counters`; ``late`` counts the ticks the station knows ran on a held
        command (skipped samples and late commands, each tick once): the device cannot tell."""
        return {**super().counters(), "late": self.held}

    def stop(self) -> dict | None:
        """v = 0, then 's' (the old firmware has no watchdog: this must run on every exit path)."""
        self._send(legacy.command_bytes(0) + legacy.STOP)
        try:
            self.port.flush()
        except (serial.SerialException, OSError):
            pass
        return None
