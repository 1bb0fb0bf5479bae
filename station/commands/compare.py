"""``station compare FILE...``: the FEM model against logged runs (step metrics, NRMSE
fits, the thesis's table alongside) with a figure per run."""

from __future__ import annotations

import argparse
from pathlib import Path

from station.commands.options import (add_force_option, add_model_options, add_out_dir_option, add_report_options,
                                      config_error, model_inputs, out_dir, out_dir_label,
                                      out_dir_remedy)
from station.config import apply_config
from station.outputs import Input, Output, Transaction, check_folder, check_outputs, unique_names
from station.plant.model import as_model
from station.signals import noting

NAME = "compare"
HELP = "simulate logged runs on the FEM model as the rig ran them; step metrics and fits vs the thesis"


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station compare``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets FILE..., the model options, ``--out-dir`` (default ``station.toml``'s ``out_dir``, else
        runs), ``--json`` and ``--force``.
    """
    parser.add_argument("files", type=Path, nargs="+", metavar="FILE", help="run logs (station or rig format)")
    add_model_options(parser)
    add_out_dir_option(parser, "the figures, <log stem>_compare.png (logs of the same stem: -2, -3 added in the "
                               "order given)")
    add_report_options(parser, json="the comparisons")
    add_force_option(parser)
    apply_config(parser)  # its out_dir


def figure_paths(files, out_dir: Path) -> list[Path]:
    """The figure of each log, ``<log stem>_compare.png`` in ``out_dir``, unique (:func:`station.outputs.unique_names`).

    Parameters
    ----------
    files : sequence of path
        The logs, in the order given.
    out_dir : Path
        The ``--out-dir`` folder.
    """
    return [out_dir / f"{stem}_compare.png" for stem in unique_names([Path(f).stem for f in files])]


def run(args: argparse.Namespace) -> int:
    """Compare each log; print the tables, write the figures (and JSON) together at the end.

    Parameters
    ----------
    args : argparse.Namespace
        The logs (``files``), the model (``--model``, ``--elements``, ``--params``), ``--out-dir``,
        ``--json``, ``--force``.

    Returns
    -------
    int
        0 once every log is compared.

    Raises
    ------
    StationError
        Unreadable log, model file or parameter set, a log without a named controller, bad element
        count; an output that is an input or another output, exists (without ``--force``) or
        cannot be written.
    """
    # lazy: start-up time (every command's parser is built at start-up: the comparison and its figures)
    from station.compare import compare_run, format_comparison
    from station.plots import plot_comparison

    config_error(args)
    folder = out_dir(args)
    check_folder(folder, out_dir_label(args))  # named as the user set it (an option, station.toml or the default)
    pngs = figure_paths(args.files, folder)
    check_outputs([Output("--json", args.json)] + [
        Output(f"the figure of {Path(f).name}", p, out_dir_remedy(args)) for f, p in zip(args.files, pngs)],
                  [Input("FILE", f) for f in args.files] + model_inputs(args), force=args.force)
    model = as_model(args.model, args.elements, args.params)
    effects = ", ".join(f"{k} = {v:g}" for k, v in model.effects) or "no effects"
    print(f"model: {model.name} ({model.params.name}, {model.n_elements} elements, {effects})")
    results = []
    with noting(lambda: f"after {len(results)} of {len(args.files)} logs; nothing written"), Transaction() as tx:
        for path, png in zip(args.files, pngs):
            c = compare_run(path, model)
            plot_comparison(c, png, transaction=tx)
            print(format_comparison(c))
            print(f"  figure: {png}")
            results.append(c.to_json())
        if args.json is not None:
            tx.write_json(args.json, {"n_elements": model.n_elements, "params": model.params.name,
                                      "model": model.to_json(), "runs": results})
    return 0
