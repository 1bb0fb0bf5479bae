#!/usr/bin/env python3
"""Benchmark: diagnose four 2 s runs over every candidate with leave-one-run-out.

After a warm-up diagnosis (numba JIT compilation, parameter-set loading), times
:func:`station.diagnosis.diagnose` on four runs: by default the four thesis logs
of the rig (``../shared/data/rig``: open-loop pulses, P step, lead step, lead +
accelerometer step; the real case, with forward selection of several effects), or with
``--blind EFFECT=VALUE`` the four logs of a hidden-effect case written by the independent
generator of tests/blind. Prints the seconds (and the CPU seconds of the process and its workers), the model simulations (counted inside
diagnose, ``Diagnosis.simulations``) and simulations per second.

Target (issue 26): the four thesis logs over the whole vocabulary in at most 20 s on a 2-core machine
(by default a worker process per core, as ``station diagnose --jobs``).

With ``--identify`` it then times ``station identify`` (:func:`station.diagnosis.identify.loop.identify`)
on the lockstep simulated rig serving a model (default the built-in ``rig``: the thesis's four
experiments, the diagnoses, the designed experiments): seconds in total and per phase (running
experiments, diagnosing, designing), experiments run and used, diagnoses, and what it found.
There is no previous release of ``identify`` to print beside it.

Usage: ``python scripts/bench_diagnose.py [--rig DIR] [--blind coulomb_friction=10]
[--workers N] [--json FILE] [--identify [MODEL]] [--budget N]``; the JSON is ``{"seconds",
"cpu_seconds", "simulations", "simulations_per_s", "cause", "causes", "gain_pct", "runs",
"workers"}``, plus ``"identify": {"model", "seconds", "cpu_seconds", "timings_s", "experiments", "used",
"diagnoses", "stopped", "causes", "effects"}`` with ``--identify``.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from station.outputs import FORCE_HELP, check_outputs, write_json

REPO = Path(__file__).resolve().parents[1]
RIG_LOGS = (
    "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt",
    "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
    "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt",
    "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt",
)

TARGET_S = 20.0
"""The four thesis logs, whole vocabulary, on 2 cores (issue 26), s."""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rig", type=Path, default=REPO.parent / "shared" / "data" / "rig",
                        help="folder of the rig's logs (default ../shared/data/rig)")
    parser.add_argument("--blind", default=None, metavar="EFFECT=VALUE",
                        help="diagnose a generated hidden-effect case instead ('none' for a clean one)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="worker processes fitting candidates at once (default: the CPU count, as station "
                             "diagnose)")
    parser.add_argument("--json", type=Path, default=None, help="write the numbers as JSON")
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)
    parser.add_argument("--identify", nargs="?", const="rig", default=None, metavar="MODEL",
                        help="also time station identify on the lockstep simulated rig serving MODEL (default rig)")
    parser.add_argument("--budget", type=int, default=8, help="identify's budget of designed experiments (default 8)")
    args = parser.parse_args(argv)
    check_outputs([("--json", args.json)], force=args.force, parser=parser)

    with tempfile.TemporaryDirectory(prefix="bench_diagnose_") as tmp:  # the generated logs, identify's runs
        return _bench(args, Path(tmp))


def _bench(args: argparse.Namespace, tmp: Path) -> int:
    from station.diagnosis import diagnose

    if args.blind is not None or not args.rig.is_dir():
        sys.path.insert(0, str(REPO))
        from tests.blind.generator import write_case

        effects = {}
        if args.blind and args.blind != "none":
            name, value = args.blind.split("=", 1)
            effects = {name: float(value)}
        runs = [str(p) for p in write_case(tmp, effects, 0)]
        what = f"generated case {effects or 'clean'}"
    else:
        runs = [str(args.rig / name) for name in RIG_LOGS]
        what = f"the rig's four thesis logs ({args.rig})"

    t = time.perf_counter()
    diagnose(runs[:2], candidates=["delay", "coulomb_friction", "param:drive_c"], workers=args.workers)
    print(f"warm-up: {time.perf_counter() - t:.1f} s", file=sys.stderr)

    t, cpu = time.perf_counter(), _cpu()
    d = diagnose(runs, workers=args.workers)
    seconds, cpu = time.perf_counter() - t, _cpu() - cpu
    rate = d.simulations / seconds
    print(f"diagnose {len(runs)} runs ({what}), every candidate, leave-one-run-out:")
    print(f"  {seconds:.1f} s, {d.simulations} model simulations, {rate:.0f} simulations/s")
    print(f"  CPU time of this process and its workers {cpu:.1f} s ({args.workers} worker(s); load average "
          f"{os.getloadavg()[0]:.1f})")
    print(f"  cause {d.cause} (accepted: {', '.join(d.causes) or 'none'}), θ RMS gain {d.gain_pct:.1f} %")
    print(f"  target <= {TARGET_S:g} s on 2 cores: {'met' if seconds <= TARGET_S else 'NOT met'}")
    doc = {"seconds": seconds, "cpu_seconds": cpu, "simulations": d.simulations, "simulations_per_s": rate,
           "cause": d.cause, "causes": d.causes, "gain_pct": d.gain_pct, "runs": runs, "workers": args.workers}
    if args.identify is not None:
        doc["identify"] = bench_identify(args.identify, args.budget, tmp / "identify")
    if args.json is not None:
        write_json(args.json, doc)
    return 0


def _cpu() -> float:
    """CPU seconds of this process and of its finished worker processes."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def bench_identify(model: str, budget: int, out_dir: Path) -> dict:
    """Time station identify on ``sim://?model=MODEL`` (lockstep) and print the numbers."""
    from station.diagnosis.identify.loop import identify

    t, cpu = time.perf_counter(), time.process_time()
    ident = identify(port=f"sim://?model={model}", budget=budget, out_dir=out_dir)
    seconds, cpu = time.perf_counter() - t, time.process_time() - cpu
    tm, n = ident.timings, len(ident.experiments)
    used = sum(r.used for r in ident.experiments)
    found = ident.model.effect_dict() if ident.model is not None else {}
    print(f"identify on sim://?model={model} (lockstep), budget {budget} designed experiments:")
    print(f"  {seconds:.1f} s: experiments {tm['experiments']:.1f} s, diagnoses {tm['diagnosis']:.1f} s, "
          f"designs {tm['design']:.1f} s; CPU time of this process {cpu:.1f} s (load average "
          f"{os.getloadavg()[0]:.1f}; the simulated rig runs in this process)")
    print(f"  {n} experiments ({n - 4} designed, {used} used), {ident.diagnoses} diagnoses; ended: {ident.stopped}")
    print(f"  found: {', '.join(f'{k} = {v:.4g}' for k, v in found.items()) or 'none'}")
    return {"model": model, "seconds": seconds, "cpu_seconds": cpu, "timings_s": tm, "experiments": n, "used": used,
            "diagnoses": ident.diagnoses, "stopped": ident.stopped,
            "causes": ident.diagnosis.causes if ident.diagnosis is not None else [], "effects": found}


if __name__ == "__main__":
    sys.exit(main())
