"""Catch up, don't give up: the session's skip, lag and burst logic on a port whose timing the
test decides (no pty, no clock of the machine), and the replay of a run with skipped samples.

Truth: the protocol spec (a sample per tick, the device holds its output when no command
came) and counting by hand; never the session's own arithmetic.
"""

from __future__ import annotations

import io
import logging
import time

import numpy as np
import pytest

from station.control import make_controller
from station.control.rerun import replay_commands
from station.link import (Burst, BurstMeter, LagError, LegacySession, LinkLimits, SequenceError, V1Session, burst_line,
                          latency_timer, port_info)
from station.link.port import _ask_low_latency
from station.progress import ProgressSink
from station.protocol import legacy, v1
from station.runlog import SKIPPED
from tests.scripted_device import MemoryPort
from tests.stalls import timed_marks

pytestmark = timed_marks()
"""A try during which the test machine froze (or a scripted device missed its own clock) is no
trial of the station's timing: it runs again, at most ten times. A failure on a machine that
kept time stands (tests/stalls.py)."""


def _v1(limits=None, lockstep=False):
    port = MemoryPort()
    session = V1Session(port, "fake://", limits or LinkLimits(timeout=0.05, check_rate=False))
    session.start(0)
    session.lockstep = lockstep
    return port, session


def _samples(port, ticks, status=lambda k: 0):
    for k in ticks:
        port.data += v1.encode(v1.Sample(k, k, 0, 0, status(k)))


def _commands(port):
    msgs = v1.Decoder().feed(b"".join(port.written))
    return [m.seq for m in msgs if isinstance(m, v1.Command)]


def _answer_newest(session):
    """The loop's catch-up: hand over each sample, answer only the newest; returns the
    tick numbers handed over and the one answered."""
    seen = [session.read_sample().n]
    while (newer := session.poll_sample()) is not None:
        seen.append(newer.n)
    session.send_command(seen[-1], 0.0)
    return seen


def test_ten_samples_at_once_are_all_handed_over_and_only_the_newest_answered():
    port, session = _v1()
    _samples(port, [0])
    assert _answer_newest(session) == [0]
    _samples(port, range(1, 11))  # the station was held up for 20 ms
    assert _answer_newest(session) == list(range(1, 11))
    assert _commands(port) == [0, 10]
    assert session.skipped == 9 and session.held == 9  # ticks 2..10 ran on the command for 0
    assert session.late_seen == 0


class _CountingPort(MemoryPort):
    """Counts the looks at the port (``in_waiting``)."""

    looks = 0

    @property
    def in_waiting(self):
        self.looks += 1
        return super().in_waiting


def test_a_read_that_emptied_the_port_is_the_look_but_catching_up_looks_again():
    port = _CountingPort()
    session = V1Session(port, "fake://", LinkLimits(timeout=0.05, check_rate=False))
    session.start(0)
    _samples(port, [0])
    assert session.read_sample().n == 0
    looks = port.looks
    _samples(port, [1])  # came after the read had taken everything: this tick answers sample 0
    assert session.poll_sample() is None and port.looks == looks  # no second system call
    session.send_command(0, 0.0)
    assert session.late_seen == 1  # the command's own look saw sample 1 waiting: late, counted
    # catching up: two samples in one read, a third arrives while the second is handed over
    assert session.read_sample().n == 1
    session.send_command(1, 0.0)
    _samples(port, [2, 3])
    assert session.read_sample().n == 2
    assert session.poll_sample().n == 3
    _samples(port, [4])
    assert session.poll_sample().n == 4  # the port was looked at again
    assert session.poll_sample() is None


def test_late_bits_of_skipped_ticks_are_not_counted_twice():
    # a v1 device reports the ticks it held as LATE: the same ticks the station skipped
    port, session = _v1()
    _samples(port, [0])
    _answer_newest(session)
    _samples(port, range(1, 11), status=lambda k: v1.LATE if k >= 2 else 0)
    _answer_newest(session)
    assert session.late == 9 and session.skipped == 9 and session.held == 9


@pytest.mark.parametrize("waiting, stops", [(11, False), (12, True), (30, True)])
def test_behind_more_than_max_lag_stops_before_any_is_answered(waiting, stops):
    # the lag: 2 ms of the device's time per sample skipped since the last answer (or come
    # while computing); --max-lag 20 ms lets 10 be skipped, not 11 (or more: seen at once)
    port, session = _v1()
    _samples(port, [0])
    _answer_newest(session)
    _samples(port, range(1, 1 + waiting))
    if stops:
        with pytest.raises(LagError, match="more than --max-lag 20 ms"):
            _answer_newest(session)
        assert _commands(port) == [0]
    else:
        _answer_newest(session)
        assert _commands(port) == [0, waiting]


