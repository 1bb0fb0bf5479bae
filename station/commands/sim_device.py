"""``station sim-device``: the simulated rig on a pty, for programs in another process.

In-process users open ``sim://`` instead (:mod:`station.sim.protocol_sim`).
``python -m station.sim.pty_server [OPTIONS]`` is the same as ``station sim-device --pty [OPTIONS]``.
"""

from __future__ import annotations

import argparse

from station.commands.options import add_model_options, add_protocol_option, add_seed_option
from station.errors import StationError

NAME = "sim-device"
HELP = ("run the simulated rig on a pseudo-terminal: prints the pty path, serves until SIGTERM/SIGINT, "
        "then prints a JSON summary of the device's counters (those of its last run: every START resets them)")


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``--pty`` and the server's options (protocol, realtime, seed, model, elements).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets ``--pty``, ``--protocol``, ``--realtime``, ``--seed`` and the model options.
    """
    parser.add_argument("--pty", action="store_true", help="serve the device on a new pty (required)")
    add_protocol_option(parser)
    parser.add_argument("--realtime", action="store_true",
                        help="tick on the device's own 500 Hz clock (default: lockstep with the station)")
    add_seed_option(parser, default=0)
    add_model_options(parser, subject="the simulated rig's model", params=False)


def run(args: argparse.Namespace) -> int:
    """Serve the device on a pty; exit code 0 after a clean SIGTERM/SIGINT.

    Parameters
    ----------
    args : argparse.Namespace
        ``--pty``, ``--protocol``, ``--realtime``, ``--seed``, ``--model``, ``--elements``.

    Raises
    ------
    StationError
        Without ``--pty``: only the pty transport exists out of process; a bad
        ``--model``, ``--elements`` or ``--seed``.
    """
    if not args.pty:
        raise StationError("sim-device: only --pty is supported for out-of-process use "
                           "(in-process, open the port URL sim:// instead)")
    from station.sim.pty_server import serve_pty  # lazy: start-up time (the FEM plant)

    if args.model is not None:  # named by its option, as every command names it
        from station.plant import load_model  # lazy: start-up time, as serve_pty above

        try:
            load_model(args.model)
        except StationError as exc:
            raise StationError(f"--model: {exc}") from None
    try:
        serve_pty(args.protocol, args.realtime, args.seed, args.elements, model=args.model)
    except (ValueError, StationError) as exc:  # a bad --model / --elements / --seed, before the pty is opened
        raise StationError(f"sim-device: {exc}") from None
    return 0
