"""The simulated legacy device as the lab's own client sees it (issue 26, item 6).

The client is written from the lab's byte format (its serial utilities), not from
``station.protocol``: 'r' reads θ (one big-endian int16), '7' zeroes the encoder, 'q' starts
a test and answers θ0, then each tick brings n, θ, a (three int16) and the client answers
'/' + v (int16, truncated); to stop, v = 0 then 's'. Three P-control runs in a row on one
``station sim-device --pty --protocol legacy``, each after a '7' as the lab's scripts did:
θ0 = 0 every time (START puts the plant at rest, and the encoder's zero with it).
"""

from __future__ import annotations

import json
import math
import signal
import struct
import subprocess
import sys
import time

import serial

KP = 2.0
STEP = 50
TICKS = 400


def _word(port: serial.Serial) -> int:
    data = port.read(2)
    assert len(data) == 2, "the device did not answer"
    return struct.unpack(">h", data)[0]


def _p_run(port: serial.Serial) -> tuple[int, list[int]]:
    """'7', 'q', then P control of a step of 50 counts from tick 10; returns θ0 and θ per tick."""
    port.write(b"7")
    port.write(b"r")
    assert _word(port) == 0  # zeroed where the hub is
    port.write(b"q")
    theta0 = _word(port)
    thetas = []
    for k in range(TICKS):
        n, theta, _a = struct.unpack(">hhh", port.read(6))
        assert n == k
        thetas.append(theta)
        u = STEP if k + 1 >= 10 else 0
        v = math.trunc(KP * (u - theta))
        port.write(b"/" + struct.pack(">h", max(-200, min(200, v))))
    port.write(b"/" + struct.pack(">h", 0) + b"s")
    time.sleep(0.2)
    port.reset_input_buffer()
    return theta0, thetas


def test_three_p_runs_after_a_zeroing_each_start_at_zero():
    proc = subprocess.Popen([sys.executable, "-m", "station", "sim-device", "--pty", "--protocol", "legacy"],
                            stdout=subprocess.PIPE, text=True)
    try:
        path = proc.stdout.readline().strip()
        assert path.startswith("/dev/"), path
        with serial.Serial(path, baudrate=115200, timeout=5) as port:
            runs = [_p_run(port) for _ in range(3)]
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=30)
    assert [theta0 for theta0, _ in runs] == [0, 0, 0]
    for _, thetas in runs:
        assert thetas[0] == 0 and abs(thetas[-1] - STEP) <= 10  # the P loop moved the hub to its step
    assert runs[0][1] == runs[1][1] == runs[2][1]  # from rest each time: identical runs
    assert proc.returncode == 0 and json.loads(out.strip().splitlines()[-1])["ticks"] >= TICKS
