"""Drive a :class:`~station.sim.device.SimDevice` from a transport, with optional faults.

A transport (the ``sim://`` handler, the pty server) owns the bytes and the clock; this
module owns what happens between them, once for every transport: the station's bytes go
in, replies and samples come out, through the fault injector. Pacing:

- lockstep: the device ticks as fast as the station answers — after START (legacy 'q')
  tick 0 runs at once, and each command for the current sample (legacy: each '/')
  triggers the next tick immediately (:meth:`DeviceDriver.feed` returns its bytes);
- realtime: the transport calls :meth:`DeviceDriver.clock_tick` every 2 ms whatever the
  station did; missing commands then show as LATE / hold / WATCHDOG.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from cobs import cobs

from station.protocol import legacy
from station.sim.device import SimDevice


@dataclass(frozen=True, slots=True)
class Faults:
    """Faults injected into the device's output stream, for tests of the station.

    Attributes
    ----------
    silent_after : int or None
        The device sends nothing after tick ``silent_after`` of a run (neither samples nor
        replies) but keeps running.
    garbage_every : int or None
        v1: after every ``garbage_every``-th sample, insert random non-zero bytes closed
        by 0x00 and then a SAMPLE frame with a corrupted CRC: two frames the station
        must drop and count. Legacy: ignored (no framing to resynchronise on).
    skip_tick : int or None
        Legacy: from tick ``skip_tick`` on, n is k + 1, as if that tick's record had
        been lost. v1: ignored.
    seed : int
        Seed of the garbage bytes.
    """

    silent_after: int | None = None
    garbage_every: int | None = None
    skip_tick: int | None = None
    seed: int = 0


class DeviceDriver:
    """A device plus its faults and pacing, as a transport sees it.

    Parameters
    ----------
    device : SimDevice
    faults : Faults, optional
        Default: none.
    lockstep : bool, default True
        Tick on the station's commands (True) or only on :meth:`clock_tick` (False).
    """

    def __init__(self, device: SimDevice, faults: Faults | None = None, lockstep: bool = True) -> None:
        self.device = device
        self.faults = faults or Faults()
        self.lockstep = lockstep
        device.set_lockstep(lockstep)
        self._rng = np.random.default_rng(self.faults.seed)

    def feed(self, data: bytes) -> bytes:
        """The station sent ``data``: the bytes the device sends in reply (lockstep: with the ticks it triggered).

        Parameters
        ----------
        data : bytes
            Bytes the station wrote.
        """
        dev = self.device
        dev.receive(data)
        out = self._filter_reply(dev.take_output())
        if self.lockstep:
            while dev.ready:
                out += self._tick()
        return out

    def clock_tick(self) -> bytes:
        """One tick of a real-time clock: the bytes the device sends (b"" when not running)."""
        return self._tick() if self.device.running else b""

    # -- fault injection ---------------------------------------------------------

    def _silent(self, k: int) -> bool:
        n = self.faults.silent_after
        return n is not None and k > n

    def _filter_reply(self, data: bytes) -> bytes:
        n = self.faults.silent_after
        return b"" if n is not None and self.device.ticks > n else data  # tick n has been sent

    def _tick(self) -> bytes:
        dev = self.device
        k = dev.tick_index
        data = dev.tick()
        if self._silent(k):
            return b""
        f = self.faults
        if dev.protocol == "legacy":
            if f.skip_tick is not None and k >= f.skip_tick:
                (t,) = legacy.TickDecoder().feed(data)
                data = legacy.tick_bytes(t._replace(n=(t.n + 1 + 32768) % 65536 - 32768))
        elif f.garbage_every and data and (k + 1) % f.garbage_every == 0:  # (a zeroing tick sends nothing)
            end = data.index(0) + 1  # the SAMPLE frame; a STOPPED may follow
            data = data[:end] + self._garbage(data[:end]) + data[end:]
        return data

    def _garbage(self, frame: bytes) -> bytes:
        """Random non-zero bytes closed by 0x00, then ``frame`` re-encoded with a wrong CRC."""
        junk = self._rng.integers(1, 256, size=int(self._rng.integers(1, 20)), dtype=np.uint8).tobytes()
        body = bytearray(cobs.decode(frame[:-1]))
        body[-1] ^= 0xFF  # the CRC's high byte: the frame decodes but fails its check
        return junk + b"\x00" + cobs.encode(bytes(body)) + b"\x00"
