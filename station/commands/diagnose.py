"""``station diagnose RUN... [--validate RUN...]``: what the model gets wrong on measured
runs, the effect that causes it, the extended model and its gain on runs it was not fitted
to (DESIGN.md "Model diagnosis contract")."""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from pathlib import Path

from station.commands.options import add_force_option, add_model_options, add_report_options, model_inputs, number
from station.errors import StationError
from station.inputs import open_regular
from station.outputs import Input, Output, Transaction, check_outputs
from station.rig import DIAGNOSE_MAX_SAMPLES
from station.signals import noting

NAME = "diagnose"
HELP = ("diagnose the model on measured runs: residual tests, the missing effect (fitted and judged on "
        "runs it was not fitted to), the extended model and its gain")


SIMULATIONS_PER_FOLD_RUN = 2400
"""Simulations of the whole vocabulary's diagnosis per run simulated in each fold (every
evaluation simulates a fold's fit and validation runs): leave-one-run-out on n runs costs about
this × n × n. Counted on the rig's thesis logs with the lookahead, the last look and the swap:
2 runs 11 007 (2752 × 4), 3 runs 24 981 (2776 × 9), 4 runs 33 076 (2067 × 16); how many steps
pay moves it more than the runs' length does."""
SECONDS_PER_SIMULATION = 0.8e-3
"""CPU time of a simulation besides its samples (building the model with its effects), s."""
SECONDS_PER_SAMPLE = 0.25e-6
"""CPU time of one sample of one simulation, s. This and :data:`SECONDS_PER_SIMULATION`
are fitted to the diagnosis's timings (docs/benchmarks.md, "The diagnosis")."""


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station diagnose``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets RUN..., ``--validate``, ``--json``, ``--report``, ``--model``, ``--save-model``,
        ``--force``, ``--max-samples``, ``--jobs``, ``--quiet``.
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
    add_force_option(parser)
    parser.add_argument("--max-samples", type=number(50, 10**9, integer=True), default=DIAGNOSE_MAX_SAMPLES, metavar="N",
                        help=f"most samples of all runs together (RUNs and --validate runs); longer logs are "
                             f"refused before they are read: the diagnosis's time grows with their length times "
                             f"the number of runs (default {DIAGNOSE_MAX_SAMPLES}: 200 s of the rig's data, a few minutes "
                             f"of computing with four runs)")
    parser.add_argument("--jobs", type=number(1, 64, integer=True), default=None, metavar="N",
                        help="local worker processes fitting candidates at once (default: the CPU count; "
                             "the same answer with any N)")
    parser.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def count_samples(path: Path) -> int:
    """A log's rows counted from its bytes, without parsing: its lines that do not start with
    ``#`` (so the rig's 2014 column-name line counts as one).

    Parameters
    ----------
    path : Path
        A run log.

    Raises
    ------
    StationError
        Not a regular file (a FIFO would block, ``/dev/zero`` never ends), missing or unreadable
        (:func:`station.inputs.open_regular`).
    """
    lines = comments = 0
    last = b"\n"
    try:
        with open_regular(path, "run log") as fh:
            while chunk := fh.read(1 << 20):
                lines += chunk.count(b"\n")
                comments += chunk.count(b"\n#") + (last == b"\n" and chunk[:1] == b"#")
                last = chunk[-1:]
    except OSError as exc:
        raise StationError(f"{path}: cannot read the run log: {exc.strerror or exc}", file=path) from None
    return max(0, lines + (last != b"\n") - comments)


