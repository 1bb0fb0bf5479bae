"""``station step``: a step test on the rig or the simulated rig."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from station import DT
from station import experiment as ex
from station import runsetup
from station.errors import StationError
from station.inputs import exists
from station.commands.options import (add_force_option, add_model_options, add_protocol_option, add_report_options,
                                      add_seed_option, model_inputs, number, warn)
from station.config import apply_config
from station.link import LinkLimits
from station.outputs import Input, Output, check_folder, check_outputs, is_device, write_json
from station.protocol import check_ticks
from station.signals import noting
from station.viz import RRD_BYTES_PER_TICK, RerunSink

MAX_DURATION_S = (2**32 - 1) * DT
"""Longest run v1 can count (START's n_ticks is a u32), s."""
MAX_AMPLITUDE = 32767.0
"""Largest step height, counts (the legacy protocol's θ word is int16; the soft limit bounds it further)."""

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
    parser.add_argument("--kp", type=number(1e-3, 100.0), default=None,
                        help="P gain for --controller p only, DAC counts per encoder count (default 2)")
    parser.add_argument("--limit", type=number(1, 255, unit="DAC counts"), default=None,
                        help="controller clamp, ±DAC counts (default 200; a compensator file's own limit wins)")
    parser.add_argument("--amplitude", type=number(-MAX_AMPLITUDE, MAX_AMPLITUDE, nonzero=True), default=None,
                        metavar="COUNTS", help="step height in encoder counts (open loop: DAC counts, at most "
                        "255); not with a file reference (default 100)")
    parser.add_argument("--duration", type=number(2 * DT, MAX_DURATION_S, unit="s"), default=None, metavar="S",
                        help="run length (default 2 s; swept sine 22 s; a file reference: its length); at most "
                             "what v1 can count (2^32-1 ticks), legacy 32767 ticks (65.5 s)")
    parser.add_argument("--reference", default="step", metavar="KIND",
                        help="step (default), pulse (open loop, 0.1 s), swept-sine, or FILE[:COLUMN] "
                             "of a run log (e.g. a rig log's u)")
    parser.add_argument("--step-time", type=number(0.0, MAX_DURATION_S, unit="s"), default=None,
                        metavar="S", help="when the step starts, before the run's end (default 0.02 s = tick 10)")
    parser.add_argument("--port", default=ex.DEFAULT_PORT, metavar="URL",
                        help="port path or pyserial URL (default sim://, the simulated rig)")
    add_protocol_option(parser)
    add_model_options(parser, subject="the simulated rig's model", params=False, note=SIM_ONLY)
    add_seed_option(parser, note=SIM_ONLY)
    parser.add_argument("--baud", type=number(300, 12_000_000, integer=True), default=None, help="baud rate (default 921600 for v1, 115200 legacy)")
    parser.add_argument("--timeout", type=number(1e-3, 60.0, unit="s"), default=ex.DEFAULT_TIMEOUT, metavar="S",
                        help="longest wait for a sample before stopping safely (default 0.1 s)")
    parser.add_argument("--soft-limit", type=number(1, 32767, unit="encoder counts"), default=ex.DEFAULT_SOFT_LIMIT,
                        metavar="COUNTS",
                        help="stop safely when |θ| exceeds this (default 2048 = two revolutions)")
    parser.add_argument("--max-lag", type=number(0, 1000, unit="ms"), default=1000 * LinkLimits.max_lag,
                        metavar="MS", help="how far the station may fall behind the device and catch up (skipped "
                        "samples and those that arrive while it computes, × 2 ms); more stops the run (reason lag). A command is "
                        "only ever computed from the newest sample (default 20 ms, the v1 watchdog's 10 ticks)")
    parser.add_argument("--max-miss", type=number(0, 99, integer=True), default=LinkLimits.max_miss, metavar="TICKS",
                        help="stop when more of the last 100 ticks than this were dropped, stale or duplicated "
                             "(reason sequence), or ran on a held command (late or skipped) beyond one catch-up of "
                             "--max-lag (reason lag) (default 10)")
    parser.add_argument("--max-step", type=number(1.0, 10000.0), default=LinkLimits.max_step, metavar="COUNTS",
                        help="largest plausible encoder change per tick; more stops the run (reason sequence; "
                             "default 40)")
    parser.add_argument("--out", type=Path, default=None, metavar="FILE",
                        help="run log (default runs/step-<controller>-<UTC time with ms>.tsv), streamed during the "
                             "run. The run's figure goes beside it as <log stem>.png")
    add_force_option(parser)
    parser.add_argument("--quiet", action="store_true",
                        help="no live progress line on stderr (it is shown only when stderr is a terminal)")
    parser.add_argument("--out-dir", type=Path, default=Path("runs"), metavar="DIR",
                        help="folder of the default run log names (default runs)")
    add_report_options(parser, json="metrics and timing", rerun="the run")
    apply_config(parser)


def check_args(args) -> None:
    """Refuse options that do not apply or do not fit together, before anything starts.

    Ranges of single options are argparse's (:mod:`station.commands.options`); this
    checks what depends on the controller and the reference, and the output paths.

    Parameters
    ----------
    args : argparse.Namespace
        What :func:`configure` added; ``step_time`` gets its default here.

    Raises
    ------
    StationError
        One line naming the option.
    """
    if getattr(args, "_config_error", None):
        raise StationError(args._config_error)
    controller = str(args.controller)
    builtin_ref = args.reference in runsetup.REFERENCES
    port = str(args.port)
    if "://" not in port and not exists(port):
        raise StationError(f"--port {port}: no such device; `station ports` lists this machine's serial ports "
                           f"(the simulated rig is sim://)")
    if args.kp is not None and controller != "p":
        raise StationError(f"--kp: the P gain applies to --controller p only, not {controller}")
    if args.amplitude is not None and not builtin_ref:
        raise StationError(f"--amplitude: not with a file reference ({args.reference}): the file's column is "
                           f"the reference")
    amplitude = ex.DEFAULT_AMPLITUDE if args.amplitude is None else args.amplitude
    if controller == "open-loop" and builtin_ref and abs(amplitude) > 255:
        raise StationError(f"--amplitude {amplitude:g}: open loop the reference is the command, at most 255 DAC counts")
    if controller != "open-loop" and builtin_ref and abs(amplitude) >= args.soft_limit:
        raise StationError(f"--amplitude {amplitude:g}: the step would pass --soft-limit {args.soft_limit:g} "
                           f"encoder counts and stop the run")
    if args.step_time is not None and (not builtin_ref or args.reference == "swept-sine"):
        raise StationError(f"--step-time: not with the {args.reference} reference "
                           f"({'its law starts at t = 1 s' if builtin_ref else 'the file gives the reference'})")
    if args.step_time is None:
        args.step_time = ex.DEFAULT_STEP_TICK * DT
    if builtin_ref and args.reference != "swept-sine":
        duration = runsetup.DEFAULT_DURATION if args.duration is None else args.duration
        if args.step_time >= duration:
            raise StationError(f"--step-time {args.step_time:g} s: the step must start before the run ends "
                               f"({duration:g} s)")
    check_outputs(outputs(args), inputs(args), force=args.force)
    if args.out is None:
        check_folder(args.out_dir, "--out-dir")
    if args.duration is not None:
        _check_resources(args.duration, args.out.parent if args.out is not None else args.out_dir,
                         rrd=args.rrd is not None)
    if args.duration is not None:
        try:
            check_ticks(args.protocol, round(args.duration / DT))
        except StationError as exc:  # the same refusal as run_step's, naming the option
            raise StationError(f"--duration {args.duration:g} s: {exc}") from None


def outputs(args) -> list[Output]:
    """The files ``station step`` writes: the log (--out), its figure beside it, --json, --rrd.

    Parameters
    ----------
    args : argparse.Namespace
        ``--out`` (None: a new default name, see :func:`station.experiment.default_log_path`),
        ``--json``, ``--rrd``.
    """
    figure = None if args.out is None or is_device(args.out) else ex.figure_path(args.out)
    return [Output("--out", args.out), Output("--out's figure", figure),
            Output("--json", args.json), Output("--rrd", args.rrd)]


def inputs(args) -> list[Input]:
    """The files ``station step`` reads: a compensator file, a reference log, a model file, station.toml.

    Parameters
    ----------
    args : argparse.Namespace
        ``--controller``, ``--reference``, ``--model`` and the settings file in use.
    """
    return [Input("--controller", args.controller), Input("--reference", runsetup.reference_path(args.reference)),
            *model_inputs(args), Input("station.toml", getattr(args, "_config", None))]


BYTES_PER_TICK_MEMORY = 200
"""Memory a run needs per tick, bytes, at its peak (the reference as floats for the loop,
latencies, the log read back for metrics and the figure), rounded up."""
BYTES_PER_TICK_DISK = 80
"""Disk a run log takes per tick, bytes (a row of our format is ~60)."""


def _check_resources(duration: float, folder: Path, rrd: bool = False) -> None:
    """Refuse a run this machine cannot hold in memory (with an .rrd recording: that too) or
    its log on disk (before it starts).

    Raises
    ------
    StationError
        Naming --duration, what the run needs and what there is.
    """
    ticks = round(duration / DT)
    need_mem, need_disk = ticks * (BYTES_PER_TICK_MEMORY + RRD_BYTES_PER_TICK * rrd), ticks * BYTES_PER_TICK_DISK
    available = _available_memory()
    if available is not None and need_mem > available:
        raise StationError(f"--duration {duration:g} s: {ticks} ticks need about {need_mem / 1e9:.1f} GB of memory; "
                           f"this machine has {available / 1e9:.1f} GB available")
    existing = Path(folder)
    while not existing.exists() and existing.parent != existing:
        existing = existing.parent
    free = shutil.disk_usage(existing).free
    if need_disk > free:
        raise StationError(f"--duration {duration:g} s: the run log would take about {need_disk / 1e9:.1f} GB; "
                           f"{existing} has {free / 1e9:.1f} GB free")


def _available_memory() -> int | None:
    """MemAvailable of /proc/meminfo, bytes (None where there is none)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def run(args) -> int:
    """Run the test; exit code 0 when it completed, 1 when it was stopped by a fault.

    Parameters
    ----------
    args : argparse.Namespace
        The controller, reference, port, simulated rig, link bounds and outputs; checked by
        :func:`check_args`.
    """
    check_args(args)
    chosen = runsetup.choose_controller(args.controller, args.kp, args.limit)  # before anything starts, once
    if chosen.note is not None:
        warn(chosen.note)
    design = runsetup.design_model_note(args.controller, args.model, args.port, args.elements)
    if design.note is not None:
        warn(design.note)
    if args.model is None and str(design.model).endswith(".toml"):  # the file's design model file: an input too
        check_outputs(outputs(args), [Input("--controller's design model", design.model)], force=args.force)
    if getattr(args, "_config", None):
        warn(f"settings from {args._config} (options given on the command line win)")
    sinks = []
    if args.rrd is not None or args.spawn:
        sinks.append(RerunSink(rrd_path=args.rrd, spawn=args.spawn, name="station step"))
    report = None
    try:
        with noting(lambda: "before the run started; nothing written"):  # in the loop, the run's outcome says it
            report = ex.run_step(port=args.port, protocol=args.protocol, controller=chosen.controller,
                                 amplitude=args.amplitude, duration=args.duration,
                                 step_time=args.step_time, reference=args.reference,
                                 out=args.out, sinks=sinks,
                                 kp=args.kp, limit=args.limit, soft_limit=args.soft_limit,
                                 timeout=args.timeout, baudrate=args.baud, force=args.force,
                                 limits=LinkLimits(timeout=args.timeout, max_lag=args.max_lag / 1000,
                                                   max_miss=args.max_miss, max_step=args.max_step),
                                 out_dir=args.out_dir, model=design.model, n_elements=args.elements, seed=args.seed,
                                 progress=not args.quiet and sys.stderr.isatty(),
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