def test_held_ticks_beyond_one_catch_up_and_max_miss_stop_on_lag():
    # every step finds 4 samples waiting: 3 skipped per 4 ticks; the budget is one catch-up
    # (10 ticks) plus --max-miss 10 in 100 ticks, so the 21st held tick stops the run
    port, session = _v1()
    _samples(port, [0])
    _answer_newest(session)
    k = 0
    with pytest.raises(LagError, match="held command.*--max-miss 10") as err:
        while True:
            _samples(port, range(k + 1, k + 5))
            _answer_newest(session)
            k += 4
    assert session.held == 21 and "cannot keep up" in str(err.value)


def test_sequence_faults_and_held_ticks_have_a_budget_each():
    port, session = _v1()
    _samples(port, [0])
    _answer_newest(session)
    port.data += v1.encode(v1.Sample(0, 0, 0, 0, 0)) * 10  # 10 duplicates: within --max-miss 10
    _samples(port, range(1, 11))                           # and a catch-up of 9 held ticks
    _answer_newest(session)
    assert session.duplicates == 10 and session.held == 9
    port.data += v1.encode(v1.Sample(10, 10, 0, 0, 0))      # the 11th duplicate
    _samples(port, [11])
    with pytest.raises(SequenceError, match="dropped, stale or duplicated"):
        _answer_newest(session)


def test_a_command_computed_too_long_after_its_sample_is_not_written():
    port, session = _v1()
    _samples(port, [0])
    n = session.read_sample().n
    _samples(port, range(1, 12))  # a controller that took 22 ms: 11 samples came meanwhile
    with pytest.raises(LagError, match="would go out 22 ms of the device's time behind"):
        session.send_command(n, 5.0)
    assert _commands(port) == []


def test_a_stall_of_the_station_with_a_device_that_waits_is_no_lag():
    # legacy cannot declare lockstep: a simulated rig that waits for each command sends
    # nothing while the station is held up, so the station is not behind, however long
    port = MemoryPort()
    session = LegacySession(port, "fake://", LinkLimits(timeout=0.05, check_rate=False))
    session._reset_run()
    port.data += legacy.tick_bytes(legacy.Tick(0, 0, 0))
    n = session.read_sample().n
    time.sleep(0.05)
    session.send_command(n, 5.0)
    assert session.max_lag_seen == 0.0 and session.held == 0


def test_a_lockstep_device_holds_nothing():
    port, session = _v1(lockstep=True)
    _samples(port, range(0, 30))
    assert _answer_newest(session) == list(range(30))
    assert session.skipped == 29 and session.held == 0


def test_legacy_catch_up_counts_held_ticks_as_late():
    port = MemoryPort()
    session = LegacySession(port, "fake://", LinkLimits(timeout=0.05, check_rate=False))
    session._reset_run()
    port.data += b"".join(legacy.tick_bytes(legacy.Tick(k, k, 0)) for k in range(6))
    assert _answer_newest(session) == list(range(6))
    assert session.counters()["late"] == session.held == session.skipped == 5


def test_samples_left_at_a_stop_come_back_in_order_once():
    port, session = _v1()
    _samples(port, range(0, 14))
    session.read_sample()
    with pytest.raises(LagError):
        while session.poll_sample() is not None:
            pass
    rest = session.unread_samples()
    got = [s.n for s in rest]
    assert got == list(range(got[0], 14)) and session.unread_samples() == []


# --- bursts --------------------------------------------------------------------------------

def _meter(chunks, start=100.0):
    meter = BurstMeter()
    for t, size in chunks:
        meter.record(size, start + t)
    return meter


def test_regular_bursts_are_measured():
    meter = _meter([(0.016 * i, 8) for i in range(1, 4)])
    burst = meter.burst(now=100.0 + 0.05)
    assert burst == Burst(8, pytest.approx(0.016), 3)


@pytest.mark.parametrize("chunks", [
    [(0.002 * i, 1) for i in range(20)],                   # one sample per wait: a healthy link
    [(0.002 * i, 1) for i in range(10)] + [(0.04, 10)],     # one stall, then caught up
    [(0.0, 8), (0.016, 3)],                                 # sizes that do not repeat
    [(0.0, 2), (0.002, 2), (0.004, 2)],                     # "bursts" at the tick itself
])
def test_what_is_not_a_burst_pattern(chunks):
    assert _meter(chunks).burst(now=100.0 + chunks[-1][0]) is None


def test_old_bursts_are_forgotten():
    meter = _meter([(0.0, 8), (0.016, 8)])
    assert meter.burst(now=100.02) is not None and meter.burst(now=101.0) is None


