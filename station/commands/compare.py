"""``station compare FILE...``: the FEM model against logged runs (step metrics, NRMSE
fits, the thesis's table alongside) with a figure per run."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from station.commands.options import add_model_options, add_report_options, check_writable, check_writable_dir

NAME = "compare"
HELP = "simulate logged runs on the FEM model as the rig ran them; step metrics and fits vs the thesis"


def configure(parser: argparse.ArgumentParser) -> None:
    """Add ``station compare``'s arguments to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets FILE..., the model options, ``--out-dir`` and ``--json``.
    """
    parser.add_argument("files", type=Path, nargs="+", metavar="FILE", help="run logs (station or rig format)")
    add_model_options(parser)
    parser.add_argument("--out-dir", type=Path, default=Path("."), metavar="DIR",
                        help="folder for the figures, <log stem>_compare.png (default: current folder)")
    add_report_options(parser, json="the comparisons")


def run(args: argparse.Namespace) -> int:
    """Compare each log; print the tables, write the figures (and JSON).

    Parameters
    ----------
    args : argparse.Namespace
        The logs (``files``), the model (``--model``, ``--elements``, ``--params``), ``--out-dir``,
        ``--json``.

    Returns
    -------
    int
        0 once every log is compared.

    Raises
    ------
    StationError
        Unreadable log, model file or parameter set, a log without a named controller, bad element
        count, unwritable output.
    """
    from station.compare import compare_run, format_comparison
    from station.plots import plot_comparison
    from station.errors import StationError
    from station.plant.model import as_model

    check_writable(args.json, "--json")
    check_writable_dir(args.out_dir, "--out-dir")
    model = as_model(args.model, args.elements, args.params)
    effects = ", ".join(f"{k} = {v:g}" for k, v in model.effects) or "no effects"
    print(f"model: {model.name} ({model.params.name}, {model.n_elements} elements, {effects})")
    results = []
    try:
        args.out_dir.mkdir(parents=True, exist_ok=True)
        for path in args.files:
            c = compare_run(path, model)
            png = args.out_dir / f"{Path(path).stem}_compare.png"
            plot_comparison(c, png)
            print(format_comparison(c))
            print(f"  figure: {png}")
            results.append(c.to_json())
        if args.json is not None:
            args.json.write_text(json.dumps({"n_elements": model.n_elements, "params": model.params.name,
                                             "model": model.to_json(), "runs": results}, indent=1))
    except OSError as exc:
        raise StationError(f"cannot write output: {exc}") from None
    return 0
