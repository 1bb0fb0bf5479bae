"""The real-rig study behind the built-in ``rig`` models (docs/diagnosis.md): fixed effect
structures fitted on a session's logs with the diagnosis's own fitting
(:func:`station.diagnosis.search.selection.trial`), judged leave-one-run-out and on logs they were
not fitted to, with the diagnosis's cost (maximum likelihood, θ + a; or, for comparison, θ alone or the
noise-weighted sum the diagnosis used before), and
the step overshoots of the model refitted on all fit logs.

    python scripts/rig_study.py                      # the four thesis logs (2013-14)
    python scripts/rig_study.py --session 2009       # the 2009 session's four logs
    python scripts/rig_study.py --effects param:drive_c,coulomb_friction,amp_offset \\
        --weight ml-theta --save-model rig.toml

Prints, per structure: the values refitted per fold, the held-out θ RMS gain per run and
pooled, the values refitted on all fit logs, the θ RMS gain on the other logs (both eras)
and the step overshoots against the rig's.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from station.analysis.metrics import step_metrics
from station.diagnosis.runs.cases import load_case
from station.diagnosis.runs.cost import Evaluator, calibrate_noise
from station.diagnosis.runs.folds import make_folds
from station.diagnosis.search.fitting import effect_axes, fit_set, set_axes
from station.diagnosis.search.selection import trial
from station.plant.model import as_model

RIG = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "rig"
THESIS = ["OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt",
          "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
          "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt",
          "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"]
OTHER_2014 = ["swept_sine_kp_1_amp_50.txt", "without_accel_01_28_14_test_2.txt"]
SESSION_2009 = ["2009/step_response_amp=100_SLFR_RTP_P_control_kp=1.0.txt",
                "2009/swept_sine_no_sat_amp=50_stopn=10000_test_1_SLFR_RTP_P_control_kp=1.0.txt",
                "2009/swept_sine_no_sat_amp=75_stopn=10000_test_1_SLFR_RTP_P_control_kp=1.0.txt",
                "2009/swept_sine_no_sat_amp=25_stopn=20000_test_1_SLFR_RTP_P_control_kp=1.0.txt"]
RIG_OVERSHOOT = {THESIS[1]: 24.0, THESIS[2]: 10.0, THESIS[3]: 21.5}
"""The thesis's measured step overshoots, % (DESIGN.md)."""

START = {"param:drive_c": 2.0, "coulomb_friction": 8.0, "static_friction": 14.0, "amp_offset": -1.0,
         "viscous_friction": 0.5, "param:act_K": 0.8}
"""Where each fold's fit starts (the last effect of a structure is bracketed on its grid)."""

STRUCTURES = [
    ("param:drive_c", "coulomb_friction"),
    ("param:drive_c", "coulomb_friction", "amp_offset"),
    ("param:drive_c", "static_friction", "amp_offset"),
]


def short(path: str) -> str:
    """A log's name cut to a table column."""
    return Path(path).name[:34]


def head(path: Path, n: int, folder: Path) -> Path:
    """The log itself, or a copy of its header and first n data rows (n > 0)."""
    if n <= 0:
        return path
    lines = path.read_text().splitlines(keepends=True)
    body = [i for i, line in enumerate(lines) if line.strip() and line.lstrip()[0] in "-0123456789"]
    if len(body) <= n:
        return path
    out = folder / path.name
    out.write_text("".join(lines[:body[n]]))
    return out


def overshoot(ev: Evaluator, effects: dict, i: int) -> float | None:
    """Step overshoot (%) of run i simulated with the effects (None: not a closed-loop step)."""
    c = ev.cases[i]
    u = np.asarray(c.run.data["u"], float)
    if not c.closed or u[-1] == 0:
        return None
    theta, _ = ev.predict(effects, i)
    t = np.arange(c.n) * 0.002
    return step_metrics(t, theta, float(u[-1])).overshoot_pct


