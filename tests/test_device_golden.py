"""One v1 device in behaviour: the firmware core (C) and the simulated device (Python) on one stimulus.

The C core runs in ``firmware/tests/golden_harness.c`` (built here with make/gcc): the
test writes one line per step (bytes from the station, the raw encoder/ADC values the
next latches see, a tick) and reads the bytes the core sent during each step. The
Python :class:`~station.sim.device.SimDevice` runs the same steps on a scripted plant
whose sensors return the same raw values. Every output frame must be equal byte for
byte, except INFO's fw_major/minor/patch and name, which identify the implementation
(``shared/spec/protocol.md``). No timer anywhere: a tick happens when the script says.
"""

from __future__ import annotations

import os
import random
import shutil
import subprocess
from pathlib import Path

import pytest
from cobs import cobs

from station.protocol import v1
from station.sim.device import SimDevice

REPO = Path(__file__).resolve().parents[1]
WATCHDOG = 10  # both implementations' default watchdog_ticks


@pytest.fixture(scope="module")
def harness(tmp_path_factory) -> Path:
    """The C core's line-driven harness, built with the firmware's own Makefile."""
    missing = [tool for tool in ("gcc", "make") if shutil.which(tool) is None]
    if missing:
        msg = f"{' and '.join(missing)} not found: cannot build firmware/tests/golden_harness.c"
        if os.environ.get("STATION_REQUIRE_SHARED") == "1":
            pytest.fail(msg + "; STATION_REQUIRE_SHARED=1 forbids skipping")
        pytest.skip(msg)
    build = tmp_path_factory.mktemp("fw")
    subprocess.run(["make", "-s", "-C", str(REPO / "firmware"), f"BUILD={build}", "harness"], check=True,
                   capture_output=True)
    return build / "golden_harness"


# -- running a script on both ---------------------------------------------------

class ScriptedPlant:
    """A plant whose outputs are whatever the script set; it records the outputs applied."""

    def __init__(self) -> None:
        self.theta, self.a = 0, 0
        self.applied: list[int] = []

    def reset(self) -> None:
        self.applied.clear()

    def outputs(self) -> tuple[float, float]:
        return self.theta, self.a

    def advance(self, v) -> None:
        self.applied.append(int(v))


class RawSensors:
    """The ADC and encoder reading exactly the scripted raw values."""

    def read(self, theta, a) -> tuple[int, int]:
        return int(theta), int(a)


def run_c(harness: Path, steps) -> list[bytes]:
    lines = []
    for step in steps:
        if step[0] == "rx":
            lines.append("rx " + step[1].hex())
        elif step[0] == "sensors":
            lines.append(f"sensors {step[1]} {step[2]}")
        else:
            lines.append("tick")
    out = subprocess.run([str(harness)], input="\n".join(lines) + "\n", capture_output=True, text=True,
                         check=True).stdout.split("\n")
    assert len(out) == len(steps) + 1 and out[-1] == "", "the harness answers one line per step"
    return [bytes.fromhex(line) for line in out[:-1]]


def run_python(steps) -> list[bytes]:
    plant = ScriptedPlant()
    dev = SimDevice("v1", plant=plant, sensors=RawSensors(), accel_offset=0.0, watchdog_ticks=WATCHDOG)
    return [play(dev, plant, step) for step in steps]


def frames_of(data: bytes) -> list[bytes]:
    return [f + b"\x00" for f in data.split(b"\x00")[:-1]] if data else []


def comparable(frame: bytes) -> bytes:
    """The frame itself; for INFO, the frame with version and name blanked (they identify the implementation)."""
    msg = v1.Decoder().feed(frame)
    if len(msg) == 1 and isinstance(msg[0], v1.Info):
        i = msg[0]
        return v1.encode(v1.Info(i.protocol_version, 0, 0, 0, i.rate_hz, i.v_limit, i.counts_per_rev,
                                 i.watchdog_ticks, ""))
    return frame


def assert_same(harness, steps) -> list[bytes]:
    c_out, py_out = run_c(harness, steps), run_python(steps)
    for i, (step, c, py) in enumerate(zip(steps, c_out, py_out)):
        fc, fp = frames_of(c), frames_of(py)
        same = len(fc) == len(fp) and all(comparable(a) == comparable(b) for a, b in zip(fc, fp))
        assert same, (f"step {i} {step[0]} {step[1:] if step[0] != 'rx' else step[1].hex()}: "
                      f"C sent {describe(c)}, Python sent {describe(py)}")
    return c_out


def describe(data: bytes) -> str:
    return repr(v1.Decoder().feed(data)) + f" ({data.hex()})"


# -- the stimulus -----------------------------------------------------------------

def rx(*msgs_or_bytes) -> tuple:
    return ("rx", b"".join(m if isinstance(m, bytes) else v1.encode(m) for m in msgs_or_bytes))


def bad_crc(msg) -> bytes:
    body = bytearray(cobs.decode(v1.encode(msg)[:-1]))
    body[-1] ^= 0x5A
    return cobs.encode(bytes(body)) + b"\x00"