def test_the_burst_line_names_the_timer_and_its_fix():
    burst = Burst(8, 0.016, 3)
    line = burst_line(burst, "/dev/ttyUSB0", (16, "/sys/bus/usb-serial/devices/ttyUSB0/latency_timer"))
    assert "bursts of 8 every 16 ms" in line and "latency timer is 16 ms" in line
    assert "echo 1 | sudo tee /sys/bus/usb-serial/devices/ttyUSB0/latency_timer" in line and "\n" not in line
    line = burst_line(burst, "/dev/pts/3", None)
    assert "latency timer" in line and "sudo tee" in line and "\n" not in line


def test_the_latency_timer_is_read_from_sysfs(tmp_path):
    folder = tmp_path / "bus" / "usb-serial" / "devices" / "ttyUSB0"
    folder.mkdir(parents=True)
    (folder / "latency_timer").write_text("16\n")
    assert latency_timer("/dev/ttyUSB0", sysfs=tmp_path) == (16, str(folder / "latency_timer"))
    assert latency_timer("/dev/ttyACM0", sysfs=tmp_path) is None
    assert latency_timer("sim://", sysfs=tmp_path) is None


def test_port_info_of_what_has_no_adapter(device_factory):
    dev = device_factory()
    assert port_info(dev.path).adapter == "pseudo-terminal" and port_info(dev.path).latency is None
    assert port_info("sim://?protocol=v1").summary() == "sim://?protocol=v1 (simulated rig)"


def test_low_latency_mode_refused_is_a_warning_not_an_error(caplog):
    class Refusing:
        def set_low_latency_mode(self, on):
            raise OSError(25, "Inappropriate ioctl for device")

    class Taking:
        def set_low_latency_mode(self, on):
            self.on = on

    with caplog.at_level(logging.WARNING, logger="station.link"):
        assert _ask_low_latency(Refusing(), "/dev/ttyUSB7") is False
    assert "refused low-latency mode" in caplog.text
    taking = Taking()
    assert _ask_low_latency(taking, "/dev/ttyUSB7") is True and taking.on is True
    assert _ask_low_latency(Taking(), "socket://localhost:1") is None


# --- what the log and replay make of skipped samples ----------------------------------------

def test_replay_does_not_step_the_controller_on_skipped_samples():
    # independent truth: the loop's rule written out by hand
    controller = make_controller("lead-accel")
    rng = np.random.default_rng(3)
    n = 200
    u = np.full(n, 100.0)
    theta = rng.integers(0, 120, n).astype(float)
    a = rng.normal(0, 2, n)
    skipped = np.zeros(n, bool)
    skipped[[0, 5, 6, 7, 50, 51, 199]] = True
    v, hat = replay_commands(controller, u, theta, a, 1, skipped)
    controller.reset()
    v_ref, hat_ref = np.zeros(n), u.copy()
    for k in range(1, n):
        if skipped[k - 1]:
            v_ref[k], hat_ref[k] = v_ref[k - 1], hat_ref[k - 1]
        else:
            v_ref[k], hat_ref[k] = controller.step(u[k], theta[k - 1], a[k - 1])
    assert np.array_equal(v, v_ref) and np.array_equal(hat, hat_ref)


def test_the_progress_line_counts_skipped_samples():
    stream = io.StringIO()
    bar = ProgressSink(1.0, stream=stream)
    status = np.array([0, SKIPPED, SKIPPED | v1.LATE, 0, v1.LATE])
    bar.write_rows({"n": np.arange(5), "status": status, "t": np.arange(5) * 0.002, "theta": np.zeros(5),
                    "v": np.zeros(5)})
    assert (bar.skipped, bar.late) == (2, 2) and "skipped 2" in stream.getvalue()


def test_station_ports_shows_the_latency_timer(tmp_path, monkeypatch, capsys):
    from serial.tools import list_ports
    from serial.tools.list_ports_common import ListPortInfo

    import station.link.port as port_module
    from station.cli import main

    folder = tmp_path / "bus" / "usb-serial" / "devices" / "ttyUSB7"
    folder.mkdir(parents=True)
    (folder / "latency_timer").write_text("16\n")
    usb, acm = ListPortInfo("/dev/ttyUSB7", skip_link_detection=True), ListPortInfo("/dev/ttyACM0", skip_link_detection=True)
    usb.description, acm.description = "FT232R USB UART", "PSoC 5LP"
    monkeypatch.setattr(list_ports, "comports", lambda *a, **k: [usb, acm])
    monkeypatch.setattr(port_module, "SYSFS", tmp_path)
    assert main(["ports"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("/dev/ttyACM0") and "latency" not in out[0]
    assert out[1].startswith("/dev/ttyUSB7  FT232R USB UART") and "latency timer 16 ms" in out[1]
    assert f"echo 1 | sudo tee {folder / 'latency_timer'}" in out[1]
