#!/usr/bin/env python3
"""Benchmark: seconds to audit logs whose header does not give the law's accelerometer feedback.

The expensive audit is the one that must find a law with accelerometer feedback in the data
(:func:`station.analysis.accel_law.accel_feedback`): a header that names a lead but not its
Ga (the rig's own lead + accelerometer logs print ``#Ga num=[]``), and the same log with three
column faults at once (θ negated, from the encoder's count, v in volts), checked rewrite by
rewrite (:func:`station.logged.columns.check_columns`). Each log is audited in a fresh child
process (``LoggedRun``: the audit, the controller, the replayed commands), after a warm-up
audit of another log, for this tree and, with ``--baseline REV``, for a git worktree of that
revision, side by side: the seconds of each and baseline / ours.

Logs: the simulated rig's lead + accelerometer step (``station.experiment.run_step``, 0.2 s
and 1 s) with its header's Ga taken out, and the 1 s one also with the three column faults;
with ``../shared`` (or ``$STATION_RIG_DATA``), the rig's lead + accelerometer step as logged and
under an open-loop header (the law and its Ga found in the data); with ``--blind CLASS/SEED``,
that log of the audit's blind generator too (``tests.blind.audit.write_audit_case``, e.g.
``lie:a_zero+coulomb_friction/3``, the slowest of its table).

Usage: ``python scripts/bench_audit.py [--baseline REV] [--rig DIR] [--blind CLASS/SEED ...] [--json FILE]``.
JSON: ``{"logs": {name: {"ours_s", "baseline_s" | null, "claim"}}}``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from station.outputs import FORCE_HELP, check_outputs, write_json

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # tests.blind (--blind) is not installed with the package
RIG_LEAD_ACCEL = "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"

_CHILD = r"""
import json, sys, time, warnings
sys.path.insert(0, {repo!r})
import numpy as np
from station.logged import LoggedRun
from station.runlog import read_log

def audit(path):
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        run = LoggedRun(read_log(path))
        run.controller
        run.replayed
        return run

audit({warm!r})
t0 = time.perf_counter()
run = audit({path!r})
seconds = time.perf_counter() - t0
claim = next((c.data for c in run.audit.claims if c.claim == "controller"), "")
print(json.dumps({{"seconds": seconds, "claim": claim}}))
"""


def _without_ga(text: str) -> str:
    """The station log ``text`` with its header's Ga taken out (a lead named, its Ga not)."""
    lines = text.split("\n")
    meta = json.loads(lines[2][2:])
    meta["controller"]["ga"] = None
    return "\n".join([lines[0], lines[1], "# " + json.dumps(meta), *lines[3:]])


def _three_faults(text: str) -> str:
    """θ negated and from the encoder's count 59, v in volts (±10 V over ±2048 counts)."""
    lines = text.split("\n")
    names = lines[0].split("\t")
    i_th, i_v = names.index("theta"), names.index("v")
    out = lines[:3]
    for line in lines[3:]:
        if not line or line.startswith("#"):
            out.append(line)
            continue
        f = line.split("\t")
        f[i_th] = repr(-(float(f[i_th]) + 59.0))
        f[i_v] = repr(float(f[i_v]) * 10.0 / 2048.0)
        out.append("\t".join(f))
    return "\n".join(out)


