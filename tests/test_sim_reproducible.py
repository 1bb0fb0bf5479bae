"""The simulated rig is reproducible: every START puts the plant at rest and restarts the
noise from its seed, so identical runs on one ``sim-device --pty`` give identical logs,
also after a wrong-protocol attempt; sim:// records its seed in the header."""

from __future__ import annotations

import signal
import subprocess
import sys

import numpy as np
import pytest

from station.cli import main
from station.experiment import run_step
from station.runlog import read_log


@pytest.fixture
def sim_device():
    proc = subprocess.Popen([sys.executable, "-m", "station", "sim-device", "--pty", "--seed", "7"],
                            stdout=subprocess.PIPE, text=True)
    path = proc.stdout.readline().strip()
    assert path.startswith("/dev/"), path
    yield path
    proc.send_signal(signal.SIGTERM)
    proc.communicate(timeout=30)


def test_three_identical_runs_on_one_sim_device_give_identical_logs(sim_device, tmp_path, capsys):
    logs = []
    for i in range(3):
        if i == 1:  # a wrong-protocol attempt in between leaves the device ready
            assert main(["step", "--port", sim_device, "--protocol", "legacy", "--timeout", "0.2",
                         "--out", str(tmp_path / "wrong.tsv"), "--quiet"]) == 2
            assert "--protocol v1" in capsys.readouterr().err
        out = tmp_path / f"run{i}.tsv"
        assert main(["step", "--port", sim_device, "--controller", "lead-accel", "--amplitude", "200",
                     "--duration", "1", "--out", str(out), "--quiet"]) == 0
        logs.append(read_log(out))
    first = logs[0].data
    assert np.ptp(first["theta"]) > 150 and np.ptp(first["a"]) > 20  # the rig moved
    for other in logs[1:]:
        for key in ("theta", "a", "v"):
            assert np.array_equal(other.data[key], first[key]), key


def test_sim_runs_repeat_in_one_process_and_the_seed_is_in_the_header(tmp_path):
    a = run_step(port="sim://?seed=3", duration=0.5, out=tmp_path / "a.tsv", figure=False)
    b = run_step(port="sim://?seed=3", duration=0.5, out=tmp_path / "b.tsv", figure=False)
    c = run_step(port="sim://?seed=4", duration=0.5, out=tmp_path / "c.tsv", figure=False)
    la, lb, lc = (read_log(r.log_path) for r in (a, b, c))
    assert la.meta["plant"]["options"]["seed"] == 3
    assert np.array_equal(la.data["a"], lb.data["a"]) and np.array_equal(la.data["theta"], lb.data["theta"])
    assert not np.array_equal(la.data["a"], lc.data["a"])  # the noise does depend on the seed


def test_every_start_restarts_the_plant_at_rest_and_the_noise():
    from station.protocol import v1
    from station.sim.device import SimDevice

    dev = SimDevice("v1", seed=5)

    def run(v: int, n: int) -> list:
        dev.receive(v1.encode(v1.Start(v1.START_RESET_ENCODER, n)))
        samples = []
        for k in range(n):
            samples += v1.Decoder().feed(dev.tick())
            dev.receive(v1.encode(v1.Command(k, v)))
        return [(s.theta, s.accel) for s in samples if isinstance(s, v1.Sample)]

    first = run(120, 200)
    run(-80, 37)  # another run leaves the beam swinging and the noise elsewhere
    assert run(120, 200) == first
