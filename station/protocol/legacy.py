"""Legacy protocol: the rig's original PSoC firmware.

115200 baud 8N1, 16-bit big-endian two's-complement words, no framing, no checksum.
Station → device: ``q`` start a test (the device answers θ0, one word), ``7`` reset the
encoder, ``r`` read θ (one word), ``s`` stop, ``/`` + v (one word, truncated toward
zero) set the command. After ``q`` the device sends n, θ, a (three words) every tick;
n counts ticks from 0 as int16, so a test lasts at most 32767 ticks. There is no
resynchronisation: the station checks that n advances by one per tick. Source:
``shared/spec/protocol.md`` ("legacy").

This module does no I/O; the decoders never raise.
"""

from __future__ import annotations

import math
import struct
from typing import NamedTuple

BAUDRATE = 115200
START = b"q"
RESET = b"7"
READ = b"r"
STOP = b"s"
SET = b"/"
MAX_TICKS = 32767
"""n is a signed 16-bit word: the longest test in ticks."""

_WORD = struct.Struct(">h")
_TICK = struct.Struct(">hhh")


class Tick(NamedTuple):
    """One tick record from the device.

    Attributes
    ----------
    n : int
        Tick number from 0 (signed 16-bit: a test lasts at most 32767 ticks).
    theta : int
        Encoder counts (int16).
    accel : int
        Accelerometer, ADC counts (int16).
    """

    n: int
    theta: int
    accel: int


def encode_word(value: int) -> bytes:
    """One big-endian int16 word.

    Parameters
    ----------
    value : int
        −32768..32767.

    Returns
    -------
    bytes
        Two bytes, big-endian two's complement.

    Raises
    ------
    struct.error
        ``value`` outside −32768..32767.
    """
    return _WORD.pack(value)


def decode_word(data: bytes) -> int:
    """Inverse of :func:`encode_word` for exactly two bytes.

    Parameters
    ----------
    data : bytes
        Exactly two bytes.

    Returns
    -------
    int
        The signed 16-bit value.
    """
    return _WORD.unpack(data)[0]


def command_bytes(v: float) -> bytes:
    """``/`` + v as the old firmware expects: truncated toward zero, clamped to int16.

    Parameters
    ----------
    v : float
        The command, DAC counts.

    Returns
    -------
    bytes
        ``/`` followed by one big-endian word.

    Raises
    ------
    ValueError
        ``v`` is NaN (a controller that produced it must not drive the motor).
    """
    if math.isnan(v):
        raise ValueError("command is NaN")
    return SET + encode_word(int(max(-32768.0, min(32767.0, v))))


def tick_bytes(tick: Tick) -> bytes:
    """The six bytes the device sends for one tick (used by the simulated device).

    Parameters
    ----------
    tick : Tick
        The record; each field must fit a signed 16-bit word.
    """
    return _TICK.pack(*tick)


class TickDecoder:
    """Station side: groups the device's byte stream into :class:`Tick` records.

    The stream has no framing, so this only splits bytes into 6-byte records; whether
    they are in step is checked by the caller through n (see the module docstring).
    """

    __slots__ = ("_buf",)

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> list[Tick]:
        """Consume ``data``; return the complete tick records it finished.

        Parameters
        ----------
        data : bytes
            The next bytes from the device.
        """
        self._buf += data
        whole = len(self._buf) - len(self._buf) % 6
        out = [Tick(*t) for t in _TICK.iter_unpack(self._buf[:whole])]
        del self._buf[:whole]
        return out

    @property
    def pending(self) -> int:
        """Bytes received but not yet part of a whole record."""
        return len(self._buf)


class CommandDecoder:
    """Device side: parses the station's commands; never raises.

    ``feed`` returns tuples ``("q",)``, ``("7",)``, ``("r",)``, ``("s",)`` and
    ``("/", v)``; any other byte is dropped and counted in ``errors``.
    """

    __slots__ = ("_pending", "errors")

    def __init__(self) -> None:
        self._pending = bytearray()  # b"/" plus up to one byte of its word
        self.errors = 0

    def feed(self, data: bytes) -> list[tuple]:
        """Consume ``data``; return the commands completed by it.

        Parameters
        ----------
        data : bytes
            The next bytes from the station.

        Returns
        -------
        list of tuple
            ``("q",)``, ``("7",)``, ``("r",)``, ``("s",)`` or ``("/", v)`` per command, in order.
        """
        out: list[tuple] = []
        for byte in data:
            if self._pending:
                self._pending.append(byte)
                if len(self._pending) == 3:
                    out.append(("/", decode_word(bytes(self._pending[1:]))))
                    self._pending.clear()
                continue
            ch = bytes((byte,))
            if ch == SET:
                self._pending.append(byte)
            elif ch in (START, RESET, READ, STOP):
                out.append((ch.decode(),))
            else:
                self.errors += 1
        return out
