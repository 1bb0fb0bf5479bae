"""The simulated device on a pseudo-terminal, for out-of-process use (``station sim-device --pty``).

The first line on stdout is the pty's slave path (flushed), so a parent process can read
it and open the port like a real device. The device then runs on the master side until
SIGTERM or SIGINT, and prints a one-line JSON summary of the last run's counters,
``{"ticks": .., "late": .., "watchdog_trips": .., "rx_errors": .., "tx_lost": .., "max_slip_ms": ..}``,
which benchmarks parse (tx_lost: bytes the device sent that did not fit into the pty because
nobody read them; the device never blocks on them; max_slip_ms: the most a realtime tick
came after its time, this process held up - its samples then go out together). Pacing as for ``sim://`` (:mod:`station.sim.driver`): lockstep, or realtime
(500 Hz on absolute deadlines, ``select`` with a timeout up to the next deadline).

Run it as ``station sim-device --pty [--realtime] [--protocol legacy] [--seed N] [--model NAME|FILE]
[--elements N]`` (:mod:`station.commands.sim_device`); ``python -m station.sim.pty_server`` with
the same options is an alias that execs it (this module never imports the command line).
"""

from __future__ import annotations

import gc
import json
import os
import select
import signal
import sys
import time
import tty
from typing import TYPE_CHECKING

from station.realtime import RealtimePriority
from station.rig import RATE_HZ

if TYPE_CHECKING:
    from station.sim.driver import Faults


def _send(fd: int, data: bytes) -> int:
    """Write ``data`` to the pty master without ever blocking the device; bytes that do not fit are lost.

    Like a UART whose receiver stopped reading: the transmitter goes on and the bytes
    are lost at the far end. Returns how many were lost.
    """
    view = memoryview(data)
    while view:
        try:
            view = view[os.write(fd, view):]
        except BlockingIOError:
            return len(view)
    return 0


def serve_pty(protocol: str = "v1", realtime: bool = False, seed: int = 0, n_elements: int | None = None,
              accel_noise_std: float = 0.3, watchdog_ticks: int = 10, faults: Faults | None = None,
              out=None, model=None) -> dict:
    """Run the simulated device on a new pty until SIGTERM/SIGINT.

    Parameters
    ----------
    protocol : {"v1", "legacy"}, default "v1"
    realtime : bool, default False
        500 Hz own clock (True) or lockstep with the station (False).
    seed, n_elements, accel_noise_std, watchdog_ticks, model
        As for :class:`station.sim.device.SimDevice` (``model``: a Model, a built-in
        model's name or a model file; default tmm-fit).
    faults : Faults, optional
        Faults to inject (:class:`station.sim.driver.Faults`).
    out : text file, default sys.stdout
        Gets the slave path (first line) and, at the end, the JSON summary line.

    Returns
    -------
    dict
        The summary printed at exit: ticks, late, watchdog_trips, rx_errors of the last
        run (all 0 when no run was started), tx_lost over the whole session.
    """
    # lazy: start-up time (the FEM plant, not needed to build the CLI)
    from station.sim.device import SimDevice
    from station.sim.driver import DeviceDriver

    out = out or sys.stdout
    device = SimDevice(protocol, seed=seed, n_elements=n_elements, model=model, accel_noise_std=accel_noise_std,
                       watchdog_ticks=watchdog_ticks)
    driver = DeviceDriver(device, faults, lockstep=not realtime)
    master, slave = os.openpty()
    tty.setraw(slave)  # no echo, no line editing, no CR/LF translation for the station
    tty.setraw(master)
    os.set_blocking(master, False)
    stop = []
    previous = {sig: signal.signal(sig, lambda *_: stop.append(True)) for sig in (signal.SIGTERM, signal.SIGINT)}
    RealtimePriority().raise_()  # for the life of this process: no restore needed
    gc.collect()
    gc.freeze()  # the plant, numba and scipy never get scanned again: no full collection stalls a tick
    print(os.ttyname(slave), file=out, flush=True)
    period = 1.0 / RATE_HZ
    deadline = time.perf_counter() + period
    lost = 0
    slip = 0.0  # the most a tick came after its time (this process held up): a benchmark tells it from lag
    try:
        while not stop:
            timeout = max(0.0, deadline - time.perf_counter()) if realtime else 0.1
            try:
                readable, _, _ = select.select([master], [], [], timeout)
            except InterruptedError:
                continue
            if readable:
                try:
                    data = os.read(master, 4096)
                except (BlockingIOError, OSError):
                    data = b""  # EIO: no process has the slave open right now
                if data:
                    lost += _send(master, driver.feed(data))
            if realtime and (now := time.perf_counter()) >= deadline:
                slip = max(slip, now - deadline)
                lost += _send(master, driver.clock_tick())
                deadline += period
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        os.close(master)
        os.close(slave)
    c = device.counters
    summary = {"ticks": c.ticks, "late": c.late, "watchdog_trips": c.watchdog_trips, "rx_errors": c.rx_errors,
               "tx_lost": lost, "max_slip_ms": round(1000 * slip, 2)}
    print(json.dumps(summary), file=out, flush=True)
    return summary


if __name__ == "__main__":  # an alias: the command line is station.commands.sim_device's (one definition)
    os.execv(sys.executable, [sys.executable, "-m", "station", "sim-device", "--pty", *sys.argv[1:]])
