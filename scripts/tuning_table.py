#!/usr/bin/env python3
"""Write docs/tuning.md and its figures: ``station tune`` for the rig's three experiments.

For each of the thesis's experiments (P kp = 2 step 50, lead step 100, lead + accelerometer
step 200) it designs the rig's structure on the built-in ``rig`` model with its default doubt
(:func:`station.design.tune`, the defaults of ``station tune``), then tabulates, beside the
thesis's table (its rig experiments), the thesis's compensator and the tuned one on the model,
over the design's model set, and over models the design never saw (a fresh draw from the same
doubt with another seed, and the nominal tmm-fit FEM). Every number in docs/tuning.md comes
from this script: rerun it when the ``rig`` model changes.

Usage: ``python scripts/tuning_table.py [--jobs N] [--unseen N] [--out docs/tuning.md]``
(figures go to ``docs/figures/tune-<structure>-{steps,bode,robust}.png``).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

EXPERIMENTS = (("p", 50.0, "24.00 % / 1.250 s", None), ("p", 50.0, "24.00 % / 1.250 s", 0),
               ("lead", 100.0, "10.00 % / > 2 s", None), ("lead-accel", 200.0, "21.50 % / 0.608 s", None))
"""(structure, step, the thesis's experiment on the rig: overshoot / thesis settling time, drawn
models: None for station tune's default, 0 for the model alone)."""


def _s(x) -> str:
    return "not settled" if x is None else f"{x:.3f} s"


def _worst(figs, key):
    vals = [getattr(f, key) for f in figs]
    return None if any(v is None for v in vals) else max(vals)


def _ratios(tuned, thesis) -> list[float]:
    """Tuned / thesis 2 % settling time per model where both settle."""
    return [f.settling_2pct_s / b.settling_2pct_s for f, b in zip(tuned, thesis)
            if f.settling_2pct_s is not None and b.settling_2pct_s]


def _row(label, figs) -> str:
    met = sum(1 for f in figs if f.settling_2pct_s is not None)
    os_ = max(f.overshoot_pct for f in figs)
    return (f"| {label} | {os_:.1f} % | {_s(_worst(figs, 'settling_2pct_s'))} | "
            f"{_s(_worst(figs, 'settling_thesis_s'))} | {max(f.peak_command for f in figs):.0f} | "
            f"{met}/{len(figs)} |")


def _figures(result, folder: Path, structure: str, tag: str) -> list[str]:
    from station.design.figures import bode_figure, robust_figure, steps_figure
    from station.design.space import thesis_compensator
    from station.plots import save_figure

    tuned = result.file.compensator()
    thesis = thesis_compensator(structure, result.space.limit)
    names = (f"thesis {structure}", f"tuned {structure}")
    out = []
    for kind, fig in (("steps", steps_figure(result.nominal, tuned, thesis, result.amplitude, names)),
                      ("bode", bode_figure(result.nominal, tuned, thesis, result.margins, names)),
                      ("robust", robust_figure(result.robust.models, tuned, thesis, result.amplitude, result.figures,
                                               result.baseline, result.requirements.overshoot_pct, names))):
        name = f"tune-{tag}-{kind}.png"
        save_figure(fig, folder / name)
        out.append(name)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=int, default=2, help="local worker processes (default 2)")
    parser.add_argument("--unseen", type=int, default=40, help="models of the unseen draw (default 40)")
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "tuning.md", help="the Markdown file")
    args = parser.parse_args(argv)

    from station.design import tune
    from station.design.evaluate import judge
    from station.design.robust import default_intervals, sample_models
    from station.design.space import thesis_compensator
    from station.plant import load_model

    folder = args.out.parent / "figures"
    folder.mkdir(parents=True, exist_ok=True)
    rig = load_model("rig")
    unseen = sample_models(rig, default_intervals(rig), args.unseen, seed=12345)
    outside = load_model("tmm-fit")
    rows, sections, times = [], [], []
    for structure, amplitude, rig_thesis, samples in EXPERIMENTS:
        t = time.perf_counter()
        extra = {} if samples is None else {"samples": samples}
        r = tune("rig", structure=structure, amplitude=amplitude, jobs=args.jobs, out=f"tuned-{structure}.toml",
                 **extra)
        tag = structure if samples is None else f"{structure}-alone"
        label = f"{structure}, step {amplitude:g}" + ("" if samples is None else ", the model alone (--samples 0)")
        times.append((tag, time.perf_counter() - t, r.evaluations))
        thesis = thesis_compensator(structure, r.space.limit)
        tuned = r.file.compensator()
        new_t = [judge(m, tuned, amplitude) for m in unseen]
        new_b = [judge(m, thesis, amplitude) for m in unseen]
        out_t, out_b = judge(outside, tuned, amplitude), judge(outside, thesis, amplitude)
        ratios = _ratios(r.figures, r.baseline)
        unseen_ratios = _ratios(new_t, new_b)
        pngs = _figures(r, folder, structure, tag)
        n = len(r.figures)
        rows.append(f"| {label} | {rig_thesis} | "
                    f"{r.baseline[0].overshoot_pct:.1f} % / {_s(r.baseline[0].settling_2pct_s)} | "
                    f"{r.figures[0].overshoot_pct:.1f} % / {_s(r.figures[0].settling_2pct_s)} | "
                    f"{max(f.overshoot_pct for f in r.figures):.1f} % / {_s(_worst(r.figures, 'settling_2pct_s'))} | "
                    f"{max(f.overshoot_pct for f in new_t):.1f} % / {_s(_worst(new_t, 'settling_2pct_s'))} |")
        params = ", ".join(f"{k} = {v:.4g}" for k, v in r.values.items())
        met = r.met()
        sec = [f"### {label}", "",
               f"Parameters: {params}. Margins on the model (python-control): gain "
               f"{r.margins.gain_margin_db:.1f} dB, phase {r.margins.phase_margin_deg:.1f}° (the thesis's: "
               f"{r.baseline_margins.gain_margin_db:.1f} dB, {r.baseline_margins.phase_margin_deg:.1f}°). "
               f"Requirements met on {sum(met)} of {n} models of the design's set"
               + (f"; 2 % settling {min(ratios):.2f}-{max(ratios):.2f}x the thesis's on the same model"
                  if ratios else "")
               + (f" ({min(unseen_ratios):.2f}-{max(unseen_ratios):.2f}x on the unseen draw)" if unseen_ratios else "")
               + ".", "",
               "```toml", r.file.to_toml().rstrip(), "```", "",
               "| compensator, models | worst overshoot | worst 2 % settling | worst thesis settling (1 %) | "
               "peak command | settled (2 %) |", "|---|---|---|---|---|---|",
               _row(f"thesis, design set ({n})", r.baseline), _row(f"tuned, design set ({n})", r.figures),
               _row(f"thesis, unseen ({len(unseen)})", new_b), _row(f"tuned, unseen ({len(unseen)})", new_t),
               _row("thesis, tmm-fit (outside the doubt)", [out_b]),
               _row("tuned, tmm-fit (outside the doubt)", [out_t]), "",
               *[f"![{p}](figures/{p})" for p in pngs], ""]
        sections += sec
    from station.design.robust import DEFAULT_DOUBT
    from station.design.tuning import DEFAULT_SAMPLES

    doubt = "; ".join(f"{name} {'x' if how == 'ratio' else ''}{lo:g}..{hi:g}" for name, how, lo, hi in DEFAULT_DOUBT)
    text = "\n".join([
        "# Tuned compensators for the rig",
        "",
        "<!-- generated by scripts/tuning_table.py: edit the script, not this file -->",
        "",
        "`station tune` designs a compensator of the rig's own structure on a model, judges it on a",
        "set of models (the model's doubt), and proves it on the simulated rig before it writes it",
        "(DESIGN.md \"Designing a compensator on a model\"; README \"Designing a compensator\").",
        "Below: the rig's three experiments, designed on the built-in `rig` model",
        f"({', '.join(f'{k} = {v:.4g}' for k, v in rig.effect_dict().items())}) with `station tune`'s",
        "defaults: overshoot ≤ 5 %, gain margin ≥ 6 dB, phase margin ≥ 30°, no limit cycle, the clamp",
        f"at ±200 DAC counts, a two-impulse reference shaper searched with the rest, and the rig's",
        f"default doubt ({doubt}; effects the simulator does not have are left out), {DEFAULT_SAMPLES} models drawn",
        f"from it beside the nominal. \"Unseen\" models are a fresh draw of {args.unseen} from the same",
        "doubt (another seed): the designs never saw them. The nominal tmm-fit FEM (no friction, half",
        "the drive damping) lies outside the doubt; it is shown apart.",
        "",
        "Settling times are the 2 % band's after the step (python-control's `step_info` definition",
        "with the station's 0.1 s hold), overshoot the thesis's; every run is the 2 s step of",
        "`station step` on the simulated rig (v1, commands rounded to whole counts, θ and a counted).",
        "",
        "| experiment | thesis's experiment on the rig (overshoot / 1 % settling) | thesis's compensator, "
        "rig model | tuned, rig model | tuned, worst over its design set | tuned, worst over unseen models |",
        "|---|---|---|---|---|---|",
        *rows,
        "",
        "P cannot promise a 2 % band of a 50-count step (1 encoder count) when the motor has dry",
        "friction: a hub that stops with |kp·e| below the friction level stays there (8 counts and",
        "more at the rig's 15.5 counts of friction and the kp a 30° phase margin allows), so a P loop",
        "settles into one count only when the hub happens to stop inside it, on some models and not",
        "on others. Over the rig's doubt no P design the search found meets the band on more than a",
        "few models, and the robust P gives up even the model itself; designed on the model alone",
        "(`--samples 0`, the second row) the tuned P settles about as fast as the thesis's with a few",
        "percent of overshoot instead of 24 %: for P, design on the model alone. Lead and lead +",
        "accelerometer meet every requirement on every model of their sets and of the unseen draw.",
        "",
        "The requirements are on the hub angle θ (the thesis's metrics). The tuned lead +",
        "accelerometer stops the hub sooner but leaves the beam ringing a little longer once the hub",
        "has stopped (the tip acceleration a in its step figure, small but visible to about 1 s, where",
        "the thesis's is quiet by 0.6 s): a bound on a after settling would be the next requirement.",
        "",
        *sections,
        "## Reproduce",
        "",
        "```sh",
        "python scripts/tuning_table.py            # this page and docs/figures/tune-*.png",
        "station tune --model rig --controller lead-accel --amplitude 200 --out C.toml --report report/",
        "station step --controller C.toml --amplitude 200 --model rig",
        "```",
        "",
        "Design times here (2 local processes, load average "
        f"{os.getloadavg()[0]:.1f}): " + ", ".join(f"{s} {sec:.0f} s ({n} evaluations)" for s, sec, n in times) + ".",
        "",
    ])
    args.out.write_text(text, encoding="utf-8")
    print(f"wrote {args.out} and {folder}/tune-*.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
