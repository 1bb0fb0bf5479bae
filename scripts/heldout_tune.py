#!/usr/bin/env python3
"""Held-out check of a tuned lead + accelerometer compensator: rigs the design never saw.

Each held-out rig is a model file (:mod:`station.plant` models, written here into a temporary
folder, never given to ``station tune``): other friction levels, no friction, a breakaway
friction, a dead zone, another drive damping, another beam EI, the 2009 session, a heavier hub,
a weaker actuator, a softer drive train, viscous friction (:data:`HELD_OUT`). On each, the
tuned compensator file and the thesis's ``lead-accel`` run as ``station step`` runs them
(:func:`station.experiment.run_step` on ``sim://?model=FILE&seed=N``: protocol v1, the
accelerometer's noise on), a step of 200 counts, and the logs give the overshoot, the hub's
2 % settling time and the tip's residual RMS (the accelerometer from 0.6 s after the step to
the run's end). The issue's bar on hidden rigs: overshoot ≤ 8 %, hub 2 % settling ≤ 0.6x the
thesis's, tip residual RMS ≤ 1.5x the thesis's.

Usage: ``python scripts/heldout_tune.py [--controller C.toml] [--seeds 3] [--json FILE]``;
without ``--controller`` it runs ``station tune --model rig --controller lead-accel
--amplitude 200`` (the defaults) first and checks that design.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from station.ranges import number  # noqa: E402
from station.outputs import FORCE_HELP, check_outputs, write_json  # noqa: E402

AMPLITUDE = 200.0
BAR = {"overshoot_pct": 8.0, "hub_ratio": 0.6, "tip_ratio": 1.5}
"""The issue's bar on hidden simulated rigs."""

HELD_OUT = (
    ("no friction", "rig", {"coulomb_friction": 0.0}),
    ("tmm-fit (no friction, drive damping x1)", "tmm-fit", {}),
    ("rig-2009 (friction 1.2, offset -1.5)", "rig-2009", {}),
    ("friction 20", "rig", {"coulomb_friction": 20.0}),
    ("breakaway 12 over Coulomb 8", "rig", {"coulomb_friction": 8.0, "static_friction": 12.0}),
    ("dead zone 3, Coulomb 4", "rig", {"coulomb_friction": 4.0, "deadzone": 3.0}),
    ("drive damping x2 of rig", "rig", {"param:drive_c": 6.44}),
    ("beam EI x0.8", "rig", {"param:EI": 0.8}),
    ("beam EI x1.2, Coulomb 8", "rig", {"param:EI": 1.2, "coulomb_friction": 8.0}),
    ("Coulomb 3", "rig", {"coulomb_friction": 3.0}),
    ("breakaway 9 over Coulomb 5.3", "rig", {"static_friction": 9.0}),
    ("hub inertia J_base x1.2", "rig", {"param:J_base": 1.2}),
    ("actuator gain act_K x0.8", "rig", {"param:act_K": 0.8}),
    ("drive stiffness drive_k x0.7", "rig", {"param:drive_k": 0.7}),
    ("viscous 1.7, Coulomb 4", "rig", {"viscous_friction": 1.74, "coulomb_friction": 3.98}),
)
"""(label, base model, effects over it): the held-out rigs. The first nine are those the design
was first judged on; the last six were added later, so that a design rule is not tuned to the
nine: less friction than the estimate, a breakaway over the sliding level, a heavier hub, a
weaker actuator (the diagnosis's in-sample act_K 0.78), a softer drive train, and the
diagnosis's viscous alternative (docs/diagnosis.md "Which model to ship")."""


def _measure(log_path: Path) -> dict:
    """Overshoot, hub 2 % settling time and tip residual RMS of a step log."""
    import numpy as np

    from station.analysis.metrics import step_info, step_metrics
    from station.rig import DEFAULT_STEP_TICK
    from station.design.tip import residual
    from station.runlog import read_log

    log = read_log(log_path)
    t, theta, a = (np.asarray(log.data[k], dtype=float) for k in ("t", "theta", "a"))
    info = step_info(t, theta, AMPLITUDE, t[DEFAULT_STEP_TICK])
    res = residual(a, DEFAULT_STEP_TICK, float(t[1] - t[0]))
    return {"overshoot_pct": step_metrics(t, theta, AMPLITUDE).overshoot_pct,
            "settling_2pct_s": info.settling_time_2pct_s, "tip_residual_rms": res.rms,
            "tip_residual_peak": res.peak}


def _run(controller: str, model_file: Path, seed: int, folder: Path, tag: str) -> dict:
    from station.experiment import run_step

    out = folder / f"{tag}.tsv"
    with warnings.catch_warnings():  # a held-out rig is another model than the design's: that is the point
        warnings.filterwarnings("ignore", message=r".* was designed on model ", category=UserWarning)
        report = run_step(port=f"sim://?seed={seed}", controller=controller, amplitude=AMPLITUDE, model=model_file,
                          out=out, figure=False, force=True)
    if not report.result.ok:
        raise SystemExit(f"{tag}: the run stopped ({report.result.reason})")
    return _measure(out)


def held_out_models() -> list[tuple[str, object]]:
    """The held-out rigs as models: (label, :class:`station.plant.model.Model`), in :data:`HELD_OUT`'s order."""
    from station.plant import load_model

    return [(label, load_model(base).with_effects(effects, name=f"held-out {i + 1}"))
            for i, (label, base, effects) in enumerate(HELD_OUT)]


