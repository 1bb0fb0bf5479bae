"""``station diagnose RUN... [--validate RUN...]``: what the model gets wrong on measured
runs, the effect that causes it, the extended model and its gain on runs it was not fitted
to (DESIGN.md "Model diagnosis contract")."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from station.commands.options import add_model_options, add_report_options, check_writable, check_writable_dir

NAME = "diagnose"
HELP = ("diagnose the model on measured runs: residual tests, the missing effect (fitted and judged on "
        "runs it was not fitted to), the extended model and its gain")


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station diagnose``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets RUN..., ``--validate``, ``--json``, ``--report``, ``--model``, ``--save-model``,
        ``--quiet``.
    """
    parser.add_argument("runs", type=Path, nargs="+", metavar="RUN", help="run logs the candidates are fitted on")
    parser.add_argument("--validate", type=Path, nargs="+", default=[], metavar="RUN",
                        help="runs they are judged on (default: leave-one-run-out over the RUNs, at least two)")
    add_report_options(parser, json="the diagnosis")
    parser.add_argument("--report", type=Path, default=None, metavar="DIR",
                        help="write DIR/report.html with its figures (also as PNG beside it)")
    add_model_options(parser, subject="the nominal model", elements=None, params=False)
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


def format_diagnosis(diag) -> str:
    """What ``station diagnose`` prints: the cause, the gain and the candidates table.

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned.
    """
    pct = lambda x: "n/a" if x is None else f"{x:.1f} %"  # noqa: E731
    lines = [f"model: {diag.nominal_model.name}; judged by {diag.validation}",
             f"cause: {diag.cause}" + (f"   (all accepted: {', '.join(diag.causes)})" if len(diag.causes) > 1 else ""),
             f"θ fit {pct(diag.baseline_fit.get('theta'))} -> {pct(diag.extended_fit.get('theta'))}, "
             f"a fit {pct(diag.baseline_fit.get('accel'))} -> {pct(diag.extended_fit.get('accel'))}, "
             f"θ RMS gain {diag.gain_pct:.1f} %",
             f"{'effect':<18} {'value':>12} {'unit':<15} {'θ gain':>8} {'cost gain':>9}  accepted"]
    for e in diag.effects:
        v = "inf" if not math.isfinite(e.value) else (f"{e.value:.0f}" if e.unit == "samples" else f"{e.value:.4g}")
        lines.append(f"{e.name:<18} {v:>12} {e.unit:<15} {e.gain_pct:>7.1f}% {e.cost_gain_pct:>8.1f}%  "
                     f"{'yes' if e.accepted else ''}")
    for r in diag.runs:
        m = r.metrics
        ov = "" if m is None else ("   overshoot rig/nominal/extended " +
                                   " / ".join(f"{m[k].overshoot_pct:.2f}" for k in ("rig", "nominal", "extended")) + " %")
        lines.append(f"  {r.file} ({r.role}): θ fit {pct(r.fit_nominal.get('theta'))} -> "
                     f"{pct(r.fit_extended.get('theta'))}, gain {r.gain_pct:.1f} %{ov}")
    lines.append(f"{diag.simulations} simulations in {diag.elapsed_s:.1f} s")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Diagnose; print the result; write the JSON, report and model file asked for.

    Parameters
    ----------
    args : argparse.Namespace
        The runs (``runs``, ``--validate``), the nominal ``--model``, the outputs (``--json``,
        ``--report``, ``--save-model``) and ``--quiet``.

    Returns
    -------
    int
        0 whenever the diagnosis ran to the end, whatever it found.

    Raises
    ------
    StationError
        One run without --validate, an unreadable log, a bad --model, unwritable output.
    """
    from station.diagnosis import diagnose
    from station.errors import StationError

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