def wrong_length(code: int, n: int) -> bytes:
    payload = bytes([code]) + bytes(range(1, n + 1))
    return cobs.encode(payload + v1.crc16(payload).to_bytes(2, "little")) + b"\x00"


GARBAGE = [
    b"\x13\x37\x00",  # not COBS
    b"\x01\x00",  # shorter than 3 bytes
    bytes([0x42]) * 80 + b"\x00",  # overlong
    wrong_length(0x02, 3),  # COMMAND one byte short
    wrong_length(0x09, 4),  # unknown type
    wrong_length(0x06, 1),  # STOP with a field
]


class Script:
    """Build a stimulus: sensor values change every tick, ticks and replies tracked."""

    def __init__(self) -> None:
        self.steps: list[tuple] = []
        self.n = 0  # ticks so far (drives the sensor values)
        self.seq = 0  # seq of the next SAMPLE the run will send (as the station tracks it)

    def tick(self, accel=None, theta=None) -> None:
        k = self.n
        self.n += 1
        theta = 1000 + 7 * k - (k * k) % 13 if theta is None else theta
        accel = ((k * 5) % 9) - 6 if accel is None else accel
        self.steps += [("sensors", theta, accel), ("tick",)]

    def rx(self, *items) -> None:
        self.steps.append(rx(*items))

    def sample(self, v=None, **kw) -> None:
        """One tick, then (v given) the COMMAND answering it, on time."""
        self.tick(**kw)
        self.seq += 1
        if v is not None:
            self.rx(v1.Command((self.seq - 1) & 0xFFFF, v))

    def start(self, flags, n_ticks=0, zero_values=None) -> None:
        self.rx(v1.Start(flags, n_ticks))
        self.seq = 0
        if flags & v1.START_ZERO_ACCEL:
            for a in zero_values or [-2, -3] * 8:
                self.tick(accel=a)


def the_script() -> list[tuple]:
    s = Script()
    # idle: bad and empty frames, a stray COMMAND, HELLO, STOP, ticks
    s.rx(GARBAGE[0])
    s.rx(b"\x00\x00")
    s.rx(v1.Command(0, 5))
    s.rx(v1.Hello())
    s.rx(v1.Stop())
    s.tick()
    # START without flags: a COMMAND before SAMPLE 0 is stale; commands on time (one saturates)
    s.start(0)
    s.rx(v1.Command(0, 9))
    s.sample(40)
    for v in (50, 300, -300, 255, -256, 7):
        s.sample(v)
    # late: two misses hold, then on time again
    s.sample()
    s.sample()
    s.sample(-20)
    s.sample(-21)
    # missing past the watchdog, then the expected seq ends the trip
    for _ in range(WATCHDOG + 3):
        s.sample()
    s.rx(v1.Command((s.seq - 1) & 0xFFFF, 33))
    s.sample(34)
    # garbage of every kind, one per tick, and several in one chunk with a COMMAND among them
    for g in GARBAGE:
        s.rx(g)
        s.sample(35)
    s.rx(GARBAGE[1], v1.Command((s.seq - 1) & 0xFFFF, 36), GARBAGE[2], b"\x00")
    s.sample(37)
    # wrong seq: from the future, a repeat of an old one, a duplicate of the right one
    s.rx(v1.Command((s.seq + 5) & 0xFFFF, 99))
    s.sample(38)
    s.rx(v1.Command((s.seq - 2) & 0xFFFF, 98))
    s.sample(39)
    s.rx(v1.Command((s.seq - 1) & 0xFFFF, 40))
    s.sample(41)
    # a frame split over several writes; HELLO mid-run
    frame = v1.encode(v1.Command((s.seq - 1) & 0xFFFF, 42))
    s.steps += [("rx", frame[:3]), ("rx", frame[3:7])]
    s.tick()
    s.steps.append(("rx", frame[7:]))  # completes after the tick it answered: stale now
    s.rx(v1.Hello())
    s.sample(43)
    # STOP: STOPPED at once, nothing after it, commands ignored
    s.sample(44)
    s.rx(v1.Stop())
    s.tick()
    s.rx(v1.Command(0, 1))
    s.tick()
    # re-START with bit0 (encoder zeroed at once), then START during the run with bit1 and
    # bit0: 16 ticks of averaging (mean -2.5 -> -3), a COMMAND, HELLO and garbage meanwhile
    s.start(v1.START_RESET_ENCODER)
    s.sample(10)
    s.sample(11, accel=-32768)
    s.rx(GARBAGE[3], v1.Start(v1.START_RESET_ENCODER | v1.START_ZERO_ACCEL, 0))
    s.seq = 0
    for i, a in enumerate([-2, -3] * 8):
        if i == 3:
            s.rx(v1.Command(0, 77), v1.Hello(), GARBAGE[0])
        s.tick(accel=a)
    s.sample(12)
    s.sample(13, accel=-32768)  # offset -3: -32765
    s.sample(14, accel=32767)  # saturates at 32767
    # the offset is the run's: START with bit1 on positive readings (mean 2.5 -> 3); then
    # START without bit1 subtracts none
    s.start(v1.START_ZERO_ACCEL, zero_values=[2, 3] * 8)
    s.sample(15, accel=-32768)  # -32771 saturates at -32768
    s.sample(16)
    s.start(0)
    s.sample(17)
    # STOP during the averaging: STOPPED at once with ticks 0, no tick 0 later
    s.rx(v1.Start(v1.START_ZERO_ACCEL | v1.START_RESET_ENCODER, 0))
    for _ in range(5):
        s.tick(accel=-4)
    s.rx(v1.Stop())
    for _ in range(20):
        s.tick()
    # n_ticks reached: STOPPED right after SAMPLE n_ticks-1, in the same tick; then silence
    s.start(v1.START_RESET_ENCODER | v1.START_ZERO_ACCEL, n_ticks=5)
    for v in (1, 2, None, 4, 5):
        s.sample(v)
    s.tick()
    s.rx(v1.Command(4, 6))
    s.tick()
    # n_ticks = 1 with a watchdog trip counted in the run before; START and garbage in one chunk
    s.start(0)
    s.sample(60)
    for _ in range(WATCHDOG):
        s.sample()
    s.rx(v1.Command((s.seq - 1) & 0xFFFF, 61))
    s.sample()
    s.rx(GARBAGE[4], v1.Start(0, 1), GARBAGE[5])
    s.seq = 0
    s.tick()
    s.tick()
    s.rx(v1.Stop())
    return s.steps