def check(controller: str | Path, seeds: int = 3, progress=None) -> list[dict]:
    """Run the held-out rigs: per rig, its runs (one per noise seed) and whether the bar holds on all.

    Parameters
    ----------
    controller : str or Path
        The tuned compensator file.
    seeds : int
        Accelerometer noise seeds per rig.
    progress : callable, optional
        Called with each rig's summary (a dict, as returned).

    Returns
    -------
    list of dict
        ``rig``, ``effects``, ``runs`` (``seed``, ``thesis``, ``tuned``: overshoot_pct, settling_2pct_s,
        tip_residual_rms, tip_residual_peak; ``hub_ratio``, ``tip_ratio``, ``meets_bar``), the worst
        ``hub_ratio``, ``tip_ratio``, ``overshoot_pct`` over the seeds, ``met``.
    """
    out = []
    with tempfile.TemporaryDirectory(prefix="heldout-") as tmp:
        folder = Path(tmp)
        for i, (label, model) in enumerate(held_out_models()):
            path = folder / f"heldout-{i + 1}.toml"
            model.save(path)
            runs = []
            for seed in range(1, seeds + 1):
                th = _run("lead-accel", path, seed, folder, f"thesis-{i}-{seed}")
                tu = _run(str(controller), path, seed, folder, f"tuned-{i}-{seed}")
                hub = (math.inf if tu["settling_2pct_s"] is None or th["settling_2pct_s"] is None
                       else tu["settling_2pct_s"] / th["settling_2pct_s"])
                tip = tu["tip_residual_rms"] / th["tip_residual_rms"]
                runs.append({"seed": seed, "thesis": th, "tuned": tu, "hub_ratio": hub, "tip_ratio": tip,
                             "meets_bar": tu["overshoot_pct"] <= BAR["overshoot_pct"] and hub <= BAR["hub_ratio"]
                             and tip <= BAR["tip_ratio"]})
            row = {"rig": label, "effects": model.effect_dict(), "runs": runs,
                   "hub_ratio": max(r["hub_ratio"] for r in runs), "tip_ratio": max(r["tip_ratio"] for r in runs),
                   "overshoot_pct": max(r["tuned"]["overshoot_pct"] for r in runs),
                   "met": all(r["meets_bar"] for r in runs)}
            out.append(row)
            if progress is not None:
                progress(row)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--controller", type=Path, default=None, metavar="C.toml",
                        help="the tuned compensator file (default: tune one with station tune's defaults)")
    parser.add_argument("--seeds", type=number(1, 100, integer=True), default=3, metavar="N",
                        help="accelerometer noise seeds per rig (default 3; the worst of them counts)")
    parser.add_argument("--jobs", type=number(1, 64, integer=True), default=2, metavar="N",
                        help="processes of the design when it is tuned here (default 2)")
    parser.add_argument("--json", type=Path, default=None, metavar="FILE", help="write the numbers as JSON")
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)
    args = parser.parse_args(argv)
    check_outputs([("--json", args.json)], force=args.force, parser=parser)

    with tempfile.TemporaryDirectory(prefix="heldout-design-") as tmp:
        controller = args.controller
        if controller is None:
            from station.design import tune

            t0 = time.perf_counter()
            controller = Path(tmp) / "C.toml"
            r = tune("rig", structure="lead-accel", amplitude=AMPLITUDE, jobs=args.jobs, out=controller)
            controller.write_text(r.file.to_toml(), encoding="utf-8")
            print(f"tuned on rig in {time.perf_counter() - t0:.0f} s: "
                  + ", ".join(f"{k} {v:.4g}" for k, v in r.values.items()), flush=True)
        print(f"{'held-out rig':42s} {'thesis os/hub/tip':>22s} {'tuned os/hub/tip':>22s}  hub x  tip x  bar")

        def fmt(m):
            s = m["settling_2pct_s"]
            return f"{m['overshoot_pct']:4.1f}%/{'n.s.' if s is None else f'{s:.3f}'}/{m['tip_residual_rms']:.2f}"

        def show(row):
            worst = max(row["runs"], key=lambda r: (not r["meets_bar"], r["hub_ratio"], r["tip_ratio"]))
            print(f"{row['rig']:42s} {fmt(worst['thesis']):>22s} {fmt(worst['tuned']):>22s}  "
                  f"{row['hub_ratio']:5.2f} {row['tip_ratio']:5.2f}  {'met' if row['met'] else 'NOT met'}", flush=True)
        rows = check(controller, args.seeds, show)
    met = sum(r["met"] for r in rows)
    worst = {k: max(r[k] for r in rows) for k in ("hub_ratio", "tip_ratio", "overshoot_pct")}
    print(f"bar (overshoot <= 8 %, hub 2 % settling <= 0.6x, tip RMS <= 1.5x the thesis's): met on {met} of "
          f"{len(rows)} held-out rigs ({args.seeds} noise seeds each); worst hub {worst['hub_ratio']:.2f}x, "
          f"tip {worst['tip_ratio']:.2f}x, overshoot {worst['overshoot_pct']:.1f} %; load average "
          f"{os.getloadavg()[0]:.1f}")
    if args.json is not None:
        write_json(args.json, {"rigs": rows, "met": met, "bar": BAR, "worst": worst})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
