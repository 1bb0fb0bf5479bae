"""Protocol v1: framed messages between the station and the SFLR device.

Frame = COBS(payload || crc16_le) || 0x00, where crc16 is CRC-16/CCITT-FALSE (poly
0x1021, init 0xFFFF, no reflection, xorout 0) over the payload and the payload is a type
byte followed by little-endian fields. Source: ``shared/spec/protocol.md``; every frame
in ``shared/spec/protocol-v1-vectors.json`` encodes and decodes exactly.

This module does no I/O: :func:`encode` turns a message into frame bytes and
:class:`Decoder` turns any byte stream into messages, dropping (and counting) bad
frames without ever raising.
"""

from __future__ import annotations

import binascii
import struct
from dataclasses import dataclass, fields

from cobs import cobs

from station.rounding import round_half_away

PROTOCOL_VERSION = 1
MAX_FRAME = 64
"""Longest frame on the wire, delimiter included, bytes."""

# status bits of SAMPLE
LATE = 1 << 0
WATCHDOG = 1 << 1
SATURATED = 1 << 2
RX_ERROR = 1 << 3
STALE = 1 << 4

# START flags
START_RESET_ENCODER = 1 << 0
START_ZERO_ACCEL = 1 << 1

# STOPPED reasons
STOPPED_BY_STOP = 0
STOPPED_N_TICKS = 1


@dataclass(frozen=True, slots=True)
class Sample:
    """SAMPLE (device→station): one interrupt tick.

    Attributes
    ----------
    seq : int
        Tick number mod 2**16.
    theta : int
        Encoder counts since the last reset (int32).
    accel : int
        Accelerometer, ADC counts (int16).
    v_applied : int
        DAC counts applied during this tick (int16).
    status : int
        LATE | WATCHDOG | SATURATED | RX_ERROR | STALE bits.
    """

    seq: int
    theta: int
    accel: int
    v_applied: int
    status: int


@dataclass(frozen=True, slots=True)
class Command:
    """COMMAND (station→device): v in DAC counts answering SAMPLE ``seq``.

    Attributes
    ----------
    seq : int
        The seq of the SAMPLE this command answers (u16).
    v : int
        Command, DAC counts (int16; the station rounds it, :func:`round_command`).
    """

    seq: int
    v: int


@dataclass(frozen=True, slots=True)
class Hello:
    """HELLO (station→device): asks for INFO.

    Attributes
    ----------
    protocol_version : int, default PROTOCOL_VERSION
        The protocol the station speaks (u8).
    """

    protocol_version: int = PROTOCOL_VERSION


@dataclass(frozen=True, slots=True)
class Info:
    """INFO (device→station): firmware identity and fixed settings.

    Attributes
    ----------
    protocol_version : int
        Protocol version (u8).
    fw_major, fw_minor, fw_patch : int
        Firmware version; with ``name`` they identify the implementation (u8 each).
    rate_hz : int
        Tick rate, Hz; 0 declares a lockstep device (u16).
    v_limit : int
        Output clamp, ±DAC counts (int16).
    counts_per_rev : int
        Encoder counts per base revolution (u16).
    watchdog_ticks : int
        Consecutive missed commands that trip the watchdog (u8).
    name : str
        At most 8 ASCII characters (NUL-padded on the wire).
    """

    protocol_version: int
    fw_major: int
    fw_minor: int
    fw_patch: int
    rate_hz: int
    v_limit: int
    counts_per_rev: int
    watchdog_ticks: int
    name: str


@dataclass(frozen=True, slots=True)
class Start:
    """START (station→device): begin a run.

    Attributes
    ----------
    flags : int
        START_RESET_ENCODER | START_ZERO_ACCEL (u8).
    n_ticks : int
        Ticks to run; 0 = until STOP (u32).
    """

    flags: int
    n_ticks: int


@dataclass(frozen=True, slots=True)
class Stop:
    """STOP (station→device): output 0 at once and answer STOPPED."""


@dataclass(frozen=True, slots=True)
class Stopped:
    """STOPPED (device→station): the run ended; its counters.

    Attributes
    ----------
    reason : int
        STOPPED_BY_STOP (0) or STOPPED_N_TICKS (1).
    ticks : int
        Samples sent in the run (u32).
    late, watchdog_trips, rx_errors : int
        The run's LATE ticks, ended watchdog trips and bad frames received (u16 each,
        saturating).
    """

    reason: int
    ticks: int
    late: int
    watchdog_trips: int
    rx_errors: int


Message = Sample | Command | Hello | Info | Start | Stop | Stopped

