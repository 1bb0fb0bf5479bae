"""``station replay FILE``: re-run a logged run's controller, check it reproduces the
logged commands, report step metrics and the model's fit."""

from __future__ import annotations

import argparse
from pathlib import Path

from station.commands.options import add_force_option, add_model_options, add_report_options, chosen_model, model_inputs
from station.outputs import Input, Output, Transaction, check_outputs

NAME = "replay"
HELP = ("replay a run log (ours or the rig's): reproduce the logged commands, detect the "
        "alignment, step metrics and the FEM model's fit")


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station replay``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets FILE, the model options (with ``--no-model``), ``--json``, ``--rrd``/``--spawn``,
        ``--force``.
    """
    parser.add_argument("file", type=Path, metavar="FILE", help="run log (station or rig format)")
    add_model_options(parser, params=False, no_model="skip the FEM model prediction")
    add_report_options(parser, json="the report", rerun="the log, the replayed v and the model")
    add_force_option(parser)


def _record(report, rrd: Path | None, spawn: bool, tx: Transaction) -> None:
    from station.viz import RerunSink  # lazy: start-up time (rerun)

    sink = RerunSink(rrd_path=rrd, spawn=spawn, name="station replay")
    done = False
    try:
        if report.log is not None:
            sink.write_rows(report.log.data)
        if report.v_replayed is not None:
            sink.log_series("v/replayed", report.v_replayed, t=report.log.data["t"])
        if report.prediction is not None:
            sink.log_prediction(report.prediction)
        done = True
    finally:
        sink.close(keep=done, transaction=tx)


def run(args: argparse.Namespace) -> int:
    """Replay ``args.file``; print the summary, write JSON / rerun output when asked.

    Parameters
    ----------
    args : argparse.Namespace
        FILE, the model (``--no-model``, ``--model``, ``--elements``), ``--json``,
        ``--rrd``/``--spawn``, ``--force``.

    Returns
    -------
    int
        0 when the replay reproduces the logged v (or the log names no controller and
        only the model ran), 1 when it does not.

    Raises
    ------
    StationError
        Unreadable log or model file, bad controller spec; an output that is an input or
        another output, exists (without ``--force``) or cannot be written.
    """
    from station.replay import format_report, replay  # lazy: start-up time (the replay and its model)

    model = chosen_model(args)
    check_outputs([Output("--json", args.json), Output("--rrd", args.rrd)],
                  [Input("FILE", args.file), *model_inputs(args)], force=args.force)
    report = replay(args.file, model=model, n_elements=args.elements)
    report.run.log.require_rows("replay")  # a header only: nothing ran (exit 2, as a bad input)
    print(format_report(report))
    with Transaction() as tx:
        if args.json is not None:
            tx.write_json(args.json, report.to_json(), indent=2)
        if args.rrd is not None or args.spawn:
            _record(report, args.rrd, args.spawn, tx)
    if args.json is not None:
        print(f"report: {args.json}")
    if args.rrd is not None:
        print(f"rerun recording: {args.rrd}")
    return 1 if report.reproduced is False else 0
