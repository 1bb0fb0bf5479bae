"""``station step``: a step test on the rig or the simulated rig."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from station import experiment as ex
from station.errors import StationError
from station.commands.options import (add_force_option, add_link_options, add_model_options, add_out_dir_option,
                                      add_protocol_option, add_report_options, add_seed_option, config_error,
                                      link_limits, model_inputs, out_dir, out_dir_label, warn)
from station.config import apply_config
from station.outputs import Output, check_folder, write_json
from station.plan import RANGES, StepPlan, plan_step
from station.signals import noting
from station.viz import RerunSink

SIM_ONLY = "simulated rig only (sim://?{key}=...)"
"""What the simulated rig's options say in ``--help``: a real port refuses them."""

NAME = "step"
HELP = ("run a step test (default: lead compensator, 100 counts, on the built-in simulated rig); "
        "also pulse, swept-sine or file references")


def configure(parser) -> None:
    """Add ``station step``'s options to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets the controller, reference, port, link bounds and output options; defaults from
        ``station.toml`` (:func:`station.config.apply_config`).
    """
    parser.add_argument("--controller", default=ex.DEFAULT_CONTROLLER,
                        help="p, lead, lead-accel, open-loop or a compensator FILE.toml (default lead)")
    parser.add_argument("--kp", type=RANGES["kp"], default=None,
                        help="P gain for --controller p only, DAC counts per encoder count (default 2)")
    parser.add_argument("--limit", type=RANGES["limit"], default=None,
                        help="controller clamp, ±DAC counts (default 200; a compensator file's own limit wins)")
    parser.add_argument("--amplitude", type=RANGES["amplitude"], default=None,
                        metavar="COUNTS", help="step height in encoder counts (open loop: DAC counts, at most "
                        "255); not with a file reference (default 100)")
    parser.add_argument("--duration", type=RANGES["duration"], default=None, metavar="S",
                        help="run length (default 2 s; swept sine 22 s; a file reference: its length); at most "
                             "what v1 can count (2^32-1 ticks), legacy 32767 ticks (65.5 s)")
    parser.add_argument("--reference", default="step", metavar="KIND",
                        help="step (default), pulse (open loop, 0.1 s), swept-sine, or FILE[:COLUMN] "
                             "of a run log (e.g. a rig log's u)")
    parser.add_argument("--step-time", type=RANGES["step_time"], default=None,
                        metavar="S", help="when the step starts, before the run's end (default 0.02 s = tick 10)")
    parser.add_argument("--port", default=ex.DEFAULT_PORT, metavar="URL",
                        help="port path or pyserial URL (default sim://, the simulated rig)")
    add_protocol_option(parser)
    add_model_options(parser, subject="the simulated rig's model", params=False, note=SIM_ONLY)
    add_seed_option(parser, note=SIM_ONLY)
    add_link_options(parser)
    parser.add_argument("--out", type=Path, default=None, metavar="FILE",
                        help="run log (default step-<controller>-<UTC time with ms>.tsv in --out-dir), streamed "
                             "during the run. The run's figure goes beside it as <log stem>.png")
    add_force_option(parser)
    parser.add_argument("--quiet", action="store_true",
                        help="no live progress line on stderr (it is shown only when stderr is a terminal)")
    add_out_dir_option(parser, "the run log and its figure when --out does not name the log")
    add_report_options(parser, json="metrics and timing", rerun="the run")
    apply_config(parser)


def plan(args) -> StepPlan:
    """The step test the options ask for, settled and checked before anything starts: the
    plan :func:`station.experiment.run_step` runs (:func:`station.plan.plan_step`, which
    a notebook's ``run_step(...)`` goes through too).

    Ranges of single options are argparse's (:data:`station.plan.RANGES`); the plan checks
    what depends on the controller, the reference and the protocol, and every output
    against every input (``--controller``, ``--reference``, the simulated rig's model file,
    ``station.toml``).

    Parameters
    ----------
    args : argparse.Namespace
        What :func:`configure` added.

    Returns
    -------
    station.plan.StepPlan

    Raises
    ------
    StationError
        One line naming the option (or the settings file).
    """
    config_error(args)
    if args.out is None:  # the output folder named as the user set it (an option, station.toml or the default)
        check_folder(out_dir(args), out_dir_label(args))
    return plan_step(port=args.port, protocol=args.protocol, controller=args.controller, amplitude=args.amplitude,
                     duration=args.duration, step_time=args.step_time, reference=args.reference,
                     kp=args.kp, limit=args.limit, soft_limit=args.soft_limit, timeout=args.timeout,
                     limits=link_limits(args),
                     baudrate=args.baud, model=args.model, n_elements=args.elements, seed=args.seed,
                     out=args.out, out_dir=out_dir(args), force=args.force,
                     outputs=[Output("--json", args.json), Output("--rrd", args.rrd)],
                     inputs=model_inputs(args),  # (the plan names --model and --port's model itself)
                     rrd=args.rrd is not None, notify=warn)


def run(args) -> int:
    """Run the test; exit code 0 when it completed, 1 when it was stopped by a fault.

    Parameters
    ----------
    args : argparse.Namespace
        The controller, reference, port, simulated rig, link bounds and outputs; checked by
        :func:`plan`.
    """
    step_plan = plan(args)  # every check, before anything starts
    if getattr(args, "_config", None):
        warn(f"settings from {args._config} (options given on the command line win)")
    sinks = []
    if args.rrd is not None or args.spawn:
        sinks.append(RerunSink(rrd_path=args.rrd, spawn=args.spawn, name="station step"))
    report = None
    try:
        with noting(lambda: "before the run started; nothing written"):  # in the loop, the run's outcome says it
            report = ex.run_step(step_plan, sinks=sinks, progress=not args.quiet and sys.stderr.isatty(),
                                 announce=lambda line: print(line, flush=True))
    finally:
        failed = _close(sinks, keep=report is not None)  # no recording of a run that never started
    print(ex.format_report(report))
    if report.figure_path is not None:
        print(f"figure: {report.figure_path}")
    if failed is not None:  # after the run's report: the log is complete, an output is not
        raise failed
    if args.rrd is not None:
        print(f"rerun recording: {args.rrd}")
    if args.json is not None:
        write_json(args.json, report.to_json())
    return report.result.outcome.exit_code


def _close(sinks, keep: bool) -> StationError | None:
    """Close every sink; the first one's error (an .rrd that could not be written), if any."""
    failed = None
    for sink in sinks:
        try:
            sink.close(keep=keep)
        except StationError as exc:
            failed = failed or exc
    return failed
