"""``station diagnose RUN... [--validate RUN...]``: what the model gets wrong on measured
runs, the effect that causes it, the extended model and its gain on runs it was not fitted
to (DESIGN.md "Model diagnosis contract")."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

NAME = "diagnose"
HELP = ("diagnose the model on measured runs: residual tests, the missing effect (fitted and judged on "
        "runs it was not fitted to), the extended model and its gain")


def configure(parser: argparse.ArgumentParser) -> None:
    """Add the command's arguments to its subparser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
    """
    parser.add_argument("runs", type=Path, nargs="+", metavar="RUN", help="run logs the candidates are fitted on")
    parser.add_argument("--validate", type=Path, nargs="+", default=[], metavar="RUN",
                        help="runs they are judged on (default: leave-one-run-out over the RUNs, at least two)")
    parser.add_argument("--json", type=Path, default=None, metavar="OUT", help="write the diagnosis as JSON")
    parser.add_argument("--report", type=Path, default=None, metavar="DIR",
                        help="write DIR/report.html with its figures (also as PNG beside it)")
    parser.add_argument("--model", default=None, metavar="NAME|FILE",
                        help="the nominal model: a built-in model's name or a model file (default tmm-fit)")
    parser.add_argument("--save-model", type=Path, default=None, metavar="FILE",
                        help="write the extended model (nominal + accepted effects) as a model file")
    parser.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def _json_safe(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_json_safe(v) for v in x]
    return x


def _short(text: str, width: int = 240) -> str:
    return text if len(text) <= width else text[:width - 1] + "…"


def format_diagnosis(diag) -> str:
    """What ``station diagnose`` prints: the cause, the gain, what is still unexplained, the
    alternatives, the candidates table (with the accepted effects' 95 % intervals) and the runs.

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned.
    """
    pct = lambda x: "n/a" if x is None else f"{x:.1f} %"  # noqa: E731
    def num(x: float, unit: str) -> str:
        return "inf" if not math.isfinite(x) else (f"{x:.0f}" if unit == "samples" else f"{x:.4g}")

    u = diag.unexplained
    lines = [f"model: {diag.nominal_model.name}; judged by {diag.validation}",
             f"cause: {diag.cause}" + (f"   (all accepted: {', '.join(diag.causes)})" if len(diag.causes) > 1 else ""),
             f"θ fit {pct(diag.baseline_fit.get('theta'))} -> {pct(diag.extended_fit.get('theta'))}, "
             f"a fit {pct(diag.baseline_fit.get('accel'))} -> {pct(diag.extended_fit.get('accel'))}, "
             f"θ RMS gain {diag.gain_pct:.1f} %",
             "unexplained: " + ("no" if u is None or not u.flag else "yes - " + _short(u.evidence))]
    if diag.causes:
        lines.append("alternatives: " + ("none" if not diag.alternatives else "; ".join(
            f"{' + '.join(a.causes)} (cost ratio {a.cost_ratio:.3f}, θ gain {a.gain_pct:.1f} %)"
            for a in diag.alternatives)))
    lines.append(f"{'effect':<18} {'value':>12} {'unit':<15} {'θ gain':>8} {'cost gain':>9}  accepted  95 % interval")
    for e in diag.effects:
        iv = "" if e.interval is None else f"  {num(e.interval.lo, e.unit)} .. {num(e.interval.hi, e.unit)}"
        end = "  (at the end of its search range)" if e.at_range_end else ""
        lines.append(f"{e.name:<18} {num(e.value, e.unit):>12} {e.unit:<15} {e.gain_pct:>7.1f}% "
                     f"{e.cost_gain_pct:>8.1f}%  "
                     f"{'yes' if e.accepted else '   '}{iv}{end}".rstrip())
    for r in diag.runs:
        m = r.metrics
        ov = "" if m is None else ("   overshoot rig/nominal/extended " +
                                   " / ".join(f"{m[k].overshoot_pct:.2f}" for k in ("rig", "nominal", "extended")) + " %")
        lines.append(f"  {r.file} ({r.role}): θ fit {pct(r.fit_nominal.get('theta'))} -> "
                     f"{pct(r.fit_extended.get('theta'))}, gain {r.gain_pct:.1f} %{ov}")
    for note in diag.notes:
        lines.append(f"note: {note}")
    lines.append(f"{diag.simulations} simulations in {diag.elapsed_s:.1f} s")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Diagnose; print the result; write the JSON, report and model file asked for.

    Parameters
    ----------
    args : argparse.Namespace
        The options parsed by the subparser :func:`configure` filled.

    Returns
    -------
    int
        0 whenever the diagnosis ran to the end, whatever it found.

    Raises
    ------
    StationError
        One run without --validate, an unreadable log, a bad --model, unwritable output, the
        same run given twice (or as a RUN and a --validate run).
    """
    from station.diagnosis import diagnose
    from station.errors import StationError

    from station.commands.options import check_writable, check_writable_dir

    for option, path in (("--json", args.json), ("--save-model", args.save_model)):
        check_writable(path, option)
    check_writable_dir(args.report, "--report")
    progress = None if args.quiet else (lambda msg: print(f"diagnose: {msg}", file=sys.stderr, flush=True))
    diag = diagnose(args.runs, validate=args.validate, model=args.model, progress=progress)
    print(format_diagnosis(diag))
    if args.report is not None:
        from station.diagnosis.report import write_report

        print(f"report: {write_report(diag, args.report)}")
    try:
        if args.json is not None:
            args.json.write_text(json.dumps(_json_safe(diag.to_json()), indent=1))
        if args.save_model is not None:
            diag.extended_model.save(args.save_model)
            print(f"model: {args.save_model}")
    except OSError as exc:
        raise StationError(f"cannot write output: {exc}") from None
    return 0
