"""Fault tests end to end: the station against a scripted rig on a pty.

Each fault must end the run with a clear message, command 0 (and stop) sent before the
log is closed, and every sample before the fault in the log.
"""

import json
import os
import re
import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest

from station.experiment import run_step
from station.link import LinkLimits
from station.runlog import SKIPPED, read_log
from tests.stalls import timed_marks

pytestmark = timed_marks()
"""A try during which the test machine froze (or a scripted device missed its own clock) is no
trial of the station's timing: it runs again, at most ten times. A failure on a machine that
kept time stands (tests/stalls.py)."""


LIMITS = LinkLimits(timeout=0.1, max_lag=0.05)
"""These faults are not about lag: a loaded test machine that holds the station up for tens
of ms must not turn them into "lag" stops (test_failsafe.py and test_catch_up.py test the
lag bounds; --max-lag 50 below is 50 ms too)."""


def test_device_going_silent_stops_with_command_zero(device_factory, tmp_path):
    dev = device_factory(protocol="v1", theta=lambda k: 0, silent_after=100)
    report = run_step(port=dev.path, controller="p", amplitude=50, duration=2.0, out=tmp_path / "log.tsv", limits=LIMITS)
    assert report.result.reason == "timeout"
    assert "went silent" in report.result.message and "tick 100" in report.result.message
    cmds = dev.commands()
    assert cmds[-1] == (100, 0)                       # command 0 for the last sample...
    assert type(dev.received[-1]).__name__ == "Stop"   # ...then STOP
    assert dev.outputs[-1] == 0                       # ...and the device's output is 0 after STOP
    log = read_log(tmp_path / "log.tsv")
    assert np.array_equal(log.data["n"], np.arange(101))