def study(ev: Evaluator, fit_idx: list[int], other_idx: list[int], names: tuple, out=print) -> dict:
    """Fit one structure leave-one-run-out and on all fit runs; print and return its values."""
    axes = effect_axes()
    folds, _ = make_folds(len(fit_idx), 0)
    t0 = time.perf_counter()
    start = {k: v for k, v in START.items() if k in names or (k == "coulomb_friction" and "static_friction" in names)}
    tr = trial(ev, folds, names, axes, [start for _ in folds])
    out(f"\n== {' + '.join(names)}")
    num = den = 0.0
    for fold, values in zip(folds, tr.fold_values):
        i = fold.val[0]
        st = tr.val_sse[i][0]
        s0 = ev.sse({}, i)[0]
        num, den = num + st, den + s0
        vals = ", ".join(f"{k} {v:.3g}" for k, v in values.items())
        out(f"  held out {short(ev.cases[i].path):34s} {vals:60s} θ RMS {math.sqrt(s0 / ev.cases[i].n):6.2f}"
            f" -> {math.sqrt(st / ev.cases[i].n):6.2f}  gain {100 * (1 - math.sqrt(st / s0)):5.1f} %")
    loo = 100 * (1 - math.sqrt(num / den))
    out(f"  leave-one-run-out θ RMS gain (pooled): {loo:.1f} %")
    # the refit starts from the folds' median values: the cost is piecewise constant and its
    # valley flat, and any one fold's values would pull the refit towards that fold's end
    middle = {k: float(np.median([fv[k] for fv in tr.fold_values])) for k in tr.fold_values[0]}
    final = fit_set(ev, set_axes(names, axes), fit_idx, middle)
    out("  refitted on all: " + ", ".join(f"{k} = {v:.4g}" for k, v in final.items()))
    fin_num = sum(ev.sse(final, i)[0] for i in fit_idx)
    fin_den = sum(ev.sse({}, i)[0] for i in fit_idx)
    out(f"  in-sample θ RMS gain {100 * (1 - math.sqrt(fin_num / fin_den)):.1f} %")
    for i in fit_idx:
        os_ = overshoot(ev, final, i)
        rig = RIG_OVERSHOOT.get(Path(ev.cases[i].path).name)
        if os_ is not None and rig is not None:
            out(f"  overshoot {short(ev.cases[i].path):34s} rig {rig:5.2f} %  model {os_:5.2f} %  ({os_ - rig:+.2f})")
    other_gain = {}
    num = den = 0.0
    for i in other_idx:
        s0, s1 = ev.sse({}, i)[0], ev.sse(final, i)[0]
        num, den = num + s1, den + s0
        other_gain[ev.cases[i].path] = 100 * (1 - math.sqrt(s1 / s0))
        out(f"  not fitted: {short(ev.cases[i].path):34s} θ RMS {math.sqrt(s0 / ev.cases[i].n):6.2f} ->"
            f" {math.sqrt(s1 / ev.cases[i].n):6.2f}  gain {other_gain[ev.cases[i].path]:6.1f} %")
    if other_idx:
        out(f"  not fitted, pooled θ RMS gain {100 * (1 - math.sqrt(num / den)):.1f} %")
    out(f"  ({ev.simulations} simulations, {time.perf_counter() - t0:.0f} s)")
    return {"loo": loo, "values": final}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--session", choices=["2014", "2009"], default="2014",
                   help="fit on the four thesis logs (2014) or the 2009 session's four")
    p.add_argument("--effects", action="append",
                   help="a structure, comma-separated effect names (repeatable; default: three)")
    p.add_argument("--weight", choices=["ml", "ml-theta", "noise", "theta"], default="ml",
                   help="the fits' cost: maximum likelihood with an unknown error variance per "
                        "run and signal (the diagnosis's, station.diagnosis.runs.cost), the same on θ "
                        "alone, or the sum of θ's and a's errors each by its noise level (the "
                        "diagnosis's before), or that on θ alone")
    p.add_argument("--fit-samples", type=int, default=0,
                   help="fit on the first N samples of each fit log (0: whole logs); the "
                        "logs not fitted are always judged whole")
    p.add_argument("--save-model", help="write the last structure refitted on all fit logs")
    args = p.parse_args(argv)
    fit_paths = THESIS if args.session == "2014" else SESSION_2009
    other = (OTHER_2014 + SESSION_2009) if args.session == "2014" else (THESIS + OTHER_2014)
    tmp = tempfile.TemporaryDirectory()
    cases = [load_case(head(RIG / f, args.fit_samples, Path(tmp.name))) for f in fit_paths]
    cases += [load_case(RIG / f) for f in other]
    ev = Evaluator(cases, as_model("tmm-fit"), likelihood=args.weight.startswith("ml"))
    calibrate_noise(ev)
    if args.weight in ("theta", "ml-theta"):
        for c in ev.cases:
            c.sigma_a = math.inf
    fit_idx = list(range(len(fit_paths)))
    other_idx = list(range(len(fit_paths), len(cases)))
    structures = [tuple(s.split(",")) for s in args.effects] if args.effects else STRUCTURES
    print(f"fit on the {args.session} logs ({len(fit_idx)}), cost weighting: {args.weight}", file=sys.stderr)
    res = None
    for names in structures:
        res = study(ev, fit_idx, other_idx, names)
    if args.save_model and res is not None:
        as_model("tmm-fit").with_effects(res["values"], name=f"rig study {args.session}").save(args.save_model)
        print(f"model: {args.save_model}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
