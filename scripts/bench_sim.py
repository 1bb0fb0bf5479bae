#!/usr/bin/env python3
"""Benchmark: 2 s closed-loop runs of the FEM plant, against real time and the thesis's way.

For each element count (default 1, 4, 10, 100) and controller (lead + accelerometer
feedback, step 200; P kp = 2, step 50; open loop, the rig's ±100 pulse) it times
`station.plant.simulate` (exact ZOH, modal form, compiled sample loop; the plant built
once beforehand, the best of several runs) and, for n <= 10, a baseline that steps the
continuous model as the thesis did: one scipy.integrate.odeint call per sample with v
held, the compensator stepped in Python. Printed side by side: seconds, real-time
factor (2 s / seconds), baseline seconds and baseline / ours, and whether the run is
stable (closed loop: small-signal closed-loop poles inside the unit circle and the
simulated hub angle bounded; open loop: no eigenvalue of Ad outside the unit circle).

Targets (issue "FEM model ..."): n = 4 >= 1000x real time and >= 50x the baseline;
n = 100 >= 50x real time; lead + accel stable at every n.

Then a Model with effects (``bench_effects``): one 1000-sample lead + accel run with
Coulomb or breakaway friction, backlash (sub-stepped), viscous friction (linear) or
amplifier effects, in ms and as a ratio to the same Model without effects (target:
friction under ~2 ms; breakaway friction about what Coulomb friction costs).

``--against DIR`` compares with another checkout of the station (e.g. the commit before a
change, ``git worktree add`` or ``git archive | tar -x``): its own ``scripts/bench_sim.py``
runs on its own ``station`` package in a subprocess, alternating with this one for
``--rounds`` rounds; printed side by side are each case's median seconds over the rounds
and the ratio this / other (cases only one side has are left out).

Usage: ``python scripts/bench_sim.py [--elements 1 4 10 100] [--baseline-max 10]
[--repeats 5] [--json FILE] [--against DIR [--rounds 3]]``. The JSON is
``{"cases": [{"n_elements", "controller", "seconds", "baseline_seconds",
"realtime_factor", "baseline_ratio", "stable"}], "effects": [{"effects", "seconds", "ratio"}]}``
(baseline fields null where not run); with ``--against`` it is
``{"against": DIR, "rows": [{"case", "seconds", "other_seconds", "ratio"}]}``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.integrate

from station.control import make_controller, pulse_reference, step_reference
from station.outputs import FORCE_HELP, check_outputs, write_json
from station.plant import DiscretePlant, closed_loop_spectral_radius, simulate
from station.rig import DEFAULT_DURATION, DEFAULT_SOFT_LIMIT, DEFAULT_STEP_TICK, DT

CASES = {  # controller -> reference of one 2 s run
    "lead-accel": lambda n: step_reference(200.0, n, at_tick=DEFAULT_STEP_TICK),
    "p": lambda n: step_reference(50.0, n, at_tick=DEFAULT_STEP_TICK),
    "open-loop": lambda n: pulse_reference(100.0, n, 20, 50, return_tick=700),
}


def baseline_run(plant: DiscretePlant, controller, u: np.ndarray, alignment: int = 1) -> np.ndarray:
    """The thesis's way: one odeint call per sample on the continuous model.

    Parameters
    ----------
    plant : DiscretePlant
        Gives the parameters and element count; the continuous model is rebuilt from it.
    controller : Compensator or OpenLoop
        Stepped in Python, sample by sample.
    u : ndarray, shape (N,)
        Reference per tick.
    alignment : int
        Computational delay, samples.

    Returns
    -------
    ndarray, shape (N,)
        Hub angle, encoder counts (rounded).
    """
    from station.plant import state_matrices

    A, B, C = state_matrices(plant.params, plant.n_elements)
    b = B[:, 0]
    x = np.zeros(A.shape[0])
    controller.reset()
    theta = np.zeros(u.size)
    accel = np.zeros(u.size)
    for k in range(u.size):
        y = C @ x
        theta[k], accel[k] = np.floor(y[0] + 0.5), np.floor(y[1] + 0.5)
        j = max(k - alignment, 0)
        v, _ = controller.step(u[k], theta[j], accel[j])
        x = scipy.integrate.odeint(lambda s, _t, vv=v: A @ s + b * vv, x, [0.0, plant.dt],
                                   Dfun=lambda _s, _t: A)[-1]
    return theta


def _best_time(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def bench(elements=(1, 4, 10, 100), controllers=tuple(CASES), baseline_max: int = 10, repeats: int = 5,
          out=sys.stdout) -> dict:
    """Run the benchmark; returns ``{"cases": [...]}`` (see the module docstring).

    Parameters
    ----------
    elements : sequence of int
        Element counts.
    controllers : sequence of str
        Keys of CASES.
    baseline_max : int
        Run the odeint baseline for n <= baseline_max (0: never).
    repeats : int
        Timed runs of `simulate` per case; the best is reported.
    out : file or None
        Where to print the table.
    """
    n_ticks = int(round(DEFAULT_DURATION / DT))
    cases = []
    if out:
        print(f"{'n':>4} {'controller':<11} {'seconds':>10} {'x real time':>12} {'baseline s':>11} "
              f"{'x baseline':>11} {'stable':>7}", file=out)
    for n in elements:
        plant = DiscretePlant(n_elements=n, dt=DT)
        for kind in controllers:
            controller = make_controller(kind)
            u = CASES[kind](n_ticks)
            run = simulate(plant, controller, u)  # compiles once, caches the modal form
            seconds = _best_time(lambda: simulate(plant, controller, u), repeats)
            bounded = bool(np.all(np.isfinite(run["theta"])) and np.abs(run["theta"]).max() < DEFAULT_SOFT_LIMIT)
            radius = closed_loop_spectral_radius(plant, controller)
            stable = bounded and (radius < 1.0 if controller.gth is not None else radius <= 1.0 + 1e-12)
            base = None
            if n <= baseline_max:
                t0 = time.perf_counter()
                baseline_run(plant, controller, u)
                base = time.perf_counter() - t0
            case = {
                "n_elements": n, "controller": kind, "seconds": seconds,
                "baseline_seconds": base, "realtime_factor": DEFAULT_DURATION / seconds,
                "baseline_ratio": None if base is None else base / seconds, "stable": stable,
            }
            cases.append(case)
            if out:
                b = "-" if base is None else f"{base:11.3f}"
                r = "-" if base is None else f"{base / seconds:11.0f}"
                print(f"{n:>4} {kind:<11} {seconds:10.2e} {DEFAULT_DURATION / seconds:12.0f} {b:>11} {r:>11} "
                      f"{str(stable):>7}", file=out, flush=True)
    return {"cases": cases}


EFFECT_CASES = {  # a 1000-sample lead + accel run (step 200) of the 4-element model with these effects
    "none": {},
    "coulomb_friction": {"coulomb_friction": 10.0},
    "backlash": {"backlash": 10.0},
    "friction+backlash": {"coulomb_friction": 10.0, "backlash": 10.0},
    "amplifier": {"saturation": 150.0, "deadzone": 5.0, "delay": 2.0},
    "static_friction": {"static_friction": 15.0, "coulomb_friction": 7.0},
    "viscous_friction": {"viscous_friction": 3.0},
    "amp_offset": {"amp_offset": -2.0, "saturation": 150.0},
}


def bench_effects(repeats: int = 20, out=sys.stdout) -> list[dict]:
    """Time `simulate` on a Model with effects (the diagnosis's inner loop) against none.

    Returns ``[{"effects", "seconds", "ratio"}]``: best of ``repeats`` after the JIT
    warm-up, and the ratio to the run without effects. Target: friction under ~2 ms.
    """
    from station.plant.model import load_model

    nominal = load_model()
    controller = make_controller("lead-accel")
    u = step_reference(200.0, 1000, at_tick=DEFAULT_STEP_TICK)
    rows = []
    for label, effects in EFFECT_CASES.items():
        model = nominal.with_effects(effects)
        simulate(model, controller, u, command="trunc")  # compile, cache the modal form
        seconds = _best_time(lambda m=model: simulate(m, controller, u, command="trunc"), repeats)
        rows.append({"effects": label, "seconds": seconds})
    for row in rows:
        row["ratio"] = row["seconds"] / rows[0]["seconds"]
        if out:
            print(f"model with {row['effects']:<18} 1000 samples: {row['seconds'] * 1e3:7.3f} ms "
                  f"({row['ratio']:.1f}x no effects)", file=out, flush=True)
    return rows


# run ROOT/scripts/bench_sim.py on ROOT's own station package: the editable install's
# import hook (if any) would otherwise hand this checkout's package to the other script
def _labelled(result: dict) -> dict[str, float]:
    """{case label: seconds} of a bench JSON (element count / controller, and the effects)."""
    rows = {f"n={c['n_elements']} {c['controller']}": c["seconds"] for c in result.get("cases", [])}
    rows.update({f"model with {e['effects']}": e["seconds"] for e in result.get("effects", [])})
    return rows


def compare(other: Path, argv: list[str], rounds: int = 3, out=sys.stdout) -> list[dict]:
    """This checkout's benchmark against another's, alternating, median seconds per case.

    Parameters
    ----------
    other : Path
        The other checkout's root (holds ``station/`` and ``scripts/bench_sim.py``).
    argv : list of str
        Options both benchmarks run with (without ``--json``/``--against``).
    rounds : int
        Runs of each side, alternating (this one first).
    out : file or None
        Where to print the table.

    Returns
    -------
    list of dict
        ``{"case", "seconds", "other_seconds", "ratio"}`` for the cases both report.
    """
    from checkout import run_on  # scripts/ is on sys.path in the parent only

    here = Path(__file__).resolve().parents[1]
    runs: dict[str, list[dict]] = {"this": [], "other": []}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(rounds):
            for side, root in (("this", here), ("other", Path(other).resolve())):
                result = run_on(root, root / "scripts" / "bench_sim.py", argv, Path(tmp) / f"{side}{k}.json")
                runs[side].append(_labelled(result))
    rows = []
    for case in runs["this"][0]:
        if all(case in r for r in runs["other"]):
            mine = statistics.median(r[case] for r in runs["this"])
            theirs = statistics.median(r[case] for r in runs["other"])
            rows.append({"case": case, "seconds": mine, "other_seconds": theirs, "ratio": mine / theirs})
    if out:
        print(f"median of {rounds} alternating rounds; other: {other}", file=out)
        print(f"{'case':<32} {'this ms':>9} {'other ms':>9} {'this/other':>10}", file=out)
        for r in rows:
            print(f"{r['case']:<32} {r['seconds'] * 1e3:9.3f} {r['other_seconds'] * 1e3:9.3f} {r['ratio']:10.3f}",
                  file=out)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--elements", type=int, nargs="+", default=[1, 4, 10, 100])
    ap.add_argument("--controllers", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--baseline-max", type=int, default=10, help="odeint baseline for n <= this (0: none)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", metavar="FILE")
    ap.add_argument("--force", action="store_true", help=FORCE_HELP)
    ap.add_argument("--against", metavar="DIR", type=Path, help="compare with another checkout's benchmark")
    ap.add_argument("--rounds", type=int, default=3, help="alternating rounds with --against (median)")
    args = ap.parse_args(argv)
    check_outputs([("--json", args.json)], force=args.force, parser=ap)
    if args.against is not None:
        if not (args.against / "scripts" / "bench_sim.py").is_file():
            ap.error(f"--against: {args.against} holds no scripts/bench_sim.py")
        same = ["--elements", *map(str, args.elements), "--controllers", *args.controllers,
                "--baseline-max", str(args.baseline_max), "--repeats", str(args.repeats)]
        rows = compare(args.against, same, args.rounds)
        if args.json:
            write_json(args.json, {"against": str(args.against), "rows": rows})
        return 0
    result = bench(args.elements, args.controllers, args.baseline_max, args.repeats)
    result["effects"] = bench_effects(max(args.repeats, 20))
    if args.json:
        write_json(args.json, result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
