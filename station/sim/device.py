"""The simulated device: the firmware side of protocol v1 and of the legacy protocol.

Pure logic, no I/O and no clock: bytes from the station go in through
:meth:`SimDevice.receive`; each 500 Hz interrupt tick is one call of
:meth:`SimDevice.tick`, which returns the bytes that tick sends; replies not tied to a
tick (INFO, STOPPED after STOP, the legacy θ words) come from
:meth:`SimDevice.take_output`. A transport (``protocol_sim``, ``pty_server``) decides
when ticks happen. Source: ``shared/spec/protocol.md`` (v1 tick order, START/STOP, status
bits; legacy) and ``shared/DESIGN.md`` ("Timing and log rows").
"""

from __future__ import annotations

from dataclasses import dataclass

from station.plant import Sensors
from station.protocol import PROTOCOLS, legacy, v1
from station.rig import COUNTS_PER_REV, DAC_LIMIT, RATE_HZ
from station.rounding import round_half_away
from station.sim.hardware import ACCEL_OFFSET, ZERO_ACCEL_READINGS, Hardware
from station.plant.model import as_model

FW_VERSION = (0, 1, 0)
"""INFO fw_major/minor/patch of the simulated device (the firmware in ``firmware/`` says 1.0.0)."""
NAME = "SIMRIG"
"""INFO name of the simulated device (spec: it names itself "SIMRIG")."""


@dataclass(slots=True)
class Counters:
    """A run's counters (reset by v1 START / legacy 'q'), as STOPPED reports them.

    Attributes
    ----------
    ticks : int
        Samples sent.
    late : int
        Ticks whose command had not arrived (v1: LATE samples; legacy: ticks with no '/'
        since the previous tick).
    watchdog_trips : int
        v1 watchdog trips ended by a command with the expected seq.
    rx_errors : int
        Bad frames (v1) or unknown bytes (legacy) received.
    """

    ticks: int = 0
    late: int = 0
    watchdog_trips: int = 0
    rx_errors: int = 0


def _int16(x: int) -> int:
    """Clip to the int16 range (an ADC reading cannot leave it)."""
    return max(-32768, min(32767, x))


def _wrap16(x: int) -> int:
    """Two's-complement wrap to int16 (a 16-bit counter sent as a word)."""
    return (x + 32768) % 65536 - 32768


class _Firmware:
    """What both protocols' firmware share: the hardware, the run state and the reply buffer."""

    def __init__(self, hw: Hardware) -> None:
        self.hw = hw
        self.counters = Counters()
        self.running = False
        self.k = 0  # index of the next tick of the run
        self._out = bytearray()

    def take_output(self) -> bytes:
        out, self._out = bytes(self._out), bytearray()
        return out

    def _begin_run(self) -> None:
        self.counters = Counters()
        self.running = True
        self.k = 0
        self.hw.restart()  # every run from rest with the same noise: identical runs, identical logs


