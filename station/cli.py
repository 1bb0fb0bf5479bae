"""The ``station`` command line: a thin layer over the package's functions.

Each subcommand lives in :mod:`station.commands` and defines ``NAME``, ``HELP``,
``configure(parser)`` and ``run(args) -> int``. A :class:`~station.errors.StationError`
is printed as one line (``station: error: ...``) with exit code 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys

from station import __version__
from station.errors import StationError
from station.signals import StopSignal

COMMANDS = ("step", "replay", "sim_device", "bode", "compare", "modes", "survey")
"""Modules of :mod:`station.commands`, in the order ``--help`` lists them."""


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser, one subparser per available command module."""
    parser = argparse.ArgumentParser(
        prog="station",
        description="Control station for the single flexible link robot: step tests on the rig or the "
                    "simulated rig, lossless run logs, replay and model checks.")
    parser.add_argument("--version", action="version", version=f"station {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"station.commands.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"station.commands.{name}":
                continue  # command not installed in this build
            raise
        cmd = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.configure(cmd)
        cmd.set_defaults(_run=module.run)
    return parser


def _raise_on_sigterm(signum, frame):
    raise StopSignal(signum)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``station`` console script; returns the exit code.

    SIGINT or SIGTERM at any moment outside a run (start-up imports included) ends the
    process with one line naming the signal and exit code 130 / 143; during a run the
    loop handles them (command 0 and stop first, see :mod:`station.signals`).
    """
    try:
        old = signal.signal(signal.SIGTERM, _raise_on_sigterm)
    except (ValueError, OSError):  # not the main thread: leave signals alone
        old = None
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        return int(args._run(args) or 0)
    except StationError as exc:
        print(f"station: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("station: stopped by SIGINT", file=sys.stderr)
        return 130
    except StopSignal as exc:
        print(f"station: stopped by {exc}", file=sys.stderr)
        return exc.exit_code
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old)


if __name__ == "__main__":
    sys.exit(main())
