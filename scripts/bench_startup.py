#!/usr/bin/env python3
"""Benchmark: how long ``station step`` takes to reach its first tick, cold and warm.

Runs ``station step --json`` (the default lead step on the built-in simulated rig, or
``--model M``) as a new user would, each in a fresh process, and reads the time from the
process's start to the first sample (``timing.first_tick_s``) and the whole command's wall
time, and the CPU time the process used until then (what the start-up costs, whatever
else the machine runs). Cold: empty caches (a fresh ``XDG_CACHE_HOME`` for the modal form and a fresh
``NUMBA_CACHE_DIR`` for compiled kernels, so nothing is reused); warm: the same caches
again after one run filled them. Python's own bytecode caches are warm in both (they come
with any install).

Target (issue 16): a warm start reaches the first tick in at most 1 s.

Usage: ``python scripts/bench_startup.py [--runs 5] [--model rig] [--json FILE]``. The
machine's load average is printed with the results: say it with any number you quote.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from station.outputs import FORCE_HELP, check_outputs, write_json


def one(env: dict, workdir: Path, model: str | None, i: int) -> dict:
    """One ``station step`` in a fresh process; its first-tick time and wall time, s."""
    out = workdir / f"r{i}.json"
    cmd = [sys.executable, "-m", "station", "step", "--quiet", "--out", str(workdir / f"r{i}.tsv"),
           "--json", str(out)] + (["--model", model] if model else [])
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"station step failed ({proc.returncode}): {proc.stderr.strip()}")
    timing = json.loads(out.read_text())["timing"]
    return {"first_tick_s": timing["first_tick_s"], "cpu_s": timing["first_tick_cpu_s"], "setup_s": timing["setup_s"],
            "wall_s": wall}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="runs of each kind (default 5)")
    parser.add_argument("--model", default=None, help="the simulated rig's model (default tmm-fit)")
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)
    args = parser.parse_args(argv)
    check_outputs([("--json", args.json)], force=args.force, parser=parser)
    load_before = os.getloadavg()
    results = {"cold": [], "warm": []}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for i in range(args.runs):  # cold: every run with empty caches
            env = dict(os.environ, XDG_CACHE_HOME=str(work / f"cold{i}"), NUMBA_CACHE_DIR=str(work / f"numba{i}"))
            results["cold"].append(one(env, work, args.model, i))
        env = dict(os.environ, XDG_CACHE_HOME=str(work / "warm"), NUMBA_CACHE_DIR=str(work / "numba-warm"))
        one(env, work, args.model, 100)  # fills the caches
        for i in range(args.runs):
            results["warm"].append(one(env, work, args.model, 200 + i))
    load_after = os.getloadavg()
    print(f"station step{' --model ' + args.model if args.model else ''}: {args.runs} runs each")
    print(f"{'start':6} {'first tick s (median, min..max)':>32} {'its CPU s':>10} {'setup s':>8} {'wall s':>7}")
    for kind, runs in results.items():
        first = [r["first_tick_s"] for r in runs]
        print(f"{kind:6} {statistics.median(first):14.2f} ({min(first):.2f}..{max(first):.2f})"
              f"{statistics.median(r['cpu_s'] for r in runs):21.2f} {statistics.median(r['setup_s'] for r in runs):8.2f}"
              f" {statistics.median(r['wall_s'] for r in runs):7.2f}")
    warm = statistics.median(r["first_tick_s"] for r in results["warm"])
    cpu = statistics.median(r["cpu_s"] for r in results["warm"])
    print(f"warm first tick {warm:.2f} s = {warm / 1.0:.2f} x target 1 s (CPU time to it {cpu:.2f} s); "
          f"load average {load_before[0]:.1f} before, {load_after[0]:.1f} after ({os.cpu_count()} CPUs)")
    if args.json:
        write_json(args.json, {"model": args.model, **results, "load_before": load_before,
                                "load_after": load_after})
    return 0


if __name__ == "__main__":
    sys.exit(main())
