"""The real-time loop against a scripted device: alignment, row layout, fail-safe order."""

import math

import numpy as np
import pytest

from station.control import make_controller
from station.link import DeviceStopped, LinkTimeout, SequenceError
from station.loop import run_loop


class ScriptedSession:
    """Plays back samples; records every command and stop, in order, in ``events``."""

    alignment = 1
    protocol = "scripted"
    max_lag_seen = 0
    stop_requested = None

    def __init__(self, samples, events, fault_at=None, fault=None):
        self.samples = list(samples)
        self.events = events
        self.fault_at, self.fault = fault_at, fault
        self.k = 0

    def counters(self):
        return {"late": 0, "late_seen": 0, "skipped": 0, "dropped": 0, "stale": 0, "duplicates": 0, "rx_errors": 0,
                "watchdog_trips": 0}

    def start(self, n_ticks):
        self.events.append(("start", n_ticks))

    def read_sample(self):
        if self.fault_at is not None and self.k == self.fault_at:
            raise self.fault
        if self.k >= len(self.samples):
            raise DeviceStopped("done", {"reason": 1, "ticks": self.k, "late": 0, "watchdog_trips": 0, "rx_errors": 0})
        s = self.samples[self.k]
        self.k += 1
        return s

    def poll_sample(self):
        return None  # one sample at a time: nothing is ever waiting

    def send_command(self, n, v):
        self.events.append(("command", n, v))

    def stop(self):
        self.events.append(("stop",))
        return None

    def unread_samples(self):
        return []


class ListWriter:
    def __init__(self, events):
        self.rows, self.events = [], events

    def append(self, row):
        self.rows.append(row)

    def close(self):
        self.events.append(("log closed", len(self.rows)))


def _samples(thetas, accels=None):
    accels = accels or [0] * len(thetas)
    return [(k, th, a, 0, 0) for k, (th, a) in enumerate(zip(thetas, accels))]


def test_command_on_sample_k_uses_theta_k_and_reference_k_plus_1():
    events = []
    theta = [0, 0, 3, 7, 12, 20]
    u = np.array([0, 0, 50, 50, 50, 50], float)
    session, writer = ScriptedSession(_samples(theta), events), ListWriter(events)
    result = run_loop(session, make_controller("p", kp=2.0), u, writer, lean=False)
    assert result.ok and result.ticks == 6
    commands = [e for e in events if e[0] == "command"]
    # the last sample (n = 5) is not answered: the run ends with it
    assert [(n, v) for _, n, v in commands] == [(k, 2.0 * (u[k + 1] - theta[k])) for k in range(5)]
    rows = np.array(writer.rows, float)
    # row k: t, n, u[k], v[k] (computed on sample k-1), theta[k]
    assert np.allclose(rows[:, 1], range(6)) and np.allclose(rows[:, 0], np.arange(6) * 0.002)
    assert np.allclose(rows[:, 2], u)
    assert rows[0, 3] == 0.0  # tick 0 outputs 0
    assert np.allclose(rows[1:, 3], [2.0 * (u[k] - theta[k - 1]) for k in range(1, 6)])
    assert math.isnan(rows[0, 9]) and np.all(rows[1:, 9] > 0)  # latency of v[k] sits in row k


@pytest.mark.parametrize("fault, reason", [
    (LinkTimeout("device went silent"), "timeout"),
    (SequenceError("tick number jumped"), "sequence"),
    (KeyboardInterrupt(), "sigint"),
    (OSError("port vanished"), "link"),
])
def test_faults_send_zero_and_stop_before_the_log_is_flushed(fault, reason):
    events = []
    session = ScriptedSession(_samples([0] * 20), events, fault_at=7, fault=fault)
    writer = ListWriter(events)
    result = run_loop(session, make_controller("lead"), np.full(20, 100.0), writer, lean=False)
    writer.close()
    assert result.reason == reason and not result.ok
    assert events[-2:] == [("stop",), ("log closed", 7)]
    assert len(writer.rows) == 7  # every sample before the fault is logged


