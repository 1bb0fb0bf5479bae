"""``station replay FILE``: re-run a logged run's controller, check it reproduces the
logged commands, report step metrics and the model's fit."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from station.commands.options import check_writable, number

NAME = "replay"
HELP = ("replay a run log (ours or the rig's): reproduce the logged commands, detect the "
        "alignment, step metrics and the FEM model's fit")


def configure(parser: argparse.ArgumentParser) -> None:
    """Add the command's arguments to its subparser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
    """
    parser.add_argument("file", type=Path, metavar="FILE", help="run log (station or rig format)")
    parser.add_argument("--json", type=Path, default=None, metavar="OUT", help="write the report as JSON")
    parser.add_argument("--no-model", dest="model", action="store_false",
                        help="skip the FEM model prediction")
    parser.add_argument("--model", dest="model_spec", default=None, metavar="NAME|FILE",
                        help="the model: a built-in model's name (station/plant/models) or a model file (default tmm-fit)")
    parser.add_argument("--elements", type=number(1, 100, integer=True), default=None, metavar="N",
                        help="beam elements of the FEM model (default: the model's, 4)")
    viz = parser.add_mutually_exclusive_group()
    viz.add_argument("--rrd", type=Path, default=None, metavar="FILE",
                     help="record the log, the replayed v and the model to a rerun .rrd file")
    viz.add_argument("--spawn", action="store_true", help="show them in a rerun viewer")


def _record(report, rrd: Path | None, spawn: bool) -> None:
    from station.viz import RerunSink

    sink = RerunSink(rrd_path=rrd, spawn=spawn, name="station replay")
    try:
        if report.log is not None:
            sink.write_rows(report.log.data)
        if report.v_replayed is not None:
            sink.log_series("v/replayed", report.v_replayed, t=report.log.data["t"])
        if report.prediction is not None:
            sink.log_prediction(report.prediction)
    finally:
        sink.close()


def run(args: argparse.Namespace) -> int:
    """Replay ``args.file``; print the summary, write JSON / rerun output when asked.

    Parameters
    ----------
    args : argparse.Namespace
        The options parsed by the subparser :func:`configure` filled.

    Returns
    -------
    int
        0 when the replay reproduces the logged v (or the log names no controller and
        only the model ran), 1 when it does not.

    Raises
    ------
    StationError
        Unreadable log or model file, bad controller spec, unwritable JSON or .rrd file.
    """
    from station.errors import StationError
    from station.replay import format_report, replay

    if not args.model and (args.model_spec is not None or args.elements is not None):
        raise StationError(f"{'--model' if args.model_spec is not None else '--elements'}: not with --no-model")
    check_writable(args.json, "--json")
    check_writable(args.rrd, "--rrd")
    model = (args.model_spec or True) if args.model else False
    report = replay(args.file, model=model, n_elements=args.elements)
    print(format_report(report))
    if args.json is not None:
        try:
            args.json.write_text(json.dumps(report.to_json(), indent=2) + "\n")
        except OSError as exc:
            raise StationError(f"{args.json}: cannot write the JSON report: {exc.strerror or exc}") from None
        print(f"report: {args.json}")
    if args.rrd is not None or args.spawn:
        _record(report, args.rrd, args.spawn)
        if args.rrd is not None:
            print(f"rerun recording: {args.rrd}")
    return 0 if report.max_abs_dv is None or report.reproduced else 1
