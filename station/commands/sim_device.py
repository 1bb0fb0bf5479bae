"""``station sim-device``: the simulated rig on a pty, for programs in another process.

In-process users open ``sim://`` instead (:mod:`station.sim.protocol_sim`).
"""

from __future__ import annotations

import argparse

from station.errors import StationError

NAME = "sim-device"
HELP = ("run the simulated rig on a pseudo-terminal: prints the pty path, serves until SIGTERM/SIGINT, "
        "then prints a JSON summary of the device's counters")


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``--pty`` and the server's options (protocol, realtime, seed, elements).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
    """
    from station.sim.pty_server import add_arguments

    parser.add_argument("--pty", action="store_true", help="serve the device on a new pty (required)")
    add_arguments(parser)


def run(args: argparse.Namespace) -> int:
    """Serve the device on a pty; exit code 0 after a clean SIGTERM/SIGINT.

    Parameters
    ----------
    args : argparse.Namespace
        The options parsed by the subparser :func:`configure` filled.

    Raises
    ------
    StationError
        Without ``--pty``: only the pty transport exists out of process; a bad
        ``--model``, ``--elements`` or ``--seed``.
    """
    if not args.pty:
        raise StationError("sim-device: only --pty is supported for out-of-process use "
                           "(in-process, open the port URL sim:// instead)")
    from station.sim.pty_server import serve_from_args

    try:
        serve_from_args(args)
    except (ValueError, StationError) as exc:  # a bad --model / --elements / --seed, before the pty is opened
        raise StationError(f"sim-device: {exc}") from None
    return 0
