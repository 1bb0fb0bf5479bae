"""``station step``: a step test on the rig or the simulated rig."""

from __future__ import annotations

import json
import math
from pathlib import Path

from station import DT
from station import experiment as ex
from station.errors import StationError
from station.link import LinkLimits

NAME = "step"
HELP = ("run a step test (default: lead compensator, 100 counts, on the built-in simulated rig); "
        "also pulse, swept-sine or file references")


def configure(parser) -> None:
    """Add ``station step``'s options to ``parser``."""
    parser.add_argument("--controller", default=ex.DEFAULT_CONTROLLER,
                        help="p, lead, lead-accel, open-loop or a compensator FILE.toml (default lead)")
    parser.add_argument("--kp", type=float, default=2.0, help="P gain for --controller p (default 2)")
    parser.add_argument("--limit", type=float, default=200.0, help="controller clamp, ±DAC counts (default 200)")
    parser.add_argument("--amplitude", type=float, default=ex.DEFAULT_AMPLITUDE, metavar="COUNTS",
                        help="step height in encoder counts (default 100)")
    parser.add_argument("--duration", type=float, default=None, metavar="S",
                        help="run length (default 2 s; swept sine 22 s; a file reference: its length)")
    parser.add_argument("--reference", default="step", metavar="KIND",
                        help="step (default), pulse (open loop, 0.1 s), swept-sine, or FILE[:COLUMN] "
                             "of a run log (e.g. a rig log's u)")
    parser.add_argument("--step-time", type=float, default=ex.DEFAULT_STEP_TICK * DT, metavar="S",
                        help="when the step starts (default 0.02 s = tick 10)")
    parser.add_argument("--port", default=ex.DEFAULT_PORT, metavar="URL",
                        help="port path or pyserial URL (default sim://, the simulated rig)")
    parser.add_argument("--protocol", choices=("v1", "legacy"), default="v1", help="wire protocol (default v1)")
    parser.add_argument("--model", default=None, metavar="NAME|FILE",
                        help="simulated rig only: its model, a built-in name or a model file (sim://?model=...)")
    parser.add_argument("--elements", type=int, default=None, metavar="N",
                        help="simulated rig only: FEM element count (sim://?elements=N)")
    parser.add_argument("--seed", type=int, default=None, metavar="N",
                        help="simulated rig only: sensor noise seed (sim://?seed=N)")
    parser.add_argument("--baud", type=int, default=None, help="baud rate (default 921600 for v1, 115200 legacy)")
    parser.add_argument("--timeout", type=float, default=ex.DEFAULT_TIMEOUT, metavar="S",
                        help="longest wait for a sample before stopping safely (default 0.1 s)")
    parser.add_argument("--soft-limit", type=float, default=ex.DEFAULT_SOFT_LIMIT, metavar="COUNTS",
                        help="stop safely when |θ| exceeds this (default 2048 = two revolutions)")
    parser.add_argument("--max-lag", type=int, default=LinkLimits.max_lag, metavar="TICKS",
                        help="stop (reason lag) when more samples than this are already waiting when a command "
                             "is due: never drive the motor from stale samples (default 2, range 0..100)")
    parser.add_argument("--max-miss", type=int, default=LinkLimits.max_miss, metavar="TICKS",
                        help="stop (reason sequence) when more of the last 100 ticks than this were dropped, "
                             "stale, duplicated or late (default 10, range 0..99)")
    parser.add_argument("--max-step", type=float, default=LinkLimits.max_step, metavar="COUNTS",
                        help="largest plausible encoder change per tick; more stops the run (reason sequence; "
                             "default 40, range 1..10000)")
    parser.add_argument("--out", type=Path, default=None, metavar="FILE", help="run log (default runs/step-*.tsv)")
    parser.add_argument("--json", type=Path, default=None, metavar="FILE", help="write metrics and timing as JSON")
    viz = parser.add_mutually_exclusive_group()
    viz.add_argument("--rrd", type=Path, default=None, metavar="FILE", help="record the run to a rerun .rrd file")
    viz.add_argument("--spawn", action="store_true", help="stream the run to a rerun viewer")


def sim_port(port: str, model=None, elements=None, seed=None) -> str:
    """``port`` with ``--model``/``--elements``/``--seed`` added as sim:// URL options.

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


def run(args) -> int:
    """Run the test; exit code 0 when it completed, 1 when it was stopped by a fault."""
    limits = _limits(args)
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
                             timeout=args.timeout, baudrate=args.baud, limits=limits)
    finally:
        for sink in sinks:
            sink.close()
    print(ex.format_report(report))
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