def test_v1_garbage_and_corrupt_frames_are_counted_and_survived(device_factory, tmp_path):
    dev = device_factory(protocol="v1", garbage_every=50)
    report = run_step(port=dev.path, controller="lead", duration=1.0, out=tmp_path / "log.tsv", limits=LIMITS)
    assert report.result.ok, report.result.message
    assert report.result.dropped == 0
    assert report.result.outcome.rx_errors == 2 * (499 // 50)  # garbage + corrupted frame each time
    assert np.array_equal(read_log(tmp_path / "log.tsv").data["n"], np.arange(500))


def test_legacy_tick_number_jump_stops_safely(device_factory, tmp_path):
    dev = device_factory(protocol="legacy", skip_at=120)
    report = run_step(port=dev.path, protocol="legacy", controller="p", amplitude=50, duration=2.0,
                      out=tmp_path / "log.tsv", limits=LIMITS)
    assert report.result.reason == "sequence" and "jumped from 119 to 121" in report.result.message
    assert dev.wait_for(lambda d: d.received and d.received[-1] == ("s",))  # no reply in legacy: wait for it
    assert dev.commands()[-1] == (None, 0)
    assert dev.received[-1] == ("s",)
    assert len(read_log(tmp_path / "log.tsv").data["n"]) == 120


def test_soft_limit_stops_safely(device_factory, tmp_path):
    dev = device_factory(protocol="v1", theta=lambda k: 5 * k)
    report = run_step(port=dev.path, controller="p", duration=2.0, soft_limit=300, out=tmp_path / "log.tsv", limits=LIMITS)
    assert report.result.reason == "soft-limit" and "305" in report.result.message
    assert dev.commands()[-1][1] == 0 and type(dev.received[-1]).__name__ == "Stop"


class _FailingController:
    """Commands +30 until its 50th call, then raises (a bug in a user's controller)."""

    spec = {"kind": "test", "name": "fails at call 50"}

    def __init__(self):
        self.calls = 0

    def reset(self):
        self.calls = 0

    def step(self, u, theta, a):
        self.calls += 1
        if self.calls == 50:
            raise FloatingPointError("overflow in my filter")
        return 30.0, u


def test_controller_exception_stops_safely(device_factory, tmp_path):
    dev = device_factory(protocol="v1", theta=lambda k: 1)
    report = run_step(port=dev.path, controller=_FailingController(), duration=1.0, out=tmp_path / "log.tsv", limits=LIMITS)
    assert report.result.reason == "controller-fault"
    found = re.search(r"FloatingPointError: overflow in my filter at tick (\d+)", report.result.message)
    assert found, report.result.message
    fault = int(found.group(1))  # 49, or later when a busy machine made the station skip samples
    data = read_log(tmp_path / "log.tsv").data
    answered = (data["status"].astype(int) & SKIPPED) == 0
    assert np.array_equal(data["n"], np.arange(fault + 1))  # the faulting sample was received: its row is logged too
    assert np.count_nonzero(answered[:fault]) == 49  # stepped once per answered sample: the 50th call raised
    (last, v_last), zero = dev.commands()[-2:]
    assert last < fault and v_last == 30 and zero == (fault, 0)  # nothing from the broken step, then 0
    assert type(dev.received[-1]).__name__ == "Stop" and dev.outputs[-1] == 0
    assert data["v"][fault] == 30.0 and data["theta"][fault] == 1


def test_sigkill_leaves_every_row_older_than_100ms(device_factory, tmp_path):
    dev = device_factory(protocol="v1", theta=lambda k: k % 7)
    log = tmp_path / "killed.tsv"
    proc = subprocess.Popen([sys.executable, "-m", "station", "step", "--port", dev.path, "--duration", "20",
                             "--max-lag", "50", "--out", str(log)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.time() + 30
    while len(dev.sent) < 500 and time.time() < deadline:  # one second of samples
        time.sleep(0.05)
    kill_time = time.time()
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=10)
    assert len(dev.sent) >= 500, proc.stderr.read().decode()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        data = read_log(log).data
    # a row cut by the kill is skipped with one RuntimeWarning; a whole last row, no warning
    assert [(w.category, "torn last line" in str(w.message)) for w in caught] == (
        [(RuntimeWarning, True)] if _torn(log) else [])
    # the same log cut in the middle of its last whole row: always torn, always the warning
    whole = log.read_bytes()[: log.read_bytes().rfind(b"\n") + 1]
    last = whole[:-1].rfind(b"\n") + 1
    cut = tmp_path / "cut.tsv"
    cut.write_bytes(whole[: last + (len(whole) - last) // 2])
    with pytest.warns(RuntimeWarning, match="torn last line"):
        rows = read_log(cut).data["n"]
    n_whole = len(data["n"])  # the whole rows (a torn tail is not in data either)
    assert len(rows) == n_whole - 1 and np.array_equal(rows, data["n"][: n_whole - 1])
    must_have = [k for k, sent_at in dev.sent if sent_at < kill_time - 0.1]
    assert len(must_have) > 400
    assert data["n"][: len(must_have)].tolist() == must_have


def _torn(path) -> bool:
    return not path.read_bytes().endswith(b"\n")


def test_cli_reports_a_fault_with_exit_code_1_and_json(device_factory, tmp_path):
    dev = device_factory(protocol="v1", silent_after=30)
    out = tmp_path / "r.json"
    proc = subprocess.run([sys.executable, "-m", "station", "step", "--port", dev.path, "--max-lag", "50",
                           "--out", str(tmp_path / "l.tsv"), "--json", str(out)], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1
    assert "STOPPED SAFELY (timeout)" in proc.stdout and "command 0 sent" in proc.stdout
    result = json.loads(out.read_text())
    assert result["reason"] == "timeout" and result["timing"]["dropped"] == 0
    assert os.path.exists(result["log"])


def test_legacy_zeroes_the_accelerometer_with_a_pre_run(device_factory, tmp_path):
    # the old firmware cannot average before tick 0: the station runs 16 ticks at v = 0 first
    dev = device_factory(protocol="legacy", accel=lambda k: -3 + (k % 2))  # mean -2.5 -> offset -3
    report = run_step(port=dev.path, protocol="legacy", controller="lead-accel", duration=0.2,
                      out=tmp_path / "log.tsv", limits=LIMITS)
    assert report.result.ok, report.result.message
    log = read_log(tmp_path / "log.tsv")
    assert log.meta["accel_zero"] == {"by": "station pre-run", "ticks": 16, "offset": -3}
    assert set(log.data["a"]) == {0.0, 1.0}  # raw -3/-2 minus the offset
    dev.wait_for(lambda d: d.received and d.received[-1] == ("s",))
    seq = dev.received
    pre = [("r",), ("/", 0), ("7",), ("q",)] + [("/", 0)] * 16 + [("/", 0), ("s",)]  # after hello's r
    assert seq[:len(pre)] == pre                       # v = 0 throughout the pre-run, then stop
    assert seq[len(pre):len(pre) + 3] == [("/", 0), ("7",), ("q",)]   # the real run starts at v = 0


def test_a_stale_sample_from_an_earlier_run_is_ignored(device_factory, tmp_path):
    # e.g. in flight over USB after a replug: the run counts from seq 0, not from 5000
    from station.protocol import v1

    stale = v1.encode(v1.Sample(5000, 77, 0, 0, 0))
    dev = device_factory(protocol="v1", theta=lambda k: 0, after_start=stale)
    report = run_step(port=dev.path, controller="p", duration=0.5, out=tmp_path / "log.tsv", limits=LIMITS)
    assert report.result.ok and report.result.dropped == 0, report.result.message
    d = read_log(tmp_path / "log.tsv").data
    assert np.array_equal(d["n"], np.arange(250)) and not np.any(d["theta"] == 77)
    assert dev.commands()[0][0] == 0
