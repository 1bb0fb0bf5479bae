"""Opening ports: missing, busy and bad URLs give one-line errors naming the port."""

import os
import pty
import subprocess
import sys

import pytest

from station.errors import StationError
from station.link import LinkLimits, open_session, sim_url
from tests.scripted_device import MemoryPort


def test_missing_port_names_it():
    with pytest.raises(StationError, match=r"cannot open port /dev/does-not-exist-42"):
        open_session("/dev/does-not-exist-42")


def test_busy_port_is_reported_busy():
    master, slave = pty.openpty()
    path = os.ttyname(slave)
    first = open_session(path, timeout=0.05)
    try:
        with pytest.raises(StationError, match=rf"cannot open port {path}: port is busy"):
            open_session(path, timeout=0.05)
    finally:
        first.close()
        os.close(master)
        os.close(slave)


def test_unknown_protocol_is_rejected():
    with pytest.raises(StationError, match="unknown protocol 'v2'"):
        open_session("loop://", protocol="v2")


def test_device_that_does_not_answer_hello():
    with open_session("loop://", timeout=0.02) as session:  # loop:// echoes HELLO back: no INFO
        with pytest.raises(StationError, match="no INFO from loop://"):
            session.hello()


def test_sim_url_gets_the_protocol_only_when_missing():
    assert sim_url("sim://", "legacy") == "sim://?protocol=legacy"
    assert sim_url("sim://?protocol=v1&seed=3", "legacy") == "sim://?protocol=v1&seed=3"
    assert sim_url("/dev/ttyACM0", "legacy") == "/dev/ttyACM0"


def test_cli_error_is_one_line_without_traceback():
    proc = subprocess.run([sys.executable, "-m", "station", "step", "--port", "/dev/does-not-exist-42"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0, proc.stderr
    assert proc.stderr.startswith("station: error: --port /dev/does-not-exist-42: no such device")
    assert "`station ports`" in proc.stderr


def test_unknown_sim_option_is_not_reported_as_busy():
    with pytest.raises(StationError) as info:
        open_session("sim://?bogus=1")
    assert "unknown option 'bogus'" in str(info.value) and "busy" not in str(info.value)


def test_v1_stop_sends_stop_even_when_the_command_write_fails():
    """STOP alone sets the device's output to 0: a failed COMMAND write must not skip it."""
    import serial

    from station.link import V1Session
    from station.protocol import v1

    class Port:
        def __init__(self):
            self.frames = []

        def write(self, data):
            msg = v1.Decoder().feed(data)[0]
            if isinstance(msg, v1.Command):
                raise serial.SerialTimeoutException("Write timeout")
            self.frames.append(msg)
            return len(data)

        def read(self, size=1):
            return b""

        in_waiting = 0

    port = Port()
    session = V1Session(port, "fake://", LinkLimits(timeout=0.01))
    session._last_seq = 41
    with pytest.raises(StationError, match="write to fake:// failed"):
        session.stop()
    assert port.frames == [v1.Stop()]


def test_v1_lost_first_samples_count_as_dropped():
    """After START the device counts from seq 0: a run whose first SAMPLE is seq 2 lost two."""
    from station.link import V1Session
    from station.protocol import v1

    frames = b"".join(v1.encode(v1.Sample(seq, 0, 0, 0, 0)) for seq in (2, 3, 5))
    # the port answers START with the device's samples, like a device would
    port = MemoryPort(on_write=lambda data: frames if any(isinstance(m, v1.Start) for m in v1.Decoder().feed(data))
                      else b"")
    session = V1Session(port, "fake://", LinkLimits(timeout=0.01))
    session.start(10)
    assert [session.read_sample()[0] for _ in range(3)] == [2, 3, 5]
    assert session.dropped == 3  # 0, 1 and 4


def test_legacy_start_zeroes_a_command_left_over_from_a_dead_station():
    """The old firmware applies the last v received from tick 0 on: a previous station that
    died after '/' 150 would drive the motor during tick 0 of the next run (logged as 0)."""
    from station.protocol import legacy

    session = open_session("sim://?noise=0", protocol="legacy")
    try:
        session.port.write(legacy.command_bytes(150))  # the dead station's last command
        session.hello()
        session.start(10)
        assert session.read_sample()[0] == 0
        plant = session.port.device.plant
        state = getattr(plant, "z", getattr(plant, "x", None))  # ModelPlant (modal) or DiscretePlant
        assert state is not None and not state.any()  # tick 0 applied 0: the plant is still at rest
    finally:
        session.close()


class _FrozenHostPort(MemoryPort):
    """A port whose reads block like a real one (``POLL_S``) and whose ``freeze``-th read
    overruns by ``freeze_s``: the host was frozen (a stalled VM), the device too; after it
    the device's next sample is there only if ``then`` holds bytes."""

    def __init__(self, freeze_s, then=b""):
        super().__init__()
        self.freeze_s, self.then, self.reads = freeze_s, then, 0

    def read(self, size=1):
        if not self.data:
            import time

            self.reads += 1
            time.sleep(self.freeze_s if self.reads == 2 else 0.01)
            if self.reads == 3:
                self.data += self.then
        return super().read(size)


def test_a_frozen_host_is_not_a_silent_device():
    """The sample deadline counts listening time: a 0.3 s freeze of the host (the device was
    frozen too and sends its next sample after it) does not stop a run with --timeout 0.1."""
    from station.link import V1Session
    from station.protocol import v1

    port = _FrozenHostPort(0.3, then=v1.encode(v1.Sample(1, 0, 0, 0, 0)))
    session = V1Session(port, "fake://", LinkLimits(timeout=0.1, check_rate=False))
    session.start(0)
    port.data += v1.encode(v1.Sample(0, 0, 0, 0, 0))
    assert session.read_sample()[0] == 0
    assert session.read_sample()[0] == 1
    assert session.held_up_s > 0.25


def test_a_silent_device_still_times_out_after_a_frozen_host():
    """Credit is the freeze only: a device that stays silent is stopped one timeout later."""
    import time

    from station.link import LinkTimeout, V1Session
    from station.protocol import v1

    port = _FrozenHostPort(0.3)
    session = V1Session(port, "fake://", LinkLimits(timeout=0.1, check_rate=False))
    session.start(0)
    port.data += v1.encode(v1.Sample(0, 0, 0, 0, 0))
    assert session.read_sample()[0] == 0
    t0 = time.perf_counter()
    with pytest.raises(LinkTimeout):
        session.read_sample()
    assert time.perf_counter() - t0 >= 0.3 + 0.1 - 0.02  # the freeze, then a full timeout
