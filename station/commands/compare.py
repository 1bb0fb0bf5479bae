"""``station compare FILE...``: the FEM model against logged runs (step metrics, NRMSE
fits, the thesis's table alongside) with a figure per run."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

NAME = "compare"
HELP = "simulate logged runs on the FEM model as the rig ran them; step metrics and fits vs the thesis"


def configure(parser: argparse.ArgumentParser) -> None:
    """Add the command's arguments to its subparser."""
    parser.add_argument("files", type=Path, nargs="+", metavar="FILE", help="run logs (station or rig format)")
    parser.add_argument("--elements", type=int, default=4, metavar="N", help="beam elements of the model (default 4)")
    parser.add_argument("--params", default="tmm-fit", metavar="SET", help="parameter set name or TOML file")
    parser.add_argument("--out-dir", type=Path, default=Path("."), metavar="DIR",
                        help="folder for the figures, <log stem>_compare.png (default: current folder)")
    parser.add_argument("--json", type=Path, default=None, metavar="OUT", help="write the comparisons as JSON")


def run(args: argparse.Namespace) -> int:
    """Compare each log; print the tables, write the figures (and JSON).

    Returns
    -------
    int
        0.

    Raises
    ------
    StationError
        Unreadable log or parameter set, a log without a named controller, bad element
        count, unwritable output.
    """
    from station.analysis.compare import compare_run, format_comparison, plot_comparison
    from station.errors import StationError
    from station.plant import DiscretePlant, load_params

    params = load_params(args.params)
    try:
        plant = DiscretePlant(params, n_elements=args.elements)
    except ValueError as exc:
        raise StationError(str(exc)) from None
    print(f"model: {params.name}, {args.elements} elements")
    results = []
    try:
        args.out_dir.mkdir(parents=True, exist_ok=True)
        for path in args.files:
            c = compare_run(path, plant)
            png = args.out_dir / f"{Path(path).stem}_compare.png"
            plot_comparison(c, png)
            print(format_comparison(c))
            print(f"  figure: {png}")
            results.append(c.to_json())
        if args.json is not None:
            args.json.write_text(json.dumps({"n_elements": args.elements, "params": params.name,
                                             "runs": results}, indent=1))
    except OSError as exc:
        raise StationError(f"cannot write output: {exc}") from None
    return 0
