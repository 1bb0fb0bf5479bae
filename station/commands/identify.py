"""``station identify --port URL``: identify a rig by experiments on the device itself (DESIGN.md
"Identifying a rig"): the thesis's four, a diagnosis, then while the diagnosis leaves rivals
the experiment that best separates them, up to ``--budget`` designed experiments."""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from station.commands.options import (add_link_options, add_model_options, add_protocol_option, add_report_options,
                                      check_port, config_error, link_limits, model_inputs, number, warn)
from station.commands.diagnose import format_diagnosis
from station.config import apply_config
from station.errors import StationError
from station.inputs import is_folder
from station.outputs import DEFAULT_OUT_DIR, FORCE_HELP, Output, Transaction, check_folder, check_outputs
from station.plant.model import as_model
from station.rig import CLAMP, DAC_LIMIT

NAME = "identify"
HELP = ("identify the rig on the device: the thesis's four experiments, a diagnosis, then the experiments that "
        "best separate what it leaves open, each a logged step run")


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station identify``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets ``--port``, ``--protocol``, ``--model``, ``--budget``, the limits, the outputs
        (``--out-dir``, ``--json``, ``--report``, ``--save-model``, ``--force``) and ``--quiet``.
    """
    parser.add_argument("--port", default="sim://", metavar="URL",
                        help="the device: port path or pyserial URL (default sim://, the simulated rig; "
                             "sim://?model=FILE serves a model file)")
    add_protocol_option(parser)
    add_model_options(parser, subject="the nominal model the diagnoses extend", elements=None, params=False)
    # the default is station.diagnosis.identify.loop.DEFAULT_BUDGET, not imported here: the diagnosis
    # loads scipy and numba, and every command's start-up builds this parser
    parser.add_argument("--budget", type=number(0, 100, integer=True), default=None, metavar="N",
                        help="designed experiments after the thesis's four, at most (default 8; 0: the four only)")
    parser.add_argument("--limit", type=number(1, DAC_LIMIT, unit="DAC counts"), default=CLAMP, metavar="COUNTS",
                        help="the controllers' clamp, ±DAC counts (default 200, the rig's)")
    add_link_options(parser, soft_limit_help="; designed experiments keep the predicted |θ| within 80 %% of it")
    parser.add_argument("--out-dir", type=Path, default=None, metavar="DIR",
                        help="folder of the experiments' logs, NN-<experiment>.tsv with their figures (default "
                             "identify-<UTC time> in station.toml's out_dir, else in runs/); a folder that holds "
                             "files needs --force")
    add_report_options(parser, json="the diagnosis and the experiments")
    parser.add_argument("--report", type=Path, default=None, metavar="DIR",
                        help="write DIR/identify.html (the experiments, why each was run, predicted vs measured) "
                             "and DIR/report.html (the last diagnosis), with PNGs")
    parser.add_argument("--save-model", type=Path, default=None, metavar="FILE",
                        help="write the identified model (nominal + accepted effects) as a model file")
    parser.add_argument("--force", action="store_true", help=FORCE_HELP + "; write into an --out-dir that holds files")
    parser.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    apply_config(parser, skip=("out_dir",))  # station.toml's bounds, as station step's (its out_dir: the parent)


EXPERIMENT_NAME = re.compile(r"^\d{2,}-")
"""The names identify gives the files of its experiments in ``--out-dir``: ``NN-<experiment>.tsv``,
its figure ``.png`` and a designed reference ``.u.tsv`` (the experiments are designed as it goes,
so the names are known by this pattern only)."""


def outputs(args: argparse.Namespace) -> list[Output]:
    """The files ``station identify`` writes besides the experiments' logs: --json,
    --save-model and the report's pages (its figures are named per experiment).

    Parameters
    ----------
    args : argparse.Namespace
        ``--json``, ``--save-model``, ``--report``.
    """
    report = [] if args.report is None else [Output("--report", args.report / name)
                                             for name in ("identify.html", "report.html")]
    return [Output("--json", args.json), Output("--save-model", args.save_model), *report]


def experiments_folder(args: argparse.Namespace) -> Path:
    """The experiments' folder, checked before any run: ``--out-dir`` (a folder that holds
    files needs ``--force``) or a new one under runs/.

    Parameters
    ----------
    args : argparse.Namespace
        ``--out-dir``, ``--force``.

    Raises
    ------
    StationError
        The folder holds files (without ``--force``) or cannot be written.
    """
    from station.diagnosis.identify.loop import default_out_dir  # lazy: start-up time (the diagnosis: scipy)

    parent = (getattr(args, "_config_values", None) or {}).get("out_dir") or Path(DEFAULT_OUT_DIR)
    folder = args.out_dir if args.out_dir is not None else default_out_dir(folder=parent)
    label = "--out-dir" if args.out_dir is not None else "the experiments' folder"
    check_folder(folder, label)  # (first: a name the file system cannot hold is refused here)
    if is_folder(folder) and any(folder.iterdir()) and not args.force:
        raise StationError(f"{label} {folder}: holds files already; use --force to write into it, or another folder")
    return folder


def check_experiment_names(outputs: list[Output], folder: Path) -> None:
    """Refuse an output that identify's experiments may write: a file in the experiments' folder
    named like one (:data:`EXPERIMENT_NAME`), before any experiment runs.

    Parameters
    ----------
    outputs : list of Output
        ``--json``, ``--save-model`` and the report's pages.
    folder : Path
        The experiments' folder.

    Raises
    ------
    StationError
        ``--json exp/01-p2-step-50.tsv: ...`` naming the folder and the names it holds.
    """
    home = Path(folder).resolve()
    for option, path, *_ in outputs:
        if path is None:
            continue
        p = Path(path).resolve()
        if p.parent == home and EXPERIMENT_NAME.match(p.name):
            raise StationError(f"{option} {path}: in {folder}, the names NN-... are the experiments' logs, figures "
                               f"and references identify writes; give another name or folder")


def format_identification(ident) -> str:
    """What ``station identify`` prints: every experiment (why, outcome), how it ended, the diagnosis.

    Parameters
    ----------
    ident : Identification
        What :func:`station.diagnosis.identify.loop.identify` returned.
    """
    from station.diagnosis.honesty.rivals import describe  # lazy: start-up time (the diagnosis: scipy)

    lines = []
    for k, r in enumerate(ident.experiments, 1):
        lines.append(f"{k:2d}. {r.experiment.label}: {r.reason}{'' if r.used else ' (not used)'}")
        lines.append(f"    why: {r.why}")
        lines.append(f"    log: {r.log}")
    t = ident.timings
    lines.append(f"ended: {ident.stopped}")
    for note in ident.kept:
        lines.append(f"kept the earlier explanation: {note}")
    if ident.model is not None:
        lines.append(f"identified model: {describe(ident.model.effect_dict())}")
    n, d = len(ident.experiments), ident.diagnoses
    lines.append(f"{n} experiment{'' if n == 1 else 's'} ({sum(r.used for r in ident.experiments)} used), "
                 f"{d} diagnos{'i' if d == 1 else 'e'}s in {t.get('total', 0):.1f} s "
                 f"(experiments {t.get('experiments', 0):.1f} s, "
                 f"diagnoses {t.get('diagnosis', 0):.1f} s, designs {t.get('design', 0):.1f} s)")
    if ident.diagnosis is not None:
        lines.append(format_diagnosis(ident.diagnosis))
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Identify; print the experiments and the diagnosis; write the outputs asked for.

    Parameters
    ----------
    args : argparse.Namespace
        The device (``--port``, ``--protocol``), ``--model``, ``--budget``, the limits and the
        outputs; checked before any run.

    Returns
    -------
    int
        0 when it ran to the end, 1 when fewer than two experiments completed (nothing to
        diagnose), 130 / 143 when a signal stopped it.

    Raises
    ------
    StationError
        Bad input (an unknown port, an unreadable model, an output that exists or cannot be
        written), before any run.
    """
    from station.diagnosis.identify.loop import DEFAULT_BUDGET, identify  # lazy: start-up time (the diagnosis: scipy)

    config_error(args)
    if getattr(args, "_config", None):
        warn(f"settings from {args._config} (options given on the command line win)")
    check_port(args.port)
    model = as_model(args.model)  # an unreadable model is refused before any run
    check_outputs(outputs(args), model_inputs(args), force=args.force)
    if args.report is not None and is_folder(args.report) and any(args.report.iterdir()) and not args.force:
        # its figures are named as the experiments come (experiment-NN.png, <log>_run.png): unknown up front
        raise StationError(f"--report {args.report}: holds files already; use --force to write into it, or another "
                           f"folder")
    folder = experiments_folder(args)
    check_experiment_names(outputs(args), folder)
    progress = None if args.quiet else (lambda msg: print(f"identify: {msg}", file=sys.stderr, flush=True))
    budget = DEFAULT_BUDGET if args.budget is None else args.budget
    ident = identify(port=args.port, model=model, budget=budget, out_dir=folder, protocol=args.protocol,
                     soft_limit=args.soft_limit, limit=args.limit, timeout=args.timeout, force=args.force,
                     progress=progress, limits=link_limits(args), baudrate=args.baud)
    print(format_identification(ident))
    with Transaction() as tx:  # every file whole or none (station.outputs)
        if args.report is not None:
            from station.diagnosis.identify.report import write_identify_report  # lazy: start-up time (matplotlib)

            page = write_identify_report(ident, args.report, tx)
        if args.json is not None:
            tx.write_json(args.json, ident.to_json())
        if args.save_model is not None and ident.model is not None:
            tx.write(args.save_model, ident.model.to_toml(), "the model")
    if args.report is not None:
        print(f"report: {page}")
    if args.save_model is not None and ident.model is not None:
        print(f"model: {args.save_model}")
    return ident.exit_code
