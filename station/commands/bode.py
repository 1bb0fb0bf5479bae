"""``station bode FILE``: measured frequency response of a run (H1 estimate with
coherence) against the FEM model's, and the θ/v antiresonances of both."""

from __future__ import annotations

import argparse
from pathlib import Path

from station.commands.options import (add_force_option, add_model_options, add_out_dir_option, add_report_options,
                                      config_error, model_inputs, number, out_dir, out_dir_label,
                                      out_dir_remedy)
from station.config import apply_config
from station.errors import StationError
from station.outputs import Input, Output, Transaction, check_folder, check_outputs
from station.plant import DiscretePlant
from station.plant.model import as_model

NAME = "bode"
HELP = "H1 frequency response (θ/v, a/v) of a swept-sine log against the FEM model; antiresonances"


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station bode``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets FILE, the model options, ``--nperseg``, ``--png``, ``--out-dir``, ``--json`` and ``--force``.
    """
    parser.add_argument("file", type=Path, metavar="FILE", help="run log (station or rig format), e.g. a swept sine")
    add_model_options(parser, "its linear part (param:NAME, beam_damping) gives the response")
    parser.add_argument("--nperseg", type=number(1024, 2**20, integer=True), default=4096, metavar="N",
                        help="Welch segment length, samples (default 4096: 0.12 Hz at 500 Hz; at least 1024, "
                             "0.5 Hz, to resolve the first antiresonance near 2.5 Hz)")
    parser.add_argument("--png", type=Path, default=None, metavar="OUT",
                        help="figure file (default FILE's stem + _bode.png in --out-dir)")
    add_out_dir_option(parser, "the figure when --png does not name it")
    add_report_options(parser, json="the antiresonances")
    add_force_option(parser)
    apply_config(parser)  # its out_dir


def run(args: argparse.Namespace) -> int:
    """Estimate, compare, print the antiresonances, write the figure (and JSON).

    Parameters
    ----------
    args : argparse.Namespace
        FILE, the model (``--model``, ``--elements``, ``--params``), ``--nperseg``, ``--png``,
        ``--json``, ``--force``.

    Returns
    -------
    int
        0 once the figure (and the JSON) is written.

    Raises
    ------
    StationError
        Unreadable log or parameter set, a log shorter than one Welch segment, a hub-held
        beam test (its v was not applied), bad element count; an output that is an input or another output, exists (without
        ``--force``) or cannot be written.
    """
    # lazy: start-up time (every command's parser is built at start-up: scipy, python-control, matplotlib)
    from station.analysis.frequency import compare_bode
    from station.logged import LoggedRun
    from station.plots import plot_bode

    config_error(args)
    if args.png is not None:
        figure = Output("--png", args.png)
    else:
        check_folder(out_dir(args), out_dir_label(args))  # named as the user set it
        figure = Output(f"the figure of {args.file.name}", out_dir(args) / f"{args.file.stem}_bode.png",
                        f"--png FILE, or {out_dir_remedy(args)}")
    png = figure.path
    check_outputs([figure, Output("--json", args.json)],
                  [Input("FILE", args.file), *model_inputs(args)], force=args.force)
    run = LoggedRun.from_path(args.file)
    log, t, dt = run.log, run.data["t"], run.dt
    if run.held is not None:  # θ/v and a/v of a v that was not applied mean nothing
        raise StationError(f"{args.file}: {run.held_note}; θ/v and a/v cannot be estimated: `station replay` "
                           f"measures the beam's first mode from its free vibration")
    for line in run.audit_lines:  # the data's contradictions first (DESIGN.md "Log audit")
        print(line)
    model = run.model_for(as_model(args.model, args.elements, args.params))  # its accelerometer as the audit found it
    args.elements = model.n_elements
    try:
        plant = DiscretePlant(model.linear_params(), n_elements=model.n_elements, dt=dt)
        cmp = compare_bode(log.data["v"], log.data["theta"], log.data["a"], dt, plant, nperseg=args.nperseg)
    except ValueError as exc:
        raise StationError(f"{args.file}: {exc}") from None
    print(f"{args.file}: H1 estimate, {len(t)} samples, resolution {cmp.theta.f[1] - cmp.theta.f[0]:.3f} Hz; "
          f"model {model.name} ({plant.params.name}), {args.elements} elements")
    print(f"{'antiresonance':>13} {'measured Hz':>12} {'model Hz':>9} {'error %':>8}")
    for i, (m, z, e) in enumerate(zip(cmp.antiresonances_measured_hz, cmp.antiresonances_model_hz,
                                      cmp.antiresonance_error_pct), 1):
        print(f"{i:>13} {m:12.3f} {z:9.3f} {e:+8.1f}")
    with Transaction() as tx:
        plot_bode(cmp, png, f"{args.file.name}: measured vs FEM model (n = {args.elements})", transaction=tx)
        if args.json is not None:
            tx.write_json(args.json, {
                "file": str(args.file), "n_elements": args.elements,
                "antiresonances": [{"measured_hz": float(m), "model_hz": float(z), "error_pct": float(e)}
                                   for m, z, e in zip(cmp.antiresonances_measured_hz, cmp.antiresonances_model_hz,
                                                      cmp.antiresonance_error_pct)]})
    print(f"figure: {png}")
    return 0