def test_controller_exception_stops_safely():
    class Exploding:
        def __init__(self):
            self.calls = 0

        def step(self, u, theta, a):
            self.calls += 1
            if self.calls == 4:
                raise ZeroDivisionError("boom")
            return 1.0, u

    events = []
    session = ScriptedSession(_samples([0] * 10), events)
    result = run_loop(session, Exploding(), np.zeros(10), ListWriter(events), lean=False)
    assert result.reason == "controller-fault" and "ZeroDivisionError" in result.message and "tick 3" in result.message
    assert events[-1] == ("stop",)
    assert [e for e in events if e[0] == "command"][-1] == ("command", 2, 1.0)  # nothing sent after the fault


def test_soft_limit_stops_and_logs_the_offending_sample():
    events = []
    theta = [0, 100, 900, 2100, 2200]
    session, writer = ScriptedSession(_samples(theta), events), ListWriter(events)
    result = run_loop(session, make_controller("p"), np.full(5, 50.0), writer, soft_limit=2048, lean=False)
    assert result.reason == "soft-limit" and "2100" in result.message
    assert events[-1] == ("stop",)
    assert [r[4] for r in writer.rows] == [0, 100, 900, 2100]
    assert not any(e[0] == "command" and e[1] == 3 for e in events)


def test_saturation_applies_to_logged_and_sent_commands():
    events = []
    session, writer = ScriptedSession(_samples([0] * 5), events), ListWriter(events)
    run_loop(session, make_controller("p", kp=10.0, limit=200.0), np.full(5, 100.0), writer, lean=False)
    assert all(abs(e[2]) <= 200.0 for e in events if e[0] == "command")
    assert max(r[3] for r in writer.rows) == 200.0


class _FailingWriteSession(ScriptedSession):
    """send_command fails (a write timeout) at sample ``fail_at``."""

    def __init__(self, samples, events, fail_at):
        super().__init__(samples, events)
        self.fail_at = fail_at

    def send_command(self, n, v):
        if n == self.fail_at:
            raise OSError("write timeout")
        super().send_command(n, v)


def test_sample_of_a_controller_fault_or_failed_write_is_logged_after_the_stop():
    """The sample that was in when the controller raised (or the write failed) is a full
    row (v[n] was sent on sample n-1): it must be in the log, after command 0 and stop."""
    class Exploding:
        def step(self, u, theta, a):
            if theta == 3:
                raise ZeroDivisionError("boom")
            return 1.0, u

    for session_of in (lambda ev: ScriptedSession(_samples([0, 1, 2, 3, 4, 5]), ev),
                       lambda ev: _FailingWriteSession(_samples([0, 1, 2, 4, 4, 5]), ev, fail_at=3)):
        events = []
        writer = ListWriter(events)
        result = run_loop(session_of(events), Exploding(), np.zeros(6), writer, lean=False)
        writer.close()
        assert result.reason in ("controller-fault", "link")
        assert [r[1] for r in writer.rows] == [0, 1, 2, 3]
        assert writer.rows[3][3] == 1.0  # v[3], sent on sample 2, acted during tick 3
        assert events[-2:] == [("stop",), ("log closed", 4)]


def test_interrupt_while_stopping_does_not_skip_the_stop():
    """A second Ctrl-C that lands inside stop() gets the stop retried; run_loop never raises."""
    class InterruptedOnce(ScriptedSession):
        def stop(self):
            self.events.append(("stop",))
            if self.events.count(("stop",)) == 1:
                raise KeyboardInterrupt
            return None

    events = []
    result = run_loop(InterruptedOnce(_samples([0] * 10), events, fault_at=5, fault=KeyboardInterrupt()),
                      make_controller("p"), np.zeros(10), ListWriter(events), lean=False)
    assert result.reason == "sigint"
    assert events[-2:] == [("stop",), ("stop",)]