class _V1Firmware(_Firmware):
    """Protocol v1 device side (spec "v1")."""

    def __init__(self, hw: Hardware, watchdog_ticks: int, name: str) -> None:
        super().__init__(hw)
        self.watchdog_ticks = watchdog_ticks
        self.name = name
        self.rate_hz = RATE_HZ  # INFO's rate_hz: 0 declares a lockstep device (spec)
        self.decoder = v1.Decoder()
        self.n_ticks = 0
        self.output = 0  # the output held between ticks (DAC counts)
        self.command: int | None = None  # v of the COMMAND with seq k-1, once it arrived
        self.misses = 0  # consecutive ticks without their command
        self.tripped = False
        self.stale = False
        self.rx_error = False  # a bad frame since the last sample (RX_ERROR)
        self.zeroing = 0  # START bit1: accelerometer readings still to average (no SAMPLE meanwhile)
        self._accel_sum = 0
        self._reset_encoder = False

    @property
    def ready(self) -> bool:
        return self.running and (self.zeroing > 0 or self.k == 0 or self.command is not None)

    def receive(self, data: bytes) -> None:
        # frame by frame, as the firmware handles each frame when its 0x00 arrives: a bad
        # frame before a START is the old run's, one after it the new run's
        start = 0
        while start < len(data):
            end = data.find(0, start)
            end = len(data) if end < 0 else end + 1
            errors = self.decoder.rx_errors
            msgs = self.decoder.feed(data[start:end])
            start = end
            if self.decoder.rx_errors != errors:
                self.counters.rx_errors += self.decoder.rx_errors - errors
                self.rx_error = True
            for msg in msgs:
                self._handle(msg)

    def _handle(self, msg: v1.Message) -> None:
        if isinstance(msg, v1.Command):
            if self.running and self.k > 0 and msg.seq == (self.k - 1) & 0xFFFF:
                self.command = msg.v
            elif self.running:  # (no run: nothing to flag, START clears the flags)
                self.stale = True  # late, bogus, during zeroing or before SAMPLE 0: ignored
        elif isinstance(msg, v1.Hello):
            self._out += v1.encode(v1.Info(v1.PROTOCOL_VERSION, *FW_VERSION, self.rate_hz, self.hw.v_limit,
                                           COUNTS_PER_REV, self.watchdog_ticks, self.name))
        elif isinstance(msg, v1.Start):
            self._start(msg)
        elif isinstance(msg, v1.Stop):
            self._out += self._stop(v1.STOPPED_BY_STOP)
        # SAMPLE, INFO, STOPPED are device→station: a station never sends them; ignored.

    def _start(self, msg: v1.Start) -> None:
        """Every counter and flag of the run restarts; bit1: 16 ticks of zeroing first; bit0: encoder zeroed before tick 0."""
        self.output = 0
        self._begin_run()
        self.n_ticks = msg.n_ticks
        self.command = None
        self.misses = 0
        self.tripped = False
        self.stale = False
        self.rx_error = False
        self.hw.accel_zero = 0  # the offset is the run's: a START without bit1 subtracts none
        self._reset_encoder = bool(msg.flags & v1.START_RESET_ENCODER)
        self._accel_sum = 0
        self.zeroing = ZERO_ACCEL_READINGS if msg.flags & v1.START_ZERO_ACCEL else 0
        if not self.zeroing and self._reset_encoder:
            self.hw.zero_encoder()

    def _zeroing_tick(self) -> bytes:
        """One of START bit1's ticks: output 0, one accelerometer reading, no SAMPLE."""
        self._accel_sum += _int16(self.hw.tick(0).a)
        self.zeroing -= 1
        if not self.zeroing:
            self.hw.accel_zero = round_half_away(self._accel_sum / ZERO_ACCEL_READINGS)
            if self._reset_encoder:
                self.hw.zero_encoder()  # just before tick 0
        return b""

    def _stop(self, reason: int) -> bytes:
        """End the run (output 0 at once); the STOPPED frame that reports it."""
        self.running = False
        self.zeroing = 0
        self.output = 0
        c = self.counters
        return v1.encode(v1.Stopped(reason, c.ticks, min(c.late, 0xFFFF), min(c.watchdog_trips, 0xFFFF),
                                    min(c.rx_errors, 0xFFFF)))

    def tick(self) -> bytes:
        """Tick k in the spec's order: (1) choose the output, (2) apply it, (3) latch, (4) send SAMPLE k."""
        if self.zeroing:
            return self._zeroing_tick()
        c = self.counters
        status = 0
        # (1) choose the output
        if self.k == 0:
            v = 0
        elif self.command is not None:
            v = self.command
            if self.tripped:
                c.watchdog_trips += 1
            self.misses, self.tripped = 0, False
        else:
            self.misses += 1
            c.late += 1
            status |= v1.LATE
            if self.misses >= self.watchdog_ticks:
                self.tripped = True
                status |= v1.WATCHDOG
                v = 0
            else:
                v = self.output
        self.command = None
        v, saturated = self.hw.clamp(v)
        if saturated:
            status |= v1.SATURATED
        # (2) apply, (3) latch: the readings see the state before v acts
        self.output = v
        reading = self.hw.tick(v)
        # (4) send SAMPLE k
        if self.rx_error:
            status |= v1.RX_ERROR
            self.rx_error = False
        if self.stale:
            status |= v1.STALE
            self.stale = False
        out = v1.encode(v1.Sample(self.k & 0xFFFF, reading.theta, _int16(reading.a), v, status))
        self.k += 1
        c.ticks += 1
        if self.n_ticks and self.k >= self.n_ticks:
            out += self._stop(v1.STOPPED_N_TICKS)
        return out


