"""``station survey DIR|FILES...``: replay every log of a folder and print one table."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from station.commands.options import add_force_option, add_model_options, chosen_model, model_inputs, number
from station.outputs import Input, Output, Transaction, check_outputs
from station.signals import noting

NAME = "survey"
HELP = ("replay every log of a folder (or the files given) on all cores and print one table: format, "
        "rows, sample time, controller (named / inferred / none), alignment, max |dv|, step metrics, "
        "model fits or beam-test results, and why a file could not be used")


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station survey``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets DIR|FILE..., ``--csv``, ``--report``, the model options (with ``--no-model``), ``--jobs``,
        ``--force``.
    """
    parser.add_argument("paths", nargs="+", type=Path, metavar="DIR|FILE",
                        help="folders (searched recursively) and files to survey")
    parser.add_argument("--csv", type=Path, default=None, metavar="OUT", help="also write the table as CSV")
    parser.add_argument("--report", type=Path, default=None, metavar="DIR",
                        help="write each file's replay JSON and the table into DIR")
    add_model_options(parser, "each log is simulated on it as the rig ran it", params=False,
                      no_model="skip the FEM model fits (beam tests are still analyzed)")
    parser.add_argument("--jobs", type=number(1, 64, integer=True), default=None, metavar="N",
                        help="worker processes (default: the machine's cores)")
    add_force_option(parser)


def run(args: argparse.Namespace) -> int:
    """Survey ``args.paths``; print the table, write CSV / reports when asked.

    Parameters
    ----------
    args : argparse.Namespace
        The paths, ``--csv``, ``--report``, the model (``--no-model``, ``--model``, ``--elements``),
        ``--jobs``, ``--force``.

    Returns
    -------
    int
        0 when the survey completed, whatever the files gave.

    Raises
    ------
    StationError
        A path that does not exist, nothing to survey, --jobs out of range, a bad --model or
        --elements (or either with --no-model); a --csv or --report file that is one of the
        surveyed files or another output, exists (without ``--force``) or cannot be written.
    """
    from station.errors import StationError
    from station.plant.model import as_model
    from station.survey import find_logs, format_table, report_files, survey, to_csv, write_reports

    model = chosen_model(args)
    if model and (model is not True or args.elements is not None):  # loaded once: a bad --model is one error
        model = as_model(None if model is True else model, args.elements)
    if args.jobs is not None and not 1 <= args.jobs <= 64:
        raise StationError(f"--jobs {args.jobs}: expected 1..64 worker processes")
    files = find_logs(args.paths)
    reports = [] if args.report is None else [Output("--report", args.report / n) for n in report_files(files)]
    check_outputs([Output("--csv", args.csv), *reports], [Input("DIR|FILE", f) for f in files] + model_inputs(args),
                  force=args.force)
    tty = sys.stderr.isatty()
    done = [0, len(files)]

    def progress(n: int, total: int, row) -> None:
        done[:] = [n, total]
        end = "\r" if tty and n < total else "\n"
        print(f"survey: {n}/{total} {Path(row.file).name} ({row.status})" + (" " * 10 if tty else ""),
              end=end, file=sys.stderr, flush=True)

    with noting(lambda: f"after {done[0]} of {done[1]} files; nothing written"):
        rows = survey(args.paths, model=model, workers=args.jobs, progress=progress)
    root = args.paths[0] if len(args.paths) == 1 and args.paths[0].is_dir() else None
    print(format_table(rows, root))
    with Transaction() as tx:
        if args.csv is not None:
            tx.write(args.csv, to_csv(rows), "the survey CSV")
        if args.report is not None:
            write_reports(rows, args.report, tx)
    if args.csv is not None:
        print(f"csv: {args.csv}")
    if args.report is not None:
        print(f"reports: {args.report}")
    return 0