# type byte, message class, struct layout of the fields after the type byte
_LAYOUT: dict[int, tuple[type, struct.Struct]] = {
    0x01: (Sample, struct.Struct("<HihhB")),
    0x02: (Command, struct.Struct("<Hh")),
    0x03: (Hello, struct.Struct("<B")),
    0x04: (Info, struct.Struct("<BBBBHhHB8s")),
    0x05: (Start, struct.Struct("<BI")),
    0x06: (Stop, struct.Struct("<")),
    0x07: (Stopped, struct.Struct("<BIHHH")),
}
# per class: type byte, layout, field names (dataclasses.fields() per message costs a µs
# on the loop's hot path: every COMMAND)
_TYPE_OF = {cls: (code, layout, tuple(f.name for f in fields(cls))) for code, (cls, layout) in _LAYOUT.items()}


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE of ``data`` (binascii.crc_hqx with init 0xFFFF).

    Parameters
    ----------
    data : bytes
        The payload.

    Returns
    -------
    int
        The CRC, 0..0xFFFF.
    """
    return binascii.crc_hqx(data, 0xFFFF)


def encode(msg: Message) -> bytes:
    """Encode one message as a whole frame, trailing 0x00 delimiter included.

    Parameters
    ----------
    msg : Message
        A v1 message (:class:`Sample`, :class:`Command`, ...).

    Returns
    -------
    bytes
        COBS(payload ‖ crc16_le) ‖ 0x00, at most :data:`MAX_FRAME` bytes.

    Raises
    ------
    TypeError
        ``msg`` is not a v1 message.
    struct.error
        A field is out of its wire range (e.g. COMMAND v outside int16).
    """
    try:
        code, layout, names = _TYPE_OF[type(msg)]
    except KeyError:
        raise TypeError(f"not a protocol v1 message: {msg!r}") from None
    values = [getattr(msg, name) for name in names]
    if isinstance(msg, Info):
        values[-1] = msg.name.encode("ascii")[:8]  # struct pads '8s' with NULs
    payload = bytes([code]) + layout.pack(*values)
    return cobs.encode(payload + crc16(payload).to_bytes(2, "little")) + b"\x00"


def decode_payload(payload: bytes) -> Message | None:
    """Decode one COBS-decoded frame body (payload || crc16_le); None when invalid.

    Parameters
    ----------
    payload : bytes
        COBS-decoded frame body: type byte, fields, crc16 little-endian.
    """
    if len(payload) < 3:
        return None
    body, crc = payload[:-2], int.from_bytes(payload[-2:], "little")
    if crc16(body) != crc:
        return None
    entry = _LAYOUT.get(body[0])
    if entry is None:
        return None
    cls, layout = entry
    if len(body) - 1 != layout.size:
        return None
    values = list(layout.unpack_from(body, 1))
    if cls is Info:
        values[-1] = values[-1].rstrip(b"\x00").decode("ascii", "replace")
    return cls(*values)


class Decoder:
    """Incremental stream decoder: bytes in, messages out; never raises.

    A frame that fails COBS decoding, is shorter than 3 bytes, fails its CRC, has an
    unknown type or a wrong length, or grows past :data:`MAX_FRAME` bytes is dropped
    and counted in ``rx_errors``; decoding carries on after the next 0x00. Empty frames
    (two 0x00 in a row) are ignored and not counted.
    """

    __slots__ = ("_buf", "_overflow", "rx_errors")

    def __init__(self) -> None:
        self._buf = bytearray()
        self._overflow = False
        self.rx_errors = 0

    def feed(self, data: bytes) -> list[Message]:
        """Consume ``data`` (any length, any split); return the messages completed by it.

        Parameters
        ----------
        data : bytes
            The next bytes of the stream.

        Returns
        -------
        list of Message
            The messages whose frames ``data`` completed, in order (bad frames counted in
            ``rx_errors``, not returned).
        """
        out: list[Message] = []
        start = 0
        while True:
            end = data.find(0, start)
            if end < 0:
                self._append(data[start:])
                return out
            self._append(data[start:end])
            start = end + 1
            frame, overflow = bytes(self._buf), self._overflow
            self._buf.clear()
            self._overflow = False
            if overflow:
                self.rx_errors += 1
            elif frame:
                msg = self._decode_frame(frame)
                if msg is None:
                    self.rx_errors += 1
                else:
                    out.append(msg)

    def _append(self, chunk: bytes) -> None:
        if self._overflow or not chunk:
            return
        if len(self._buf) + len(chunk) >= MAX_FRAME:
            self._overflow = True  # too long to be a frame: drop until the next 0x00
            self._buf.clear()
            return
        self._buf += chunk

    @staticmethod
    def _decode_frame(frame: bytes) -> Message | None:
        try:
            payload = cobs.decode(frame)
        except cobs.DecodeError:
            return None
        return decode_payload(payload)


def round_command(v: float) -> int:
    """Round a command to whole DAC counts as the spec requires.

    Parameters
    ----------
    v : float
        The controller's output, DAC counts.

    Returns
    -------
    int
        Nearest integer, halves away from zero (:func:`station.rounding.round_half_away`),
        clamped to the int16 wire range.

    Raises
    ------
    ValueError
        ``v`` is NaN: a controller that produced it must not drive the motor.
    """
    if v != v:
        raise ValueError("command is NaN")
    return round_half_away(max(-32768.0, min(32767.0, v)))
