"""``station plot LOG... [--out PNG]``: a figure of run logs, ours or the rig's, several overlaid."""

from __future__ import annotations

import argparse
from pathlib import Path

from station.commands.options import (add_force_option, add_out_dir_option, config_error, model_inputs, out_dir,
                                      out_dir_label, out_dir_remedy)
from station.config import apply_config
from station.outputs import Input, Output, check_folder, check_outputs

NAME = "plot"
HELP = "draw run logs (ours or the rig's; several are overlaid): θ and u, v and v_applied, a"


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station plot``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets LOG..., ``--out``, ``--out-dir``, ``--align`` and ``--force``.
    """
    parser.add_argument("files", type=Path, nargs="+", metavar="LOG", help="run logs (station or rig format)")
    parser.add_argument("--out", type=Path, default=None, metavar="PNG",
                        help="figure file (default: the first log's stem + .png in --out-dir)")
    add_out_dir_option(parser, "the figure when --out does not name it")
    parser.add_argument("--align", choices=("time", "step"), default="time",
                        help="line the logs up on t as logged (time, the default) or with each log's step "
                             "at t = 0 (step: the rig's logs step at 0.1 s, station step at 0.02 s)")
    add_force_option(parser)
    apply_config(parser)  # its out_dir


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

    config_error(args)
    if args.out is not None:
        figure = Output("--out", args.out)
    else:
        check_folder(out_dir(args), out_dir_label(args))  # named as the user set it
        figure = Output(f"the figure of {args.files[0].name}", out_dir(args) / f"{args.files[0].stem}.png",
                        f"--out FILE, or {out_dir_remedy(args)}")
    out = figure.path
    check_outputs([figure], [Input("LOG", f) for f in args.files] + model_inputs(args), force=args.force)
    print(f"figure: {plot_log_files(args.files, out, align=args.align)}")
    return 0
