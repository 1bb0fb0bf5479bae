"""``station survey DIR|FILES...``: replay every log of a folder and print one table; with
``--diagnose``, one model structure on all its logs grouped into sessions and the effects that
drift between them (DESIGN.md "Sessions and drift")."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from station.commands.options import add_force_option, add_model_options, chosen_model, model_inputs, number
from station.errors import StationError
from station.inputs import is_folder
from station.outputs import Input, Output, Transaction, check_outputs
from station.plant.model import as_model
from station.rig import SESSIONS_MAX_SAMPLES
from station.signals import noting

NAME = "survey"
HELP = ("replay every log of a folder (or the files given) on all cores and print one table: format, "
        "rows, sample time, controller (named / inferred / none), alignment, max |dv|, step metrics, "
        "model fits or beam-test results, and why a file could not be used; --diagnose: the logs grouped "
        "into sessions, one model structure on all of them, and the effects that drift between sessions")

DIAGNOSE_ONLY = ("json", "save_models", "max_samples")
"""Options that belong to ``--diagnose``."""


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station survey``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets DIR|FILE..., ``--csv``, ``--report``, the model options (with ``--no-model``), ``--jobs``,
        ``--force``, and ``--diagnose`` with ``--json``, ``--save-models``, ``--max-samples``.
    """
    parser.add_argument("paths", nargs="+", type=Path, metavar="DIR|FILE",
                        help="folders (searched recursively) and files to survey")
    parser.add_argument("--csv", type=Path, default=None, metavar="OUT", help="also write the table as CSV")
    parser.add_argument("--report", type=Path, default=None, metavar="DIR",
                        help="write each file's replay JSON and the table into DIR (with --diagnose: report.html "
                             "and drift.png)")
    add_model_options(parser, "each log is simulated on it as the rig ran it", params=False,
                      no_model="skip the FEM model fits (beam tests are still analyzed)")
    parser.add_argument("--jobs", type=number(1, 64, integer=True), default=None, metavar="N",
                        help="worker processes (default: the machine's cores)")
    add_force_option(parser)
    diag = parser.add_argument_group("sessions and drift (--diagnose)")
    diag.add_argument("--diagnose", action="store_true",
                      help="group the logs into sessions (the folder a log is in, or 'session' in our log header), "
                           "fit one model structure on all of them and give the effects that drift between "
                           "sessions a value per session")
    diag.add_argument("--json", type=Path, default=None, metavar="OUT",
                      help="write the sessions, their effects, the shared effects and the drifting ones as JSON")
    diag.add_argument("--save-models", type=Path, default=None, metavar="DIR",
                      help="write each session's model (nominal + shared + its drifting values) as DIR/<session>.toml")
    diag.add_argument("--max-samples", type=number(50, 10**9, integer=True), default=None, metavar="N",
                      help=f"most samples of all runs together; longer runs are cut to their first samples, the "
                           f"longest first, and each cut is said (default {SESSIONS_MAX_SAMPLES}: the rig's folder then "
                           f"takes a few minutes)")


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
    # lazy: start-up time (every command's parser is built at start-up: the survey)
    from station.survey import find_logs, format_table, report_files, survey, to_csv, write_reports

    if args.diagnose:
        return run_diagnose(args)
    for name in DIAGNOSE_ONLY:
        if getattr(args, name) is not None:
            raise StationError(f"--{name.replace('_', '-')}: only with --diagnose")
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
    root = args.paths[0] if len(args.paths) == 1 and is_folder(args.paths[0]) else None
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


def _diagnose_checks(args: argparse.Namespace) -> None:
    """Options that do not go with --diagnose (one line, before anything starts)."""
    if not args.model:
        raise StationError("--no-model: not with --diagnose (the diagnosis simulates every log on the model)")
    for option, value in (("--csv", args.csv), ("--jobs", args.jobs)):
        if value is not None:
            raise StationError(f"{option}: not with --diagnose (it belongs to the survey's table of replays)")


def run_diagnose(args: argparse.Namespace) -> int:
    """``station survey DIR... --diagnose``: the logs grouped into sessions, one model structure on
    all of them and the effects that drift between sessions (:mod:`station.diagnosis.sessions.diagnose`).

    Parameters
    ----------
    args : argparse.Namespace
        The paths, ``--model`` / ``--elements``, ``--json``, ``--save-models``, ``--report``,
        ``--max-samples``, ``--force``.

    Returns
    -------
    int
        0 when the diagnosis ran to the end, whatever it found.

    Raises
    ------
    StationError
        A path that does not exist, no log, ``--csv``, ``--jobs`` or ``--no-model`` with
        ``--diagnose``, a bad ``--model``; an output that is an input or another output,
        exists (without ``--force``) or cannot be written; no usable run, or only one.
    """
    # lazy: start-up time (the diagnosis: scipy)
    from station.diagnosis.sessions.diagnose import diagnose_sessions
    from station.diagnosis.sessions.logs import group_sessions, model_file_names
    from station.diagnosis.sessions.report import REPORT_FILES, format_sessions
    from station.survey import find_logs, not_a_log

    _diagnose_checks(args)
    files = find_logs(args.paths)
    logs = [f for f in files if not_a_log(f) is None]
    if not logs:
        raise StationError(f"{', '.join(map(str, args.paths))}: no logs to diagnose")
    sessions = group_sessions(logs)
    model_paths = ({} if args.save_models is None else
                   {s.name: args.save_models / f for s, f in zip(sessions, model_file_names(sessions))})
    outputs = [Output("--json", args.json), *(Output("--save-models", p) for p in model_paths.values()),
               *([] if args.report is None else [Output("--report", args.report / n) for n in REPORT_FILES])]
    check_outputs(outputs, [Input("DIR|FILE", f) for f in files] + model_inputs(args), force=args.force)
    spec = chosen_model(args)
    model = as_model(None if spec is True else spec, args.elements)
    last = ["reading the logs"]

    def progress(msg: str) -> None:
        last[0] = msg
        print(f"survey: {msg}", file=sys.stderr, flush=True)

    print(f"survey: {len(logs)} logs in {len(sessions)} session(s): "
          + ", ".join(f"{s.name} ({len(s.paths)})" for s in sessions), file=sys.stderr, flush=True)
    with noting(lambda: f"the diagnosis was at: {last[0]}; nothing written"):
        result = diagnose_sessions(sessions, model=model, progress=progress,
                                   max_samples=SESSIONS_MAX_SAMPLES if args.max_samples is None else args.max_samples)
    models = {s.name: str(model_paths[s.name]) for s in result.sessions if s.name in model_paths}
    print(format_sessions(result, models))
    with Transaction() as tx:
        if args.report is not None:
            from station.diagnosis.sessions.report import write_report  # lazy: start-up time (matplotlib)

            page = write_report(result, args.report, tx, models)
        if args.json is not None:
            tx.write_json(args.json, result.to_json(models))
        for name, path in models.items():
            tx.write(path, result.model_text(name), "the session's model")
    if args.report is not None:
        print(f"report: {page}")
    return 0
