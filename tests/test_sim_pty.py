"""The pty server (station/sim/pty_server.py) and ``station sim-device`` in another process."""

import argparse
import json
import signal
import subprocess
import sys

import pytest
import serial

from station.commands import sim_device
from station.errors import StationError
from station.protocol import legacy, v1


def start(*options):
    proc = subprocess.Popen([sys.executable, "-m", "station.sim.pty_server", *options],
                            stdout=subprocess.PIPE, text=True)
    path = proc.stdout.readline().strip()
    assert path.startswith("/dev/"), path
    return proc, path


def stop(proc):
    proc.send_signal(signal.SIGTERM)
    out, _ = proc.communicate(timeout=20)
    assert proc.returncode == 0
    return json.loads(out.strip().splitlines()[-1])


def read_until(port, dec, count, cls=v1.Sample):
    got = []
    while len([m for m in got if isinstance(m, cls)]) < count:
        data = port.read(max(1, port.in_waiting))
        assert data, f"timeout after {got}"
        got += dec.feed(data)
    return got


def test_v1_lockstep_round_trip_and_summary():
    proc, path = start("--seed", "1")
    try:
        with serial.Serial(path, timeout=2) as port:
            dec = v1.Decoder()
            port.write(v1.encode(v1.Hello()))
            (info,) = read_until(port, dec, 1, v1.Info)
            assert info.name == "SIMRIG"
            port.write(v1.encode(v1.Start(3, 0)))
            for k in range(20):
                (s,) = read_until(port, dec, 1)
                assert (s.seq, s.status) == (k, 0)
                port.write(v1.encode(v1.Command(k, 30)))
            (s,) = read_until(port, dec, 1)
            assert s.v_applied == 30
            assert dec.rx_errors == 0
    finally:
        summary = stop(proc)
    assert summary == {"ticks": 21, "late": 0, "watchdog_trips": 0, "rx_errors": 0, "tx_lost": 0, "max_slip_ms": 0.0}


def test_legacy_realtime_ticks_without_the_station():
    proc, path = start("--protocol", "legacy", "--realtime")
    try:
        with serial.Serial(path, timeout=2) as port:
            port.write(legacy.START)
            assert len(port.read(2)) == 2  # theta0
            dec = legacy.TickDecoder()
            ticks = []
            while len(ticks) < 50:
                ticks += dec.feed(port.read(6))
            assert [t.n for t in ticks] == list(range(len(ticks)))
            port.write(legacy.command_bytes(0) + legacy.STOP)
    finally:
        summary = stop(proc)
    assert summary["ticks"] >= 50
    assert summary["late"] >= summary["ticks"] - 2  # one '/' in the whole run


def test_realtime_device_whose_station_stopped_reading_still_exits_on_sigterm():
    import time

    proc, path = start("--realtime", "--protocol", "v1", "--seed", "2")
    try:
        with serial.Serial(path, timeout=1) as port:
            port.write(v1.encode(v1.Start(0, 0)))
            time.sleep(2.0)  # ~1000 samples (16 kB) never read
    finally:
        summary = stop(proc)
    assert summary["ticks"] > 500
    assert summary["watchdog_trips"] == 0 and summary["late"] == summary["ticks"] - 1


def test_command_without_pty_is_a_one_line_station_error():
    parser = argparse.ArgumentParser()
    sim_device.configure(parser)
    with pytest.raises(StationError, match="only --pty"):
        sim_device.run(parser.parse_args([]))


@pytest.mark.parametrize("option", [["--elements", "0"], ["--seed", "-1"]])
def test_sim_device_bad_option_is_refused_in_one_line(option, capsys):
    from station.cli import main

    assert main(["sim-device", "--pty", *option]) == 2  # refused while parsing: no pty opened
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"argument {option[0]}" in err[0]
