"""``station tune``: design a compensator of the rig's structure on a model, robust to what the
diagnosis doubts, verified on the simulated rig before it is written (DESIGN.md "Designing a
compensator on a model")."""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import warnings
from pathlib import Path

from station.analysis.metrics import NOT_SETTLED, STEP_INFO_BAND_PCT, settling_label
from station.commands.options import add_model_options, add_report_options, model_inputs, number
from station.design.robust import DEFAULT_DOUBT, DEFAULT_SAMPLES
from station.design.space import (DEFAULT_FILTER, DEFAULT_HUB_RATIO, DEFAULT_SHAPER, DEFAULT_TIP_RMS, FILTERS, SHAPERS,
                                  STRUCTURES)
from station.outputs import FORCE_HELP, Input, Output, Transaction, check_outputs
from station.rig import CLAMP, DAC_LIMIT, DEFAULT_SOFT_LIMIT, THESIS_STEPS

NAME = "tune"
HELP = ("design a compensator (p, lead, lead + accelerometer, optional reference shaper) on a model, robust over "
        "its doubt, verified on the simulated rig, written as a compensator file")

def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station tune``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets ``--model``, ``--controller``, ``--amplitude``, ``--limit``, ``--overshoot``,
        ``--shaper``, ``--filter``, ``--tip-rms``, ``--hub-ratio``, ``--robust``, ``--samples``, ``--jobs``,
        ``--scheduler``, ``--out``, ``--json``, ``--report``, ``--force``, ``--quiet``.
    """
    # light modules only: every command's parser is built at start-up (the design's
    # evaluation imports scipy.signal and python-control, most of a second)

    add_model_options(parser, "the model the compensator is designed on (its effects included), or a diagnosis "
                      "JSON (its extended model); without it, "
                      "the first --robust diagnosis JSON's extended model", subject="the design model",
                      elements=None, params=False)
    parser.add_argument("--controller", choices=STRUCTURES, default="lead-accel",
                        help="the compensator's structure (default lead-accel: Gth and the accelerometer filter Ga)")
    parser.add_argument("--amplitude", type=number(-DEFAULT_SOFT_LIMIT, DEFAULT_SOFT_LIMIT, unit="encoder counts", nonzero=True),
                        default=None, metavar="COUNTS",
                        help="the step it is designed for (default: the rig's experiment, p 50, lead 100, "
                             "lead-accel 200)")
    parser.add_argument("--limit", type=number(1, DAC_LIMIT, unit="DAC counts"), default=CLAMP, metavar="COUNTS",
                        help="the compensator's clamp, written into the file (default 200)")
    parser.add_argument("--overshoot", type=number(0, 100, unit="percent"), default=5.0, metavar="PCT",
                        help="largest overshoot on every model (default 5)")
    parser.add_argument("--shaper", choices=SHAPERS, default=DEFAULT_SHAPER,
                        help=f"reference shaper: none, ZV or ZVD of the model's first beam mode, two impulses "
                             f"optimized with the rest (opt), or those convolved with two more for the second beam "
                             f"mode (opt2) (default {DEFAULT_SHAPER})")
    parser.add_argument("--filter", choices=FILTERS, default=DEFAULT_FILTER,
                        help=f"what Gth holds beside its gain, searched at the beam's second mode (about 18 Hz): none, "
                             f"a notch or a second-order roll-off (default {DEFAULT_FILTER})")
    parser.add_argument("--tip-rms", type=number(0, 100, unit="x the thesis's"), default=DEFAULT_TIP_RMS,
                        metavar="RATIO",
                        help=f"largest tip residual RMS (the accelerometer from 0.6 s after the step to the run's "
                             f"end) on every model, as a multiple of the thesis's compensator's on the same model "
                             f"(at least the accelerometer's noise, 0.3 counts); 0: no bound on the tip "
                             f"(default {DEFAULT_TIP_RMS:g}: at least as quiet)")
    parser.add_argument("--hub-ratio", type=number(0, 10, unit="x the thesis's", nonzero=True),
                        default=DEFAULT_HUB_RATIO, metavar="RATIO",
                        help=f"the bar on the design model: its hub settling (2 %%) at most this multiple of the "
                             f"thesis's compensator's there, before the worst case over the set counts (default "
                             f"{DEFAULT_HUB_RATIO:g}: the hidden rigs' 0.6 with a margin; 1: no later than the "
                             f"thesis's)")
    parser.add_argument("--robust", nargs="+", default=[], metavar="FILE",
                        help="model files (or built-in names) and diagnosis JSONs (extended model, alternatives, "
                             "intervals) the design is judged on too")
    parser.add_argument("--samples", type=number(0, 1000, integer=True), default=DEFAULT_SAMPLES, metavar="N",
                        help=f"models drawn from the doubt (the diagnosis JSON's intervals, else {_doubt()}), "
                             f"besides its corners (default {DEFAULT_SAMPLES}; 0: neither, the model and the "
                             f"--robust files alone)")
    parser.add_argument("--jobs", type=number(1, 64, integer=True), default=None, metavar="N",
                        help="local worker processes (default: the CPU count)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="evaluate on a Dask distributed cluster (tcp://host:8786) instead of local processes")
    parser.add_argument("--out", type=Path, default=None, metavar="FILE.toml",
                        help="write the compensator file (station step --controller FILE runs it)")
    add_report_options(parser, json="the design, its metrics on the model and the set, and the thesis's")
    parser.add_argument("--report", type=Path, default=None, metavar="DIR",
                        help="write DIR/report.html with its figures (also as PNG beside it)")
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)
    parser.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def _doubt() -> str:
    """The default doubt in words (:data:`station.design.robust.DEFAULT_DOUBT`), for the help."""
    return ", ".join(f"{name} {lo:g}..{hi:g}" + ("x the model's" if how == "ratio" else "")
                     for name, how, lo, hi in DEFAULT_DOUBT)


def outputs(args: argparse.Namespace) -> list[Output]:
    """The files ``station tune`` writes: --out, --json and the report's files.

    Parameters
    ----------
    args : argparse.Namespace
        ``out``, ``json``, ``report``.
    """
    from station.design.report import REPORT_FILES  # lazy: start-up time (the design: scipy)

    report = [] if args.report is None else [Output("--report", args.report / name) for name in REPORT_FILES]
    return [Output("--out", args.out), Output("--json", args.json), *report]


def inputs(args: argparse.Namespace) -> list[Input]:
    """The files ``station tune`` reads: the model and every --robust file.

    Parameters
    ----------
    args : argparse.Namespace
        ``model``, ``robust``.
    """
    return model_inputs(args) + [Input("--robust", p) for p in args.robust]

def format_result(result) -> str:
    """What ``station tune`` prints: the design, its hub and tip on the model and at worst over
    the set beside the thesis's, every settling time named by its band.

    Parameters
    ----------
    result : station.design.result.TuneResult
    """
    from station.design.hold import held_summary  # lazy: start-up time (the design: scipy)

    def settle(x):
        return NOT_SETTLED if x is None else f"{x:.3f} s"

    def worst(values):
        return None if any(x is None for x in values) else max(values)

    s2 = settling_label(STEP_INFO_BAND_PCT)
    d = result.design_json()
    lines = [f"{result.space.structure} on {result.nominal.name!r}, step {result.amplitude:g}, "
             f"{len(result.robust.models)} model(s): " + ", ".join(f"{k} {v['value']:.4g}"
                                                                  for k, v in d["parameters"].items())]
    for name, figs in (("tuned", result.figures), ("thesis", result.baseline)):
        f = figs[0]
        lines.append(f"  {name:6s} model: overshoot {f.overshoot_pct:5.1f} %, hub {s2} {settle(f.settling_2pct_s)}, "
                     f"tip {s2} {settle(f.tip_settling_2pct_s)}, tip residual RMS {f.tip_residual_rms:.2f} "
                     f"(peak {f.tip_residual_peak:.0f});  worst over the set: overshoot "
                     f"{max(g.overshoot_pct for g in figs):5.1f} %, hub {s2} "
                     f"{settle(worst([g.settling_2pct_s for g in figs]))}, tip residual RMS "
                     f"{max(g.tip_residual_rms for g in figs):.2f}")
    m = result.margins
    tip = "" if result.tip_rms is None else f", the tip's residual RMS at most {result.tip_rms:g}x the thesis's"
    lines.append(f"  margins (model): gain {m.gain_margin_db:.1f} dB, phase {m.phase_margin_deg:.1f}°; requirements"
                 f"{tip}: {'met on every model' if d['feasible'] else f'met on {sum(result.met())} of {len(result.met())} models'}")
    if result.tradeoff is not None:
        c = result.tradeoff.points[result.tradeoff.chosen]
        lines.append(f"  worst over the set against the thesis's on the same model: hub {s2} {c.hub_ratio:.2f}x, tip "
                     f"residual RMS {c.tip_ratio:.2f}x; the trade-off front holds {len(result.tradeoff.front)} of "
                     f"{len(result.tradeoff.points)} designs (--report draws it)")
    note = held_summary(result.figures, result.model_requirements())["note"]
    if note:
        lines.append(f"  {note}")
    v = result.verification
    if v is not None:
        lines.append(f"  station step on the simulated rig: {v.reason}, overshoot {v.overshoot_pct:.1f} %, hub {s2} "
                     f"{settle(v.settling_2pct_s)}, tip residual RMS {v.tip_residual_rms:.2f}; log "
                     f"{'equals' if v.matches else 'DIFFERS from'} "
                     f"the simulation (max |Δθ| {v.max_abs_dtheta:g}, |Δv| {v.max_abs_dv:g})")
    lines.append(f"  {result.evaluations} evaluations (a design on a model) in {result.elapsed_s:.1f} s "
                 f"({result.executor})")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Check everything, design, verify, write what was asked for.

    Parameters
    ----------
    args : argparse.Namespace
        The options of :func:`configure`.

    Returns
    -------
    int
        0 when the design ran to the end (its JSON says whether every requirement was met).

    Raises
    ------
    StationError
        Bad input, before any work: an impossible value, an unreadable or unstable model, a
        JSON with no model, an output that exists (without ``--force``), repeats another or is
        an input; an unreachable scheduler.
    """
    from station.design.executor import check_scheduler  # lazy: start-up time (light: the design's package is PEP 562)

    if args.scheduler is not None:  # first: a wrong address is one line at once, before the design's imports
        check_scheduler(args.scheduler)
    # lazy: start-up time (the design: scipy, python-control)
    from station.design.tuning import check_request, tune
    from station.design.verify import verify

    structure = args.controller
    jobs = args.jobs if args.jobs is not None else max(1, min(os.cpu_count() or 1, 64))
    amplitude = THESIS_STEPS[structure] if args.amplitude is None else args.amplitude
    tip_rms = args.tip_rms or None  # 0: no bound on the tip
    check_request(structure, amplitude, args.limit, args.overshoot, args.shaper, args.samples, jobs, tip_rms,
                  args.filter, args.hub_ratio)
    check_outputs(outputs(args), inputs(args), force=args.force)
    progress = None if args.quiet else (lambda msg: print(f"tune: {msg}", file=sys.stderr, flush=True))
    out = args.out
    result = tune(model=args.model, structure=structure, amplitude=amplitude, limit=args.limit,
                  overshoot=args.overshoot, shaper=args.shaper, robust=args.robust, samples=args.samples,
                  jobs=jobs, scheduler=args.scheduler, out=out or Path("tuned.toml"), progress=progress,
                  tip_rms=tip_rms, filter=args.filter, hub_ratio=args.hub_ratio)
    with tempfile.TemporaryDirectory(prefix="station-tune-") as tmp:
        path = Path(tmp) / (out.name if out is not None else "tuned.toml")  # verified before it is written
        path.write_text(result.file.to_toml(), encoding="utf-8")
        if progress:
            progress("verifying: station step on the simulated rig serving the model")
        log = Path(tmp) / "verify-step.tsv"
        result.verification = verify(result.nominal, path, amplitude, log=log)
        verify_log = log.read_bytes() if log.is_file() else None
    print(format_result(result))
    for line in result.warnings():
        warnings.warn(line, RuntimeWarning, stacklevel=2)
    with Transaction() as tx:  # every file whole or none (station.outputs)
        if out is not None:
            tx.write(out, result.file.to_toml(), "the compensator file")
        if args.report is not None:
            from station.design.report import write_report  # lazy: start-up time (matplotlib)

            page = write_report(result, args.report, tx, verify_log)
        if args.json is not None:
            tx.write_json(args.json, result.to_json(out))
    if out is None:
        print("compensator file (use --out FILE.toml to write it):")
        print(result.file.to_toml(), end="")
    else:
        print(f"compensator: {out}")
    if args.report is not None:
        print(f"report: {page}")
    return 0