class _LegacyFirmware(_Firmware):
    """The rig's original PSoC firmware (spec "legacy"): no framing, no watchdog."""

    def __init__(self, hw: Hardware) -> None:
        super().__init__(hw)
        self.decoder = legacy.CommandDecoder()
        self.v = 0  # the last v received; applied every tick, also after the station died
        self.fresh = False  # a '/' arrived since the previous tick
        self._rx_at_start = 0

    @property
    def ready(self) -> bool:
        return self.running and (self.k == 0 or self.fresh)

    def receive(self, data: bytes) -> None:
        for cmd in self.decoder.feed(data):
            op = cmd[0]
            if op == "/":
                self.v = cmd[1]
                self.fresh = True
            elif op == "q":
                self._begin_run()
                self._rx_at_start = self.decoder.errors
                self.fresh = False
                self._out += self._theta_word()
            elif op == "7":
                self.hw.zero_encoder()
            elif op == "r":
                self._out += self._theta_word()
            elif op == "s":
                self.running = False
        self.counters.rx_errors = self.decoder.errors - self._rx_at_start

    def _theta_word(self) -> bytes:
        return legacy.encode_word(_wrap16(self.hw.read().theta))

    def tick(self) -> bytes:
        """Tick k: apply the last v received, latch, send n, θ, a."""
        if self.k > 0 and not self.fresh:
            self.counters.late += 1
        self.fresh = False
        v, _ = self.hw.clamp(self.v)
        reading = self.hw.tick(v)
        out = legacy.tick_bytes(legacy.Tick(_wrap16(self.k), _wrap16(reading.theta), _int16(reading.a)))
        self.k += 1
        self.counters.ticks += 1
        return out


