"""Protocol v1 session (framed, ours; ``shared/spec/protocol.md``) on the :class:`Session` supervisor."""

from __future__ import annotations

import dataclasses
import logging

from serial.serialutil import Timeout

from station.rig import DT
from station.errors import StationError
from station.link.faults import DeviceStopped
from station.link.session import HANDSHAKE_TIMEOUT, ZERO_ACCEL_TICKS, Sample, Session, logger
from station.protocol import v1

FIRST_SEQ_WINDOW = 16
"""v1: the first sample of a run must have seq <= this (the device restarts at 0 on START);
a larger one was in flight from an earlier run and is ignored."""


class V1Session(Session):
    """Protocol v1 session (``shared/spec/protocol.md``).

    Parameters
    ----------
    port, url, limits
        As :class:`Session`.
    """

    __slots__ = ("_last_seq",)
    protocol = "v1"
    sample_bytes = 16

    def __init__(self, port, url, limits):
        super().__init__(port, url, limits)
        self._decoder = v1.Decoder()
        self._last_seq = -1

    def _write(self, msg) -> None:
        self._send(v1.encode(msg), ("%s", msg))

    def _next_message(self, deadline: Timeout):
        """The next decoded message, or None when ``deadline`` expires first (whatever arrives)."""
        while not self._pending:
            if deadline.expired():
                return None
            self._receive()
        return self._pending.popleft()

    def hello(self) -> dict:
        """Send HELLO and wait for INFO; returns INFO's fields as a dict.

        INFO rate_hz = 0 declares a lockstep device: it ticks when asked, so it has no rate to
        check (a wait is the host's, bounded by the sample timeout).

        Raises StationError when no INFO arrives within 1 s, whatever else arrives
        (not a v1 device?).
        """
        self.port.reset_input_buffer()
        # an empty frame first (spec: ignored) ends whatever a wrong-protocol attempt left in
        self._send(b"\x00")  # the device's frame buffer, so it cannot swallow HELLO
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
        self._listen(self.timeout + ZERO_ACCEL_TICKS * DT)

    def _next_pending(self) -> Sample | None:
        """The next valid, new SAMPLE among the pending messages (hot path), or None.

        Modular sequence arithmetic: a repeated seq is a duplicate, a seq behind the last
        one is stale (both discarded and counted), a gap of g counts g − 1 dropped; the
        sample is then accepted (:meth:`Session._accept`: plausibility, LATE, rate).
        STOPPED raises :class:`DeviceStopped` (n_ticks reached).
        """
        pending = self._pending
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
        return None

    def _lenient(self, msgs: list) -> list[Sample]:
        out = []
        for msg in msgs:
            if type(msg) is v1.Sample and self._last_seq >= 0 and 0 < (step := (msg.seq - self._last_seq) & 0xFFFF) < 0x8000:
                self._n += step
                self._last_seq = msg.seq
                out.append(Sample(self._n, msg.theta, msg.accel, msg.v_applied, msg.status))
        return out

    def send_command(self, n: int, v: float) -> None:
        """Answer sample n with command v (DAC counts, rounded halves away from zero).

        Raises LagError first when the station is more than ``max_lag`` behind
        (:meth:`Session._command`).

        Parameters
        ----------
        n : int
            The sample answered (its seq is n mod 2**16).
        v : float
            The command, DAC counts.
        """
        seq = n & 0xFFFF
        self._command(n, v1.encode(v1.Command(seq, v1.round_command(v))), ("COMMAND seq %d v %r", seq, v))

    def stop(self) -> dict | None:
        """Command 0 for the last sample, then STOP; wait for STOPPED. Returns its fields or None
        (the samples that arrive meanwhile are kept for :meth:`Session.unread_samples`).

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
            self._stop_seen.append(msg)  # samples in flight: logged (unread_samples)
        return None
