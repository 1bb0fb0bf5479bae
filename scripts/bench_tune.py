#!/usr/bin/env python3
"""Benchmark: ``station tune`` of lead + accelerometer (+ shaper) with its robust defaults, beside a one-model design.

Times :func:`station.design.tune` on the built-in ``rig`` model, step of 200 counts, with
``station tune``'s defaults (the tip's bound, the two-mode shaper): once with ``--samples 20``
(the nominal, the doubt's corners and 20 models drawn from it), once with ``--samples 0`` (the
model alone), both with the same executor (``--jobs``, default 2: this machine's cores), after
a warm-up (worker start-up and numba's cached kernel). Prints the seconds, the evaluations (a
design on a model) and evaluations per second of each, their ratio, the load average, and the
design's worst case over the set beside the thesis's: overshoot, hub settling (2 %), tip
residual RMS.

Target (issues 18 and 25): the robust design in under 60 s on a 2-core machine.

Usage: ``python scripts/bench_tune.py [--jobs N] [--samples N] [--json FILE]``; the JSON is
``{"robust": {"seconds", "runs", "models", "worst_settling_2pct_s", "worst_overshoot_pct",
"worst_tip_residual_rms", ...}, "one_model": {...}, "ratio", "jobs", "load_average"}``.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from station.outputs import FORCE_HELP, check_outputs, write_json


def _s(x) -> str:
    return "not settled" if x is None else f"{x:.3f} s"


def _design(samples: int, jobs: int) -> dict:
    from station.design import tune

    t = time.perf_counter()
    r = tune("rig", structure="lead-accel", amplitude=200.0, samples=samples, jobs=jobs)
    seconds = time.perf_counter() - t
    settle = [f.settling_2pct_s for f in r.figures]
    base = [f.settling_2pct_s for f in r.baseline]
    return {"seconds": seconds, "runs": r.evaluations, "models": len(r.figures),
            "worst_settling_2pct_s": None if None in settle else max(settle),
            "worst_overshoot_pct": max(f.overshoot_pct for f in r.figures),
            "worst_tip_residual_rms": max(f.tip_residual_rms for f in r.figures),
            "thesis_worst_settling_2pct_s": None if None in base else max(base),
            "thesis_worst_tip_residual_rms": max(f.tip_residual_rms for f in r.baseline),
            "all_met": all(r.met())}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=int, default=2, help="local worker processes (default 2)")
    parser.add_argument("--samples", type=int, default=20, help="drawn models of the robust design (default 20)")
    parser.add_argument("--json", type=Path, default=None, help="write the numbers as JSON")
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)
    args = parser.parse_args(argv)
    check_outputs([("--json", args.json)], force=args.force, parser=parser)

    from station.design import Budget, tune

    t = time.perf_counter()
    tune("rig", structure="p", shaper="none", samples=0, jobs=args.jobs,
         budget=Budget(global_log2=4, keep=1, starts=1, maxfev=5, rounds=1))
    print(f"warm-up: {time.perf_counter() - t:.1f} s")
    robust = _design(args.samples, args.jobs)
    one = _design(0, args.jobs)
    ratio = robust["seconds"] / one["seconds"]
    load = os.getloadavg()[0]
    from station.analysis.metrics import STEP_INFO_BAND_PCT, settling_label

    print(f"station tune --model rig --controller lead-accel --amplitude 200, {args.jobs} local processes:")
    for name, d in ((f"{robust['models']} models", robust), ("1 model", one)):
        print(f"  {name:10s} {d['seconds']:6.1f} s, {d['runs']:6d} evaluations ({d['runs'] / d['seconds']:.0f}/s); "
              f"worst hub {settling_label(STEP_INFO_BAND_PCT)} {_s(d['worst_settling_2pct_s'])} (thesis "
              f"{_s(d['thesis_worst_settling_2pct_s'])}), worst tip residual RMS {d['worst_tip_residual_rms']:.2f} "
              f"(thesis {d['thesis_worst_tip_residual_rms']:.2f}), worst overshoot {d['worst_overshoot_pct']:.1f} %, "
              f"requirements {'met' if d['all_met'] else 'NOT met'}")
    print(f"  robust / one-model time: {ratio:.2f}x; load average {load:.1f} on {os.cpu_count()} CPUs")
    print(f"  target < 60 s for the robust design on 2 cores: {'met' if robust['seconds'] < 60 else 'NOT met'}")
    if args.json is not None:
        write_json(args.json, {"robust": robust, "one_model": one, "ratio": ratio, "jobs": args.jobs,
                                "load_average": load})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
