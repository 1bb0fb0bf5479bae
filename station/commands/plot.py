"""``station plot LOG... [--out PNG]``: a figure of run logs, ours or the rig's, several overlaid."""

from __future__ import annotations

import argparse
from pathlib import Path

from station.commands.options import add_force_option
from station.outputs import Input, Output, check_outputs

NAME = "plot"
HELP = "draw run logs (ours or the rig's; several are overlaid): θ and u, v and v_applied, a"


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station plot``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets LOG..., ``--out``, ``--align`` and ``--force``.
    """
    parser.add_argument("files", type=Path, nargs="+", metavar="LOG", help="run logs (station or rig format)")
    parser.add_argument("--out", type=Path, default=None, metavar="PNG",
                        help="figure file (default: the first log's stem + .png in the current folder)")
    parser.add_argument("--align", choices=("time", "step"), default="time",
                        help="line the logs up on t as logged (time, the default) or with each log's step "
                             "at t = 0 (step: the rig's logs step at 0.1 s, station step at 0.02 s)")
    add_force_option(parser)


def run(args: argparse.Namespace) -> int:
    """Read the logs, overlay them, write the PNG; 0.

    Parameters
    ----------
    args : argparse.Namespace
        The logs (``files``), ``--out``, ``--align`` and ``--force``.

    Raises
    ------
    StationError
        An unreadable log (file, line, field); an --out that is one of the logs, exists
        (without ``--force``) or cannot be written.
    """
    from station.plots import plot_log_files  # lazy: start-up time (matplotlib)

    out = args.out if args.out is not None else Path(args.files[0].stem + ".png")
    check_outputs([Output("--out", out)], [Input("LOG", f) for f in args.files], force=args.force)
    print(f"figure: {plot_log_files(args.files, out, align=args.align)}")
    return 0