def test_the_stimulus_gives_the_same_bytes_in_c_and_python(harness):
    steps = the_script()
    out = assert_same(harness, steps)
    # the script exercised what it claims: every status bit, both STOPPED reasons, INFO
    msgs = [m for data in out for m in v1.Decoder().feed(data)]
    status = 0
    for m in msgs:
        status |= m.status if isinstance(m, v1.Sample) else 0
    assert status == v1.LATE | v1.WATCHDOG | v1.SATURATED | v1.RX_ERROR | v1.STALE
    stopped = [m for m in msgs if isinstance(m, v1.Stopped)]
    assert {m.reason for m in stopped} == {v1.STOPPED_BY_STOP, v1.STOPPED_N_TICKS}
    assert any(m.watchdog_trips for m in stopped) and any(m.rx_errors for m in stopped)
    assert sum(isinstance(m, v1.Info) for m in msgs) == 3


def test_the_implementations_identify_themselves_in_info(harness):
    (c,), (py,) = run_c(harness, [rx(v1.Hello())]), run_python([rx(v1.Hello())])
    (ic,), (ip,) = v1.Decoder().feed(c), v1.Decoder().feed(py)
    assert ic.name == "SFLR" and ip.name == "SIMRIG"
    assert (ic.fw_major, ic.fw_minor, ic.fw_patch) != (ip.fw_major, ip.fw_minor, ip.fw_patch)


def test_random_stimuli_give_the_same_bytes(harness):
    """Seeded random scripts: messages near the expected seq, garbage, splits, STARTs, ticks."""
    rng = random.Random(20260311)
    for _ in range(4):
        shadow_plant = ScriptedPlant()  # a third device tells the script the seq to answer
        shadow = SimDevice("v1", plant=shadow_plant, sensors=RawSensors(), accel_offset=0.0)
        steps: list[tuple] = []

        def add(step):
            steps.append(step)
            play(shadow, shadow_plant, step)

        for _ in range(1500):
            r = rng.random()
            expected = (shadow.tick_index - 1) & 0xFFFF
            if r < 0.45:
                add(("sensors", rng.randint(-2**30, 2**30), rng.randint(-40, 40)))
                add(("tick",))
            elif r < 0.75:
                v = rng.randint(-32768, 32767) if rng.random() < 0.1 else rng.randint(-300, 300)
                add(rx(v1.Command((expected + rng.choice([0, 0, 0, 0, 1, -1, 7])) & 0xFFFF, v)))
            elif r < 0.82:
                add(rx(rng.choice(GARBAGE + [bad_crc(v1.Command(0, 1)), b"\x00"])))
            elif r < 0.86:
                add(rx(v1.Start(rng.randrange(4), rng.choice([0, 0, 1, 3, 40]))))
            elif r < 0.88:
                add(rx(v1.Stop()))
            elif r < 0.90:
                add(rx(v1.Hello()))
            else:  # a COMMAND split at a random point, noise in front
                data = bytes(rng.randrange(1, 256) for _ in range(rng.randrange(3))) + v1.encode(
                    v1.Command(expected, rng.randint(-255, 255)))
                cut = rng.randrange(1, len(data))
                add(("rx", data[:cut]))
                add(("rx", data[cut:]))
        assert_same(harness, steps)


def play(dev: SimDevice, plant: ScriptedPlant, step) -> bytes:
    """One step on a Python device: the bytes it sent."""
    if step[0] == "rx":
        dev.receive(step[1])
        return dev.take_output()
    if step[0] == "sensors":
        plant.theta, plant.a = step[1], step[2]
        return b""
    return dev.tick() + dev.take_output()
