"""``station ports``: the serial ports of this machine with their description (pyserial ``list_ports``)."""

from __future__ import annotations

import argparse

NAME = "ports"
HELP = "list the serial ports of this machine with their description (the rig's USB-serial adapter among them)"


def configure(parser: argparse.ArgumentParser) -> None:
    """No options.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets nothing.
    """


def list_ports() -> list[tuple[str, str]]:
    """``(device, description)`` of every serial port pyserial finds, sorted by device."""
    from serial.tools import list_ports as lp

    return sorted((p.device, p.description or "") for p in lp.comports())


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
    width = max(len(d) for d, _ in ports)
    for device, description in ports:
        print(f"{device:<{width}}  {description}")
    return 0