def _human(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min" if seconds < 7200 else \
        f"{seconds / 3600:.1f} h"


def plan(runs, validate, max_samples: int) -> str:
    """Refuse logs longer than the bound before they are read; else say what the diagnosis will cost.

    Parameters
    ----------
    runs, validate : sequence of Path
        The RUNs and the ``--validate`` runs.
    max_samples : int
        ``--max-samples``.

    Returns
    -------
    str
        One line: runs, samples, the simulations expected and their computing time here.

    Raises
    ------
    StationError
        The runs hold more than ``max_samples`` samples together (names the longest, the
        option and what it would cost).
    """
    counts = {p: count_samples(p) for p in list(runs) + list(validate)}
    total = sum(counts.values())
    folds = 1 if validate else len(runs)
    simulations = SIMULATIONS_PER_FOLD_RUN * folds * len(counts)  # each fold simulates all its runs
    seconds = simulations * (SECONDS_PER_SIMULATION + total / max(1, len(counts)) * SECONDS_PER_SAMPLE)
    if total > max_samples:
        longest = max(counts, key=counts.get)
        raise StationError(f"--max-samples {max_samples}: {longest} holds about {counts[longest]} samples "
                           f"({total} in all {len(counts)} runs), refused before reading them; the diagnosis would "
                           f"take about {_human(seconds)} of computing here: give --max-samples {total} to run it anyway")
    return (f"{len(counts)} run{'s' if len(counts) > 1 else ''}, {total} samples (--max-samples {max_samples}): "
            f"about {simulations} simulations, {_human(seconds)} of computing here")


SENTENCE_END = re.compile(r"(?<=[.!?])\s+(?=\S)")
"""Where a sentence ends inside a text: after its full stop, before the next sentence."""


def whole_sentences(text: str, width: int = 240) -> str:
    """``text``, or as many of its first sentences as fit in ``width`` characters, never cut
    inside one (the first is kept whole however long); " (…)" says that more followed.

    Parameters
    ----------
    text : str
        Prose: sentences ending in ".", "!" or "?".
    width : int
        Characters to aim for.

    Returns
    -------
    str
        A prefix of ``text`` ending at a sentence end (plus " (…)"), or ``text`` itself.
    """
    if len(text) <= width:
        return text
    ends = [m.start() for m in SENTENCE_END.finditer(text)]
    fit = [e for e in ends if e <= width]
    cut = fit[-1] if fit else (ends[0] if ends else len(text))
    return text if cut >= len(text) else text[:cut] + " (…)"


CANDIDATE_COLUMNS = ("effect", "value (alone)", "unit", "θ gain (alone)", "cost gain (alone)", "value (extended)",
                     "95 % interval (extended)", "accepted")
"""The candidates table's columns, as the HTML report's: "alone" is the nominal model plus this
effect only (fitted on the fit runs, its gains judged on held-out data); "extended" is its value
fitted jointly with the other accepted effects and that value's 95 % interval (accepted effects
only)."""


def _num(x: float, unit: str) -> str:
    return "inf" if not math.isfinite(x) else (f"{x:.0f}" if unit == "samples" else f"{x:.4g}")


def candidate_rows(diag) -> list[str]:
    """The candidates table ``station diagnose`` and ``station identify`` print: a header of
    :data:`CANDIDATE_COLUMNS`, then one line per effect, every cell read from its
    :class:`~station.diagnosis.answer.result.EffectResult` (the alone fit's value and gains
    beside the extended model's value and interval, never one as the other); an effect that an
    accepted one holds (a breakaway's sliding level) shows its value in the extended model and
    "held" (the identified model lists it).

    Parameters
    ----------
    diag : Diagnosis
        Its ``effects``.

    Returns
    -------
    list of str
        The header and the rows, aligned.
    """
    cells = []
    held = diag.held
    for e in diag.effects:
        alone = e.value_alone if e.accepted and math.isfinite(e.value_alone) else e.value
        # an effect an accepted one holds (a breakaway's sliding level) is in the model at its value there
        ext = _num(e.value, e.unit) if e.accepted else _num(held[e.name], e.unit) if e.name in held else "-"
        mark = "yes" if e.accepted else "held" if e.name in held else "no"
        # an interval's ends as found, also in samples (rounded, 0.6 .. 1.4 would read 1 .. 1: narrow)
        iv = "-" if e.interval is None else f"{_num(e.interval.lo, '')} .. {_num(e.interval.hi, '')}"
        end = "  (at the end of its search range)" if e.at_range_end else ""
        cells.append((e.name, _num(alone, e.unit), e.unit, f"{e.gain_pct:.1f} %", f"{e.cost_gain_pct:.1f} %", ext, iv,
                      mark + end))
    return align_columns(CANDIDATE_COLUMNS, cells, right=CANDIDATE_RIGHT)


CANDIDATE_RIGHT = frozenset({1, 3, 4, 5})
"""The candidates table's columns of numbers (right-aligned)."""


def align_columns(head, rows, right=frozenset(), gap: str = " ") -> list[str]:
    """A table's lines, every column as wide as its widest cell (the header's included), so no
    cell pushes the ones after it out of their column; numbers (``right``) right-aligned, the
    last column as it is.

    Parameters
    ----------
    head : sequence of str
        The column names.
    rows : sequence of sequence of str
        The cells, one sequence per row, as many as ``head``.
    right : set of int
        Indices of the right-aligned columns.
    gap : str
        Between two columns.
    """
    rows = [tuple(r) for r in rows]
    width = [max([len(head[i])] + [len(r[i]) for r in rows]) for i in range(len(head))]

    def line(cells) -> str:
        last = len(cells) - 1
        return gap.join(c if i == last else c.rjust(width[i]) if i in right else c.ljust(width[i])
                        for i, c in enumerate(cells)).rstrip()

    return [line(tuple(head))] + [line(r) for r in rows]


def format_diagnosis(diag) -> str:
    """What ``station diagnose`` prints: the cause, the gain, what is still unexplained, the
    alternatives, the candidates table (with the accepted effects' 95 % intervals) and the runs.

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned.
    """
    from station.logged.sensors import fault_text  # lazy: start-up time (the log audit: numpy)

    pct = lambda x: "n/a" if x is None else f"{x:.1f} %"  # noqa: E731

    u = diag.unexplained
    lines = diag.audit_lines()
    faults = diag.decided_faults
    lines += [f"model: {diag.nominal_model.name}" + (
        " with the sensor faults decided from the data (" + ", ".join(fault_text(k, v) for k, v in faults.items()) + ")"
        if faults else "") + f"; judged by {diag.validation}",
             f"cause: {diag.cause}" + (f"   (causes: {', '.join(diag.causes)})" if len(diag.causes) > 1 else ""),
             f"θ fit {pct(diag.baseline_fit.get('theta'))} -> {pct(diag.extended_fit.get('theta'))}, "
             f"a fit {pct(diag.baseline_fit.get('accel'))} -> {pct(diag.extended_fit.get('accel'))}, "
             f"θ RMS gain {diag.gain_pct:.1f} % on runs not used to fit ({diag.validation})",
             "unexplained: " + ("no" if u is None or not u.flag else "yes - " + whole_sentences(u.evidence)
                                + f" ({diag.prediction_words()})")]
    if diag.accepted:
        lines.append("alternatives: " + ("none" + (" (beside the sensor wiring the data cannot decide, above)"
                                                  if diag.wiring_alike else "") if not diag.alternatives else "; ".join(
            f"{' + '.join(a.causes)} (cost ratio {a.cost_ratio:.3f}, θ gain {a.gain_pct:.1f} %)"
            for a in diag.alternatives)))
    lines += candidate_rows(diag)
    for r in diag.runs:
        m = r.metrics
        ov = "" if m is None else ("   overshoot rig/nominal/extended " +
                                   " / ".join(f"{m[k].overshoot_pct:.2f}" for k in ("rig", "nominal", "extended")) + " %")
        role = "fitted on: in-sample" if r.role == "fit" else "not used to fit"
        lines.append(f"  {r.file} ({role}): θ fit {pct(r.fit_nominal.get('theta'))} -> "
                     f"{pct(r.fit_extended.get('theta'))}, gain {r.gain_pct:.1f} %{ov}")
    for note in diag.notes:
        lines.append(f"note: {note}")
    lines.append(f"{diag.simulations} simulations in {diag.elapsed_s:.1f} s")
    return "\n".join(lines)


def outputs(args: argparse.Namespace) -> list[Output]:
    """Every file ``station diagnose`` writes: --json, --save-model and the report's files.

    Parameters
    ----------
    args : argparse.Namespace
        ``runs``, ``--validate`` (the report names its figures after them), ``--json``,
        ``--save-model``, ``--report``.
    """
    from station.diagnosis.answer.report import report_files  # lazy: start-up time (matplotlib)

    report = [] if args.report is None else [
        Output("--report", args.report / name) for name in report_files([p.name for p in args.runs + args.validate])]
    return [Output("--json", args.json), Output("--save-model", args.save_model), *report]


def run(args: argparse.Namespace) -> int:
    """Diagnose; print the result; write the JSON, report and model file asked for, together.

    Parameters
    ----------
    args : argparse.Namespace
        The runs (``runs``, ``--validate``), the nominal ``--model``, the outputs (``--json``,
        ``--report``, ``--save-model``, ``--force``), ``--max-samples`` and ``--quiet``.

    Returns
    -------
    int
        0 whenever the diagnosis ran to the end, whatever it found.

    Raises
    ------
    StationError
        One run without --validate, an unreadable log, runs longer than --max-samples, a bad
        --model, the same run given twice (or as a RUN and a --validate run); an output that is
        an input or another output, exists (without ``--force``) or cannot be written.
    """
    from station.diagnosis import diagnose  # lazy: start-up time (the diagnosis: scipy)

    check_outputs(outputs(args), [Input("RUN", p) for p in args.runs] +
                  [Input("--validate", p) for p in args.validate] + model_inputs(args), force=args.force)
    cost = [plan(args.runs, args.validate, args.max_samples)]  # said with the first step: the runs are readable
    last = ["reading the runs"]

    def progress(msg: str) -> None:
        last[0] = msg
        if not args.quiet:
            for line in cost + [msg]:
                print(f"diagnose: {line}", file=sys.stderr, flush=True)
            cost.clear()
    with noting(lambda: f"the diagnosis was at: {last[0]}; nothing written"):
        diag = diagnose(args.runs, validate=args.validate, model=args.model, progress=progress,
                        workers=args.jobs or min(os.cpu_count() or 1, 64))
    print(format_diagnosis(diag))
    if args.save_model is not None and diag.accepted and diag.gain_pct <= 0:
        print(f"diagnose: warning: --save-model {args.save_model}: {diag.prediction_words()}; "
              f"simulate with it knowing that", file=sys.stderr)
    with Transaction() as tx:
        if args.report is not None:
            from station.diagnosis.answer.report import write_report  # lazy: start-up time (matplotlib)

            page = write_report(diag, args.report, tx)
        if args.json is not None:
            tx.write_json(args.json, diag.to_json())
        if args.save_model is not None:
            tx.write(args.save_model, diag.extended_model.to_toml(), "the model")
    if args.report is not None:
        print(f"report: {page}")
    if args.save_model is not None:
        print(f"model: {args.save_model}")
    return 0
