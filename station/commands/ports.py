"""``station ports``: the serial ports of this machine, their adapter and its latency timer
(pyserial ``list_ports``; Linux sysfs for the timer)."""

from __future__ import annotations

import argparse

from serial.tools import list_ports as lp

from station.link import PortInfo, latency_timer

NAME = "ports"
HELP = ("list the serial ports of this machine with their adapter and, where the OS has one, the USB serial "
        "adapter's latency timer (the rig's adapter among them)")


def configure(parser: argparse.ArgumentParser) -> None:
    """No options.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets nothing.
    """


def list_ports() -> list[PortInfo]:
    """Every serial port pyserial finds, sorted by device, with its adapter and latency timer."""
    found = []
    for p in lp.comports():
        adapter = p.description if p.description not in (None, "n/a") else ""
        hwid = p.hwid if p.hwid not in (None, "n/a") else ""
        found.append(PortInfo(p.device, adapter, hwid, latency_timer(p.device)))
    return sorted(found)


def _timer_text(info: PortInfo) -> str:
    if info.latency is None:
        return ""
    ms, path = info.latency
    if ms <= 1:
        return f"latency timer {ms} ms"
    return (f"latency timer {ms} ms: samples come in bursts of ~{ms // 2}; the station asks for 1 ms when it opens "
            f"the port (or: echo 1 | sudo tee {path})")


def run(args: argparse.Namespace) -> int:
    """Print one port per line (or say there is none); 0 in both cases.

    Parameters
    ----------
    args : argparse.Namespace
        Nothing is read from it.
    """
    ports = list_ports()
    if not ports:
        print("no serial ports found (is the rig's USB cable plugged in?); the simulated rig is --port sim://")
        return 0
    width = max(len(p.device) for p in ports)
    for info in ports:
        parts = [text for text in (info.adapter, info.hwid, _timer_text(info)) if text]
        print(f"{info.device:<{width}}  {'   '.join(parts)}".rstrip())
    return 0
