"""The ``station`` command line: a thin layer over the package's functions.

Each subcommand lives in :mod:`station.commands` and defines ``NAME``, ``HELP``,
``configure(parser)`` and ``run(args) -> int``. A :class:`~station.errors.StationError`
is printed as one line (``station: error: ...``) with exit code 2, never a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import sys
import warnings

from station import __version__
from station.commands.options import StationParser, document_ranges
from station.errors import StationError, one_line
from station.signals import StopSignal, StopSignals

COMMANDS = ("step", "replay", "sim_device", "bode", "compare", "modes", "survey", "diagnose", "identify", "tune",
            "plot", "ports")
"""Modules of :mod:`station.commands`, in the order ``--help`` lists them."""
VERBOSE_HELP = "log what the link, loop and simulated device do (-v: info, -vv: every byte)"
"""``-v``/``--verbose``, before or after the command (``station -v step`` or ``station step -v``)."""


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser, one subparser per available command module."""
    parser = StationParser(
        prog="station",
        description="Control station for the single flexible link robot: step tests on the rig or the "
                    "simulated rig, lossless run logs, replay and model checks.")
    parser.add_argument("--version", action="version", version=f"station {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help=VERBOSE_HELP)
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
        cmd.add_argument("-v", "--verbose", action="count", default=argparse.SUPPRESS, help=VERBOSE_HELP)
        document_ranges(cmd)
        cmd.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``station`` console script; returns the exit code.

    SIGINT or SIGTERM at any moment - start-up imports included - ends the process with
    one line naming the signal and what the stopped work had (``StopSignal.note``), exit
    code 130 / 143, within a second (long work calls :func:`station.signals.check_stop`);
    during a run the loop handles
    them (command 0 and stop first, see :mod:`station.signals`) and the run's outcome
    gives the code. Called as the console script (``argv`` None), signals arriving once
    the work is done are ignored until the process exits (the tail of a burst must not
    kill it with a different code); called with ``argv`` (tests, notebooks), the old
    handlers are put back.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments; None: ``sys.argv[1:]`` (the console script).
    """
    try:
        return _main(argv)
    except KeyboardInterrupt:  # SIGINT before the guard took the signals (on its own `with` line)
        print("station: stopped by SIGINT", file=sys.stderr)
        return 130


def _main(argv: list[str] | None) -> int:
    """:func:`main` inside the signal guard."""
    with StopSignals(ignore_after=argv is None) as signals, warnings.catch_warnings():
        warnings.showwarning = _one_line_warning
        try:
            try:
                parser = build_parser()
                try:
                    args = parser.parse_args(argv)
                except SystemExit as exc:  # --help, or a refused value: argparse said it in one line
                    return exc.code if isinstance(exc.code, int) else 2
                with _logging(args.verbose):
                    return int(args._run(args) or 0)
            except StationError as exc:
                print(f"station: error: {one_line(str(exc))}", file=sys.stderr)
                return exc.exit_code
            except BrokenPipeError:  # `station step | head`: the reader left; nothing to say
                _silence_stdout()
                return 0
        except StopSignal as exc:  # outside a run's loop: the work stopped, saying what it had
            print(f"station: stopped by {exc}; {exc.note or 'nothing written'}",
                  file=sys.stderr)
            return exc.exit_code
        except KeyboardInterrupt:  # SIGINT before the guard was installed, or raised by code
            print("station: stopped by SIGINT", file=sys.stderr)
            return 130
        finally:
            signals.defer()


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line for the user (``station: warning: ...``), not Python's two-line form."""
    print(f"station: warning: {message}", file=sys.stderr if file is None else file)


@contextlib.contextmanager
def _logging(verbose: int):
    """The station's loggers on stderr for one command: warnings as one line each
    (``station: warning: ...``); ``-v``: INFO with times and names, ``-vv``: DEBUG (every byte
    on the wire). The handler goes when the command ends (``main`` may run again in a process)."""
    handler = logging.StreamHandler(sys.stderr)
    root = logging.getLogger("station")
    level = root.level
    if verbose <= 0:
        handler.setFormatter(logging.Formatter("station: warning: %(message)s"))
        handler.setLevel(logging.WARNING)
    else:
        handler.setFormatter(logging.Formatter("%(relativeCreated)9.1f ms %(name)s: %(message)s"))
        root.setLevel(logging.DEBUG if verbose >= 2 else logging.INFO)
    root.addHandler(handler)
    try:
        yield
    finally:
        root.removeHandler(handler)
        root.setLevel(level)


def _silence_stdout() -> None:
    """Point stdout at /dev/null so the interpreter's final flush cannot raise again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


if __name__ == "__main__":
    sys.exit(main())