class SimDevice:
    """The device side of a protocol on a simulated plant; no I/O, no clock.

    Parameters
    ----------
    protocol : {"v1", "legacy"}, default "v1"
        Which firmware to run (``shared/spec/protocol.md``).
    plant : object, optional
        ``reset()``, ``outputs() -> (theta, a)`` (noise-free floats, encoder and ADC
        counts), ``advance(v)`` (one 2 ms zero-order-hold step). Default: ``model``'s
        tick-by-tick plant (:meth:`station.plant.model.Model.plant`, effects included).
        Reset on construction.
    seed : int, default 0
        Seed of the default sensors' noise, so a run is reproducible.
    n_elements : int, optional
        FEM element count of the default plant (default: the model's, 4 for tmm-fit).
    model : Model, str or Path, optional
        The model behind the default plant: a :class:`station.plant.model.Model`, a
        built-in model's name or a model file (default "tmm-fit", the nominal FEM).
    accel_noise_std : float, default 0.3
        Accelerometer noise of the default sensors, ADC counts (std).
    sensors : object, optional
        ``read(theta, a) -> (int, int)``. Default ``station.plant.Sensors(seed,
        accel_noise_std)``.
    accel_offset : float, default -2.0
        Accelerometer reading at rest, counts (DESIGN.md); v1 START bit1 removes it.
    v_limit : int, default 255
        The DAC's range, ±counts: v1 clamps and sets SATURATED; legacy clamps.
    watchdog_ticks : int, default 10
        v1: consecutive missed commands after which the output is 0 and WATCHDOG set.
    name : str, default :data:`NAME` ("SIMRIG")
        v1 INFO name (at most 8 ASCII characters).

    Raises
    ------
    ValueError
        Unknown ``protocol``, or ``watchdog_ticks`` outside 1..255.

    Notes
    -----
    v1: tick k (1) chooses the output (tick 0: 0; the COMMAND with seq k−1 if it arrived;
    else hold + LATE, and from the ``watchdog_ticks``-th consecutive miss 0 + WATCHDOG),
    clamps it (SATURATED), (2) applies it, (3) latches the sensors, which see the plant
    before this output acts, (4) sends SAMPLE k; reaching START's n_ticks appends
    STOPPED reason 1 to SAMPLE n_ticks−1. START bit1: the next 16 ticks average the
    accelerometer (output 0, no SAMPLE; lockstep runs them at once), then bit0 zeroes
    the encoder and tick 0 follows. STOP: output 0 and STOPPED at once. The same
    stimulus gives the same bytes as the firmware core in ``firmware/core`` but for
    INFO's version and name (``tests/test_device_golden.py``). Legacy: 'q' answers θ0 and starts the run; tick k applies the last
    v received and sends n = k, θ, a; 's' stops sending, the last v stays (no watchdog).
    Counters (:attr:`ticks`, :attr:`late`, :attr:`watchdog_trips`, :attr:`rx_errors`)
    are those of the current run and reset when a run starts. The plant only evolves
    during ticks: a transport calls :meth:`tick` while :attr:`running`.
    """

    def __init__(self, protocol: str = "v1", plant=None, seed: int = 0, *, n_elements: int | None = None,
                 model=None, accel_noise_std: float = 0.3, sensors=None, accel_offset: float = ACCEL_OFFSET,
                 v_limit: int = int(DAC_LIMIT), watchdog_ticks: int = 10, name: str = NAME) -> None:
        if protocol not in PROTOCOLS:
            raise ValueError(f"unknown protocol {protocol!r}: expected one of {', '.join(PROTOCOLS)}")
        if not 1 <= watchdog_ticks <= 255:
            raise ValueError(f"watchdog_ticks must be 1..255 (a u8 in INFO), got {watchdog_ticks}")
        if plant is None:
            plant = as_model(model, n_elements).plant()
        if sensors is None:
            sensors = Sensors(seed=seed, accel_noise_std=accel_noise_std)
        self.protocol = protocol
        hw = Hardware(plant, sensors, accel_offset=accel_offset, v_limit=v_limit)
        self._fw = _V1Firmware(hw, watchdog_ticks, name) if protocol == "v1" else _LegacyFirmware(hw)

    def receive(self, data: bytes) -> None:
        """Feed bytes from the station (any split); commands take effect at once, replies go to :meth:`take_output`.

        Parameters
        ----------
        data : bytes
            Bytes from the station, split anywhere.
        """
        self._fw.receive(data)

    def tick(self) -> bytes:
        """One 500 Hz interrupt tick; the bytes it sends (b"" when no run is going on)."""
        return self._fw.tick() if self._fw.running else b""

    def take_output(self) -> bytes:
        """Replies not tied to a tick, in order, since the last call (INFO, STOPPED after STOP, legacy θ words)."""
        return self._fw.take_output()

    @property
    def running(self) -> bool:
        """A run is going on: each :meth:`tick` sends a sample."""
        return self._fw.running

    @property
    def ready(self) -> bool:
        """Lockstep pacing: the next tick's command is in (or the next tick is tick 0), so it can run now."""
        return self._fw.ready

    def set_lockstep(self, lockstep: bool) -> None:
        """Declare the pacing in v1 INFO: rate_hz = 0 for lockstep, 500 for its own clock (spec).

        Parameters
        ----------
        lockstep : bool
            True: the transport ticks the device on the station's commands (INFO rate_hz 0).
        """
        if isinstance(self._fw, _V1Firmware):
            self._fw.rate_hz = 0 if lockstep else RATE_HZ

    @property
    def plant(self):
        """The plant behind the device (a :class:`station.plant.simulate.ModelPlant` by default)."""
        return self._fw.hw.plant

    @property
    def tick_index(self) -> int:
        """k of the next tick of the run."""
        return self._fw.k

    @property
    def counters(self) -> Counters:
        """The current run's counters (a copy)."""
        c = self._fw.counters
        return Counters(c.ticks, c.late, c.watchdog_trips, c.rx_errors)

    ticks = property(lambda self: self._fw.counters.ticks, doc="Ticks sent in the current run.")
    late = property(lambda self: self._fw.counters.late, doc="Late ticks in the current run (see :class:`Counters`).")
    watchdog_trips = property(lambda self: self._fw.counters.watchdog_trips, doc="v1 watchdog trips ended in the current run.")
    rx_errors = property(lambda self: self._fw.counters.rx_errors, doc="Bad frames (v1) / unknown bytes (legacy) in the current run.")