def make_logs(folder: Path, rig: Path | None, blind: list[tuple[str, int]] = ()) -> dict[str, Path]:
    """The logs benchmarked, written in ``folder``: name -> path (``blind``: (class, seed) of
    the audit's blind generator)."""
    from station.experiment import run_step

    logs = {}
    for seconds in (0.2, 1.0):
        out = folder / f"lead_accel_{seconds:g}s.tsv"
        run_step(controller="lead-accel", amplitude=100, duration=seconds, out=out, figure=False)
        bare = folder / f"no_ga_{seconds:g}s.tsv"
        bare.write_text(_without_ga(out.read_text()))
        logs[f"lead + Ga, header without Ga, {seconds:g} s"] = bare
    faults = folder / "no_ga_three_faults.tsv"
    faults.write_text(_three_faults(logs["lead + Ga, header without Ga, 1 s"].read_text()))
    logs["the same, θ negated from count 59, v in volts"] = faults
    if rig is not None and (rig / RIG_LEAD_ACCEL).is_file():
        logs["the rig's lead + Ga step (#Ga num=[])"] = rig / RIG_LEAD_ACCEL
        lines = (rig / RIG_LEAD_ACCEL).read_text().split("\n")
        ol = folder / "rig_lead_accel_ol.txt"
        ol.write_text("\n".join(["#SLFR RTP OL_Test"] + [x for x in lines[1:] if not x.startswith(("#Gth", "#Ga"))]))
        logs["the rig's lead + Ga step under an open-loop header"] = ol
    if blind:
        from tests.blind.audit import write_audit_case  # lazy: the blind generator, only when asked for

        for name, seed in blind:
            logs[f"blind {name}, seed {seed}"] = write_audit_case(folder / "blind", name, seed)[0]
    return logs


def _blind(text: str) -> tuple[str, int]:
    """``--blind``'s CLASS/SEED, checked: the class one of the generator's."""
    from tests.blind.audit import CLASSES  # lazy: the blind generator, only when asked for

    name, _, seed = text.rpartition("/")
    if name.removesuffix("+coulomb_friction") not in CLASSES or not seed.isdigit():
        raise argparse.ArgumentTypeError(f"expected CLASS/SEED with CLASS one of tests/blind/audit.py's "
                                         f"(optionally +coulomb_friction) and SEED a whole number, got {text!r}")
    return name, int(seed)


def time_audit(tree: Path, path: Path, warm: Path) -> dict:
    """Audit ``path`` in a child process importing ``station`` from ``tree``."""
    code = _CHILD.format(repo=str(tree), path=str(path), warm=str(warm))
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; 0 on success."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", help="a git revision to time beside this tree (a temporary worktree)")
    parser.add_argument("--rig", type=Path, help="the rig's logs (default $STATION_RIG_DATA or ../shared/data/rig)")
    parser.add_argument("--blind", type=_blind, action="append", default=[], metavar="CLASS/SEED",
                        help="also a log of the audit's blind generator, e.g. lie:a_zero+coulomb_friction/3")
    parser.add_argument("--json", type=Path, help="write the results here")
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)
    args = parser.parse_args(argv)
    check_outputs([("--json", args.json)], force=args.force, parser=parser)
    rig = args.rig or Path(os.environ.get("STATION_RIG_DATA", REPO.parent / "shared" / "data" / "rig"))
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        logs = make_logs(folder, rig if rig.is_dir() else None, args.blind)
        base = None
        if args.baseline:
            base = folder / "baseline"
            subprocess.run(["git", "-C", str(REPO), "worktree", "add", "-q", "--detach", str(base), args.baseline],
                           check=True)
        warm = logs["lead + Ga, header without Ga, 0.2 s"].with_name("lead_accel_0.2s.tsv")
        try:
            for name, path in logs.items():
                print(f"{name}: ", end="", flush=True)
                ours = time_audit(REPO, path, warm)
                theirs = time_audit(base, path, warm) if base is not None else None
                results[name] = {"ours_s": ours["seconds"], "baseline_s": theirs and theirs["seconds"],
                                 "claim": ours["claim"]}
                line = f"{ours['seconds']:.2f} s"
                if theirs is not None:
                    ratio = theirs["seconds"] / ours["seconds"]
                    line += f", baseline {theirs['seconds']:.2f} s, baseline / ours {ratio:.2f}"
                print(line + f"\n    {ours['claim']}", flush=True)
        finally:
            if base is not None:
                subprocess.run(["git", "-C", str(REPO), "worktree", "remove", "--force", str(base)], check=False)
    if args.json:
        write_json(args.json, {"logs": results})
    return 0


if __name__ == "__main__":
    sys.exit(main())
