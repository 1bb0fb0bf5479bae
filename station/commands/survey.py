"""``station survey DIR|FILES...``: replay every log of a folder and print one table."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from station.commands.options import add_model_options, check_writable, check_writable_dir, chosen_model, number

NAME = "survey"
HELP = ("replay every log of a folder (or the files given) on all cores and print one table: format, "
        "rows, sample time, controller (named / inferred / none), alignment, max |dv|, step metrics, "
        "model fits or beam-test results, and why a file could not be used")


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station survey``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets DIR|FILE..., ``--csv``, ``--report``, the model options (with ``--no-model``), ``--jobs``.
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


def run(args: argparse.Namespace) -> int:
    """Survey ``args.paths``; print the table, write CSV / reports when asked.

    Parameters
    ----------
    args : argparse.Namespace
        The paths, ``--csv``, ``--report``, the model (``--no-model``, ``--model``, ``--elements``),
        ``--jobs``.

    Returns
    -------
    int
        0 when the survey completed, whatever the files gave.

    Raises
    ------
    StationError
        A path that does not exist, nothing to survey, --jobs out of range, a bad --model or
        --elements (or either with --no-model), or an unwritable --csv / --report.
    """
    from station.errors import StationError
    from station.plant.model import as_model
    from station.survey import format_table, survey, to_csv, write_reports

    model = chosen_model(args)
    if model and (model is not True or args.elements is not None):  # loaded once: a bad --model is one error
        model = as_model(None if model is True else model, args.elements)
    if args.jobs is not None and not 1 <= args.jobs <= 64:
        raise StationError(f"--jobs {args.jobs}: expected 1..64 worker processes")
    if args.csv is not None and not (args.csv.parent.is_dir()):
        raise StationError(f"--csv {args.csv}: folder {args.csv.parent} does not exist")
    check_writable(args.csv, "--csv")
    check_writable_dir(args.report, "--report")
    tty = sys.stderr.isatty()

    def progress(done: int, total: int, row) -> None:
        status = "ok" if row.usable else "unusable"
        end = "\r" if tty and done < total else "\n"
        print(f"survey: {done}/{total} {Path(row.file).name} ({status})" + (" " * 10 if tty else ""),
              end=end, file=sys.stderr, flush=True)

    rows = survey(args.paths, model=model, workers=args.jobs, progress=progress)
    root = args.paths[0] if len(args.paths) == 1 and args.paths[0].is_dir() else None
    print(format_table(rows, root))
    if args.csv is not None:
        try:
            args.csv.write_text(to_csv(rows))
        except OSError as exc:
            raise StationError(f"--csv {args.csv}: cannot write: {exc.strerror or exc}") from None
        print(f"csv: {args.csv}")
    if args.report is not None:
        write_reports(rows, args.report)
        print(f"reports: {args.report}")
    return 0
