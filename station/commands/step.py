"""``station step``: a step test on the rig or the simulated rig."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from station import DT
from station import experiment as ex
from station.errors import StationError
from station.commands.options import check_writable, check_writable_dir, number, warn
from station.link import LinkLimits
from station.protocol import PROTOCOLS, check_ticks

MAX_DURATION_S = (2**32 - 1) * DT
"""Longest run v1 can count (START's n_ticks is a u32), s."""
MAX_AMPLITUDE = 32767.0
"""Largest step height, counts (the legacy protocol's θ word is int16; the soft limit bounds it further)."""

NAME = "step"
HELP = ("run a step test (default: lead compensator, 100 counts, on the built-in simulated rig); "
        "also pulse, swept-sine or file references")


def configure(parser) -> None:
    """Add ``station step``'s options to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
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
    parser.add_argument("--protocol", choices=PROTOCOLS, default="v1", help="wire protocol (default v1)")
    parser.add_argument("--model", default=None, metavar="NAME|FILE",
                        help="simulated rig only: its model, a built-in name or a model file (sim://?model=...)")
    parser.add_argument("--elements", type=number(1, 100, integer=True), default=None, metavar="N",
                        help="simulated rig only: FEM element count (sim://?elements=N)")
    parser.add_argument("--seed", type=number(0, 2**32 - 1, integer=True), default=None, metavar="N",
                        help="simulated rig only: sensor noise seed (sim://?seed=N)")
    parser.add_argument("--baud", type=number(300, 12_000_000, integer=True), default=None, help="baud rate (default 921600 for v1, 115200 legacy)")
    parser.add_argument("--timeout", type=number(1e-3, 60.0, unit="s"), default=ex.DEFAULT_TIMEOUT, metavar="S",
                        help="longest wait for a sample before stopping safely (default 0.1 s)")
    parser.add_argument("--soft-limit", type=number(1, 32767, unit="encoder counts"), default=ex.DEFAULT_SOFT_LIMIT,
                        metavar="COUNTS",
                        help="stop safely when |θ| exceeds this (default 2048 = two revolutions)")
    parser.add_argument("--max-lag", type=number(0, 100, integer=True), default=LinkLimits.max_lag, metavar="TICKS",
                        help="stop (reason lag) when more samples than this are already waiting when a command "
                             "is due: never drive the motor from stale samples (default 2)")
    parser.add_argument("--max-miss", type=number(0, 99, integer=True), default=LinkLimits.max_miss, metavar="TICKS",
                        help="stop (reason sequence) when more of the last 100 ticks than this were dropped, "
                             "stale, duplicated or late (default 10)")
    parser.add_argument("--max-step", type=number(1.0, 10000.0), default=LinkLimits.max_step, metavar="COUNTS",
                        help="largest plausible encoder change per tick; more stops the run (reason sequence; "
                             "default 40)")
    parser.add_argument("--out", type=Path, default=None, metavar="FILE",
                        help="run log (default runs/step-<controller>-<UTC time with ms>.tsv); never overwritten "
                             "without --force. The run's figure goes beside it as <log stem>.png")
    parser.add_argument("--force", action="store_true", help="overwrite an existing --out file")
    parser.add_argument("--quiet", action="store_true",
                        help="no live progress line on stderr (it is shown only when stderr is a terminal)")
    parser.add_argument("--json", type=Path, default=None, metavar="FILE", help="write metrics and timing as JSON")
    parser.add_argument("--out-dir", type=Path, default=Path("runs"), metavar="DIR",
                        help="folder of the default run log names (default runs)")
    viz = parser.add_mutually_exclusive_group()
    viz.add_argument("--rrd", type=Path, default=None, metavar="FILE", help="record the run to a rerun .rrd file")
    viz.add_argument("--spawn", action="store_true", help="stream the run to a rerun viewer")
    _apply_config(parser)


def _apply_config(parser) -> None:
    """Defaults from ``station.toml`` (:mod:`station.config`), each checked by its option's
    own type; command-line options win. A bad file is reported when the command runs."""
    from station.config import config_path, load_config

    path = None
    try:
        path = config_path()
        settings = load_config(path)
        actions = {a.dest: a for a in parser._actions}
        defaults = {}
        for key, value in settings.items():
            action = actions[key]
            if isinstance(value, bool) or not isinstance(value, (str, int, float)):
                raise StationError(f"{path}: {key}: expected a string or a number, got {value!r}")
            text = str(value)
            try:
                converted = action.type(text) if action.type is not None else text
            except (argparse.ArgumentTypeError, ValueError, TypeError) as exc:
                raise StationError(f"{path}: {key} = {value!r}: {exc}") from None
            if action.choices is not None and converted not in action.choices:
                raise StationError(f"{path}: {key} = {value!r}: expected one of {', '.join(action.choices)}")
            defaults[key] = converted
        parser.set_defaults(**defaults, _config=str(path) if path else None, _config_error=None)
    except StationError as exc:
        parser.set_defaults(_config=str(path) if path else None, _config_error=str(exc))


def sim_port(port: str, model=None, elements=None, seed=None) -> str:
    """``port`` with ``--model``/``--elements``/``--seed`` added as sim:// URL options.

    Parameters
    ----------
    port : str
        The ``--port`` value.
    model, elements, seed : str or int, optional
        ``--model``, ``--elements``, ``--seed`` (None: not given).

    Raises
    ------
    StationError
        One of them given for a port that is not ``sim://``.
    """
    import urllib.parse

    extra = {k: str(v) for k, v in (("model", model), ("elements", elements), ("seed", seed)) if v is not None}
    if not extra:
        return port
    if not port.lower().startswith("sim://"):
        raise StationError(f"--{next(iter(extra))}: only for the simulated rig (--port sim://...), not {port!r}")
    query = urllib.parse.urlencode(extra)
    return port + ("&" if "?" in port else "?") + query


def check_args(args) -> None:
    """Refuse options that do not apply or do not fit together, before anything starts.

    Ranges of single options are argparse's (:mod:`station.commands.options`); this
    checks what depends on the controller and the reference, and the output paths.

    Parameters
    ----------
    args : argparse.Namespace
        The options parsed by the subparser :func:`configure` filled.

    Raises
    ------
    StationError
        One line naming the option.
    """
    if getattr(args, "_config_error", None):
        raise StationError(args._config_error)
    controller = str(args.controller)
    builtin_ref = args.reference in ex.REFERENCES
    port = str(args.port)
    if "://" not in port and not Path(port).exists():
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
        duration = ex.DEFAULT_DURATION if args.duration is None else args.duration
        if args.step_time >= duration:
            raise StationError(f"--step-time {args.step_time:g} s: the step must start before the run ends "
                               f"({duration:g} s)")
    if args.duration is not None:
        _check_resources(args.duration, args.out.parent if args.out is not None else args.out_dir)
    if args.duration is not None:
        try:
            check_ticks(args.protocol, round(args.duration / DT))
        except StationError as exc:  # the same refusal as run_step's, naming the option
            raise StationError(f"--duration {args.duration:g} s: {exc}") from None
    if args.limit is not None and controller.endswith(".toml"):
        file_limit = _file_limit(controller)
        if file_limit is not None:
            warn(f"--limit {args.limit:g} is not used: {controller} sets limit = {file_limit} (the file wins)")
    check_writable(args.out, "--out", overwrite=args.force)
    if args.out is None:
        check_writable_dir(args.out_dir, "--out-dir")
    check_writable(args.json, "--json")
    check_writable(args.rrd, "--rrd")


BYTES_PER_TICK_MEMORY = 200
"""Memory a run needs per tick, bytes, at its peak (the reference as floats for the loop,
latencies, the log read back for metrics and the figure), rounded up."""
BYTES_PER_TICK_DISK = 80
"""Disk a run log takes per tick, bytes (a row of our format is ~60)."""


def _check_resources(duration: float, folder: Path) -> None:
    """Refuse a run this machine cannot hold in memory or its log on disk (before it starts).

    Raises
    ------
    StationError
        Naming --duration, what the run needs and what there is.
    """
    import shutil

    ticks = round(duration / DT)
    need_mem, need_disk = ticks * BYTES_PER_TICK_MEMORY, ticks * BYTES_PER_TICK_DISK
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


def _file_limit(path: str):
    """The ``limit`` a compensator file sets, or None (unreadable files are the loader's to report)."""
    import tomllib

    try:
        return tomllib.loads(Path(path).read_text(encoding="utf-8")).get("limit")
    except (OSError, ValueError):
        return None


def run(args) -> int:
    """Run the test; exit code 0 when it completed, 1 when it was stopped by a fault.

    Parameters
    ----------
    args : argparse.Namespace
        The options parsed by the subparser :func:`configure` filled.
    """
    limits = _limits(args)
    check_args(args)
    if getattr(args, "_config", None):
        warn(f"settings from {args._config} (options given on the command line win)")
    args.port = sim_port(args.port, args.model, args.elements, args.seed)
    sinks = []
    if args.rrd is not None or args.spawn:
        from station.viz import RerunSink

        sinks.append(RerunSink(rrd_path=args.rrd, spawn=args.spawn, name="station step"))
    try:
        report = ex.run_step(port=args.port, protocol=args.protocol, controller=args.controller,
                             amplitude=args.amplitude, duration=args.duration,
                             step_tick=int(round(args.step_time / DT)), reference=args.reference,
                             out=args.out, sinks=sinks,
                             kp=args.kp, limit=args.limit, soft_limit=args.soft_limit,
                             timeout=args.timeout, baudrate=args.baud, limits=limits, force=args.force,
                             out_dir=args.out_dir,
                             progress=not args.quiet and sys.stderr.isatty())
    finally:
        for sink in sinks:
            sink.close()
    print(ex.format_report(report))
    if report.figure_path is not None:
        print(f"figure: {report.figure_path}")
    if args.rrd is not None:
        print(f"rerun recording: {args.rrd}")
    if args.json is not None:
        try:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps(report.to_json(), indent=1) + "\n")
        except OSError as exc:
            raise StationError(f"{args.json}: cannot write the JSON report: {exc.strerror or exc}") from None
    return report.result.outcome.exit_code


def _limits(args) -> LinkLimits:
    """The link's fail-safe bounds from the options, each checked before anything starts."""
    checks = (("--timeout", args.timeout, 1e-3, 60.0), ("--max-lag", args.max_lag, 0, 100),
              ("--max-miss", args.max_miss, 0, 99), ("--max-step", args.max_step, 1.0, 10000.0))
    for option, value, low, high in checks:
        if not (math.isfinite(value) and low <= value <= high):
            raise StationError(f"{option} {value}: expected a number in [{low:g}, {high:g}]")
    return LinkLimits(timeout=args.timeout, max_lag=args.max_lag, max_miss=args.max_miss, max_step=args.max_step)
