#!/usr/bin/env python3
"""Write docs/tuning.md and its figures: ``station tune`` for the rig's three experiments, the
hub against the tip, what each structure can do, and the held-out check.

For each of the thesis's experiments (P kp = 2 step 50, lead step 100, lead + accelerometer
step 200) it designs the rig's structure on the built-in ``rig`` model with its default doubt
(:func:`station.design.tune`, the defaults of ``station tune``), then tabulates, beside the
thesis's table (its rig experiments), the thesis's compensator and the tuned one on the model,
over the design's model set, and over models the design never saw (a fresh draw from the same
doubt with another seed, and the nominal tmm-fit FEM): the hub (overshoot, 2 % settling) and
the tip (its 2 % settling, its residual RMS from 0.6 s after the step). For lead +
accelerometer it also designs each structure past the thesis's (two-mode shaper, notch or
roll-off in Gth, damper in Ga, no bound on the tip), draws the hub-tip trade-off, probes a notch
on the former fast design, runs the held-out check (scripts/heldout_tune.py: ``station step`` on
rigs the design never saw), sweeps the rule (``--hub-ratio``, and the doubt widened: each design
checked on the held-out rigs) and shows where the limit is (the held-out rigs the rule misses,
each designed for alone and together with ``rig``). Every number in docs/tuning.md comes from this script:
rerun it when the ``rig`` model or the design changes.

Usage: ``python scripts/tuning_table.py [--jobs N] [--unseen N] [--seeds N] [--out docs/tuning.md]``
(figures go to ``docs/figures/tune-<structure>-{steps,bode,robust,tradeoff}.png``).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import os
import time
from pathlib import Path
from unittest import mock

REPO = Path(__file__).resolve().parents[1]

EXPERIMENTS = (("p", 50.0, "24.00 % / 1.250 s", None), ("p", 50.0, "24.00 % / 1.250 s", 0),
               ("lead", 100.0, "10.00 % / > 2 s", None), ("lead-accel", 200.0, "21.50 % / 0.608 s", None))
"""(structure, step, the thesis's experiment on the rig: overshoot / settling (1 %), drawn
models: None for station tune's default, 0 for the model alone)."""

STRUCTURES = (("opt", "none", 1.0, "the thesis's structure: lead, Ga's gain and frequency, two-impulse shaper"),
              ("opt2", "none", 1.0, "the same with a second impulse pair for the second mode (the default)"),
              ("opt2", "notch", 1.0, "and a notch in Gth at the second mode"),
              ("opt2", "rolloff", 1.0, "and a second-order roll-off in Gth"),
              ("opt2", "damper", 1.0, "and a band-pass at the second mode in Ga (active damping)"),
              ("opt2", "none", None, "the default structure with no bound on the tip (the hub alone)"))
"""lead + accelerometer structures compared on rig: (shaper, filter, tip bound, what it is)."""

RULES = ((1.0, False), (0.6, False), (0.55, False), (0.5, False), (0.55, True))
"""(``--hub-ratio``, the doubt widened) the rule table designs lead + accelerometer with: the bar
on the design model, and the default doubt or :data:`WIDE_DOUBT`; 0.55 with the default doubt
is ``station tune``'s default (reused, not designed twice)."""

WIDE_DOUBT = (("coulomb_friction", "absolute", 0.0, 16.0), ("static_friction", "ratio", 0.7, 1.5),
              ("amp_offset", "absolute", -3.0, 3.0), ("param:drive_c", "ratio", 0.48, 1.4),
              ("param:EI", "ratio", 0.8, 1.1))
"""The default doubt with the drive damping down to least squares' 95 % interval (x1.54 of
tmm-fit: 0.48x `rig`'s) and the beam's EI down to 0.8x."""

LIMIT_RIGS = ("tmm-fit (no friction, drive damping x1)", "beam EI x0.8", "rig-2009 (friction 1.2, offset -1.5)")
"""Held-out rigs (scripts/heldout_tune.py's labels) the limit table designs for alone, and
together with ``rig``, with the hidden rigs' bar as the requirement."""

FIRST_HELD_OUT = 9
"""scripts/heldout_tune.py's rigs from this index on were added beside the first nine while the
design rule was chosen (marked "added")."""

FORMER = {"k0": 7.176, "z": 50.24, "ratio": 1.808, "ga_gain": 0.5804, "ga_freq": 0.4487, "shaper_t2": 0.2084,
          "shaper_a2": 0.4238}
"""The former tuned lead + accelerometer (hub only): the notch probe starts from it."""


def _s(x) -> str:
    return "not settled" if x is None else f"{x:.3f} s"


def _x(ratio: float) -> str:
    return "not settled" if not math.isfinite(ratio) else f"{ratio:.2f}x"


def _worst(figs, key):
    vals = [getattr(f, key) for f in figs]
    return None if any(v is None for v in vals) else max(vals)


def _ratios(tuned, thesis) -> list[float]:
    """Tuned / thesis hub 2 % settling time per model where both settle."""
    return [f.settling_2pct_s / b.settling_2pct_s for f, b in zip(tuned, thesis)
            if f.settling_2pct_s is not None and b.settling_2pct_s]


def _tip_ratios(tuned, thesis) -> list[float]:
    from station.design.evaluate import tip_reference

    return [f.tip_residual_rms / tip_reference(b.tip_residual_rms) for f, b in zip(tuned, thesis)]


def _row(label, figs) -> str:
    met = sum(1 for f in figs if f.settling_2pct_s is not None)
    return (f"| {label} | {max(f.overshoot_pct for f in figs):.1f} % | {_s(_worst(figs, 'settling_2pct_s'))} | "
            f"{_s(_worst(figs, 'settling_thesis_s'))} | {_s(_worst(figs, 'tip_settling_2pct_s'))} | "
            f"{max(f.tip_residual_rms for f in figs):.2f} | {max(f.peak_command for f in figs):.0f} | "
            f"{met}/{len(figs)} |")


def _one(f) -> str:
    return f"{f.overshoot_pct:.1f} % / {_s(f.settling_2pct_s)} / {f.tip_residual_rms:.2f}"


def _figures(result, folder: Path, structure: str, tag: str) -> list[str]:
    from station.design.figures import bode_figure, robust_figure, steps_figure, tradeoff_figure
    from station.design.space import thesis_compensator
    from station.plots import save_figure

    import station.design.robust as robust_module

    tuned = result.file.compensator()
    thesis = thesis_compensator(structure, result.space.limit)
    names = (f"thesis {structure}", f"tuned {structure}")
    out = []
    for kind, fig in (("steps", steps_figure(result.nominal, tuned, thesis, result.amplitude, names)),
                      ("bode", bode_figure(result.nominal, tuned, thesis, result.margins, names)),
                      ("robust", robust_figure(result.robust.models, tuned, thesis, result.amplitude, result.figures,
                                               result.baseline, result.requirements.overshoot_pct, names)),
                      ("tradeoff", tradeoff_figure(result.tradeoff, result.tip_rms))):
        name = f"tune-{tag}-{kind}.png"
        save_figure(fig, folder / name)
        out.append(name)
    return out


def _heldout():
    spec = importlib.util.spec_from_file_location("heldout_tune", REPO / "scripts" / "heldout_tune.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _notch_probe(rig) -> list[str]:
    """The former fast design with a notch at the second mode: in Gth as the station runs it
    (its recursion on the clamped command), and with the notch on e in a state of its own."""
    import math

    import numpy as np

    from station.analysis.metrics import step_info, step_metrics
    from station.control.reference import step_reference
    from station.control.tf import tustin
    from station.design.evaluate import judge
    from station.design.space import DesignSpace, filter_s, ga_s, lead_s
    from station.design.tip import residual
    from station.plant.simulate import simulate
    from station.rig import CLAMP, DEFAULT_STEP_TICK, DT

    notch = {"notch_hz": 18.3, "notch_depth": 0.1, "notch_width": 0.1}
    base = DesignSpace("lead-accel", "opt").compensator_file(FORMER).compensator()
    inside = DesignSpace("lead-accel", "opt", filter="notch").compensator_file(dict(FORMER, **notch)).compensator()

    class Filter:
        def __init__(self, num, den):
            self.b, self.a = np.asarray(num, float), np.asarray(den, float)
            self.reset()

        def reset(self):
            self.x, self.y = np.zeros(self.b.size), np.zeros(self.a.size)

        def __call__(self, x, clamp=math.inf):
            self.x = np.r_[x, self.x[:-1]]
            y = min(max((self.b @ self.x - self.a[1:] @ self.y[:-1]) / self.a[0], -clamp), clamp)
            self.y = np.r_[y, self.y[:-1]]
            return y

    class Separate:
        """v = sat(lead(notch(e))), the notch with a state of its own (not a station compensator)."""

        limit = CLAMP

        def __init__(self):
            self.lead = Filter(*tustin(*lead_s(FORMER["k0"], FORMER["z"], FORMER["ratio"]), DT))
            self.ga = Filter(*tustin(*ga_s(FORMER["ga_gain"], FORMER["ga_freq"]), DT))
            self.notch = Filter(*tustin(*filter_s("notch", notch), DT))
            self.shaper = base.shaper

        def reset(self):
            for f in (self.lead, self.ga, self.notch, self.shaper):
                f.reset()

        def step(self, u, theta, a):
            r = self.shaper.step(u) - self.ga(a)
            return self.lead(self.notch(r - theta), self.limit), r

    u = step_reference(200.0, 1000, at_tick=DEFAULT_STEP_TICK)
    rows = []
    for label, comp in (("the former design (hub only)", base), ("with the notch in Gth (as the station runs it)", inside)):
        f = judge(rig, comp, 200.0)
        rows.append(f"| {label} | {f.gain_margin_db:.1f} dB / {f.phase_margin_deg:.1f}° | {_one(f)} |")
    run = simulate(rig, Separate(), u, alignment=1, command="round")
    info = step_info(run.t, run.theta, 200.0, run.t[DEFAULT_STEP_TICK])
    rows.append(f"| with the notch on e, a state of its own (not a station compensator) | same as in Gth | "
                f"{step_metrics(run.t, run.theta, 200.0).overshoot_pct:.1f} % / {_s(info.settling_time_2pct_s)} / "
                f"{residual(run.a, DEFAULT_STEP_TICK).rms:.2f} |")
    return rows


def _hub_ok(figures, baseline, bar: float = 0.6) -> int:
    """Models where the hub settles (2 %) in at most ``bar`` times the thesis's time."""
    return sum(1 for f, b in zip(figures, baseline)
               if f.settling_2pct_s is not None and b.settling_2pct_s and f.settling_2pct_s <= bar * b.settling_2pct_s)


def _check(heldout, result, folder: Path, seeds: int) -> list[dict]:
    """The held-out check of a lead + accelerometer design (scripts/heldout_tune.py)."""
    controller = folder / "tuned-lead-accel-heldout.toml"
    try:
        controller.write_text(result.file.to_toml(), encoding="utf-8")
        return heldout.check(controller, seeds)
    finally:
        controller.unlink(missing_ok=True)


def _meets(r, i) -> bool:
    """The hidden rigs' bar on model ``i`` of a design (without noise)."""
    f, b = r.figures[i], r.baseline[i]
    return (f.settling_2pct_s is not None and b.settling_2pct_s is not None and f.overshoot_pct <= 8.0
            and f.settling_2pct_s <= 0.6 * b.settling_2pct_s and f.tip_residual_rms <= 1.5 * max(b.tip_residual_rms, 0.3))


def _limit_rows(heldout, jobs: int) -> tuple[list[str], list[tuple[str, bool, bool, float]]]:
    """Each of :data:`LIMIT_RIGS` designed for alone, and together with ``rig``, on the hidden
    rigs' bar (overshoot 8 %, tip 1.5x, hub 0.6x on the design model): the table's rows, and
    per rig (label, the bar met alone, met on both together, the pair's worst tip ratio)."""
    import tempfile

    from station.design import tune

    rigs = dict(heldout.held_out_models())
    bar = {"overshoot": 8.0, "tip_rms": 1.5, "hub_ratio": 0.6, "samples": 0, "front": 0, "jobs": jobs}

    def ratios(r, i):
        f, b = r.figures[i], r.baseline[i]
        hub = "not settled" if f.settling_2pct_s is None else f"{f.settling_2pct_s / b.settling_2pct_s:.2f}x"
        return f"{hub} / {f.tip_residual_rms / max(b.tip_residual_rms, 0.3):.2f}x / {f.overshoot_pct:.1f} %"

    rows, found = [], []
    with tempfile.TemporaryDirectory(prefix="tuning-limit-") as tmp:
        for label in LIMIT_RIGS:
            path = Path(tmp) / "rig-x.toml"
            rigs[label].save(path)
            alone = tune(rigs[label], structure="lead-accel", amplitude=200.0, **bar)
            both = tune("rig", structure="lead-accel", amplitude=200.0, robust=[path], **bar)
            path.unlink()
            rows.append(f"| {label} | {ratios(alone, 0)} | {ratios(both, 0)} | {ratios(both, 1)} |")
            found.append((label.split(" (")[0], _meets(alone, 0), _meets(both, 0) and _meets(both, 1),
                          max(f.tip_residual_rms / max(b.tip_residual_rms, 0.3) for f, b in zip(both.figures,
                                                                                                  both.baseline))))
            print(f"limit {label}: alone {ratios(alone, 0)}; with rig {ratios(both, 0)} and {ratios(both, 1)}",
                  flush=True)
    return rows, found


def _limit_words(found) -> str:
    """The limit table in words (:func:`_limit_rows`' findings)."""
    def names(xs):
        return ", ".join(xs) if xs else "none"
    alone = [n for n, a, _, _ in found if a]
    pair = [(n, t) for n, _, p, t in found if p]
    none = [n for n, _, p, _ in found if not p]
    text = (f"- **One compensator for `rig` and such a rig?** Designed for each alone on the hidden rigs' bar "
            f"(the last table), the bar is met on {names(alone)}")
    if pair:
        text += (f"; designed for `rig` and it together, one design meets it on both for "
                 f"{names([n for n, _ in pair])}, its tip at up to {max(t for _, t in pair):.2f}x the thesis's "
                 f"(the rule asks 1x on every model of its set, and no design found holds that and the set's "
                 f"corners too)")
    if none:
        text += (f"; for {names(none)} together with `rig` the search finds none: one compensator of this "
                 f"structure does not serve both")
    return text + "."


def _fails_words(r) -> str:
    """Which models of the set the design misses (the hub above 0.6x, or any requirement), in words."""
    from station.design.evaluate import violations

    rig_c = r.nominal.effect("param:drive_c")
    low = [m.effect("param:drive_c") <= 0.75 * rig_c for m in r.robust.models]
    hub = [i for i, (f, b) in enumerate(zip(r.figures, r.baseline))
           if not (f.settling_2pct_s and b.settling_2pct_s and f.settling_2pct_s <= 0.6 * b.settling_2pct_s)]
    tip = [i for i, (f, q) in enumerate(zip(r.figures, r.model_requirements())) if "tip" in violations(f, q)]
    no_friction = [r.robust.models[i].effect("coulomb_friction") == 0 for i in tip]
    return (f"Of the {len(hub)} models where the hub is above 0.6x, {sum(low[i] for i in hub)} have the drive "
            f"damping in the doubt's lowest quarter (at most {0.75 * rig_c:.2f}x tmm-fit's, `rig` {rig_c:.2f}x); "
            f"of the {len(tip)} where the tip is louder than the thesis's, {sum(no_friction)} have no friction.")


def _limit_figure(rules):
    """Per rule (the bar on the design model): each model's hub settling (2 %) over the thesis's,
    on the design set and on the held-out rigs, against the hidden rigs' bar of 0.6x."""
    import numpy as np

    from station.plots import new_figure

    fig = new_figure(9, 5)
    ax = fig.subplots()
    top = 1.6
    for k, (_, r, held) in enumerate(rules):
        hub = [f.settling_2pct_s / b.settling_2pct_s if f.settling_2pct_s and b.settling_2pct_s else top
               for f, b in zip(r.figures, r.baseline)]
        jitter = np.linspace(-0.12, 0.12, len(hub))
        ax.scatter(k - 0.15 + jitter, np.minimum(hub, top), s=12, color="0.55",
                   label="the design set's models" if k == 0 else None)
        ax.scatter([k - 0.15], [min(hub[0], top)], s=60, marker="D", color="C0", zorder=5,
                   label="rig (the design model)" if k == 0 else None)
        for met in (True, False):
            ys = [min(h["hub_ratio"], top) for h in held if h["met"] == met]
            ax.scatter(k + 0.15 + np.linspace(-0.08, 0.08, len(ys)), ys, s=22, marker="o" if met else "x",
                       color="C2" if met else "C3",
                       label=(("held-out rig: bar met" if met else "held-out rig: bar NOT met") if k == 0 else None))
    ax.axhline(0.6, color="C2", lw=0.8, ls=":", label="hidden rigs' bar: 0.6x")
    ax.set_xticks(range(len(rules)), [f"--hub-ratio {label}".replace(", ", "\n") for label, _, _ in rules])
    ax.set_ylabel("hub settling (2 %) / the thesis's")
    ax.set_title(f"per model, against the thesis's on the same model ({top:g}: more, or not settled); "
                 f"held-out: the worst noise seed", fontsize=9)
    ax.set_ylim(0.3, top + 0.05)
    ax.grid(True, axis="y", lw=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return fig


def main(argv: list[str] | None = None) -> int:
    import sys

    sys.path.insert(0, str(REPO))
    from station.ranges import number

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=number(1, 64, integer=True), default=2,
                        help="local worker processes (default 2)")
    parser.add_argument("--unseen", type=number(1, 1000, integer=True), default=40,
                        help="models of the unseen draw (default 40)")
    parser.add_argument("--seeds", type=number(1, 100, integer=True), default=3,
                        help="noise seeds per held-out rig (default 3)")
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "tuning.md", help="the Markdown file")
    args = parser.parse_args(argv)

    from station.analysis.metrics import STEP_INFO_BAND_PCT, THESIS_BAND_PCT, settling_label
    from station.design import tune
    from station.design.evaluate import judge, violations
    from station.design.hold import held_summary
    from station.design.robust import DEFAULT_DOUBT, default_intervals, sample_models
    from station.design.space import thesis_compensator
    from station.design.tuning import DEFAULT_SAMPLES
    from station.plant import load_model
    from station.plots import save_figure

    import station.design.robust as robust_module

    s1, s2 = settling_label(THESIS_BAND_PCT), settling_label(STEP_INFO_BAND_PCT)
    folder = args.out.parent / "figures"
    folder.mkdir(parents=True, exist_ok=True)
    rig = load_model("rig")
    unseen = sample_models(rig, default_intervals(rig), args.unseen, seed=12345)
    outside = load_model("tmm-fit")
    rows, sections, times, p_summary, met_lines, la = [], [], [], [], [], None
    for structure, amplitude, rig_thesis, samples in EXPERIMENTS:
        t = time.perf_counter()
        extra = {} if samples is None else {"samples": samples}
        r = tune("rig", structure=structure, amplitude=amplitude, jobs=args.jobs, out=f"tuned-{structure}.toml",
                 **extra)
        tag = structure if samples is None else f"{structure}-alone"
        label = f"{structure}, step {amplitude:g}" + ("" if samples is None else ", the model alone (--samples 0)")
        times.append((tag, time.perf_counter() - t, r.evaluations))
        print(f"{tag}: {times[-1][1]:.0f} s", flush=True)
        thesis = thesis_compensator(structure, r.space.limit)
        tuned = r.file.compensator()
        new_t = [judge(m, tuned, amplitude) for m in unseen]
        new_b = [judge(m, thesis, amplitude) for m in unseen]
        out_t, out_b = judge(outside, tuned, amplitude), judge(outside, thesis, amplitude)
        ratios, tips = _ratios(r.figures, r.baseline), _tip_ratios(r.figures, r.baseline)
        unseen_ratios, unseen_tips = _ratios(new_t, new_b), _tip_ratios(new_t, new_b)
        pngs = _figures(r, folder, structure, tag)
        n = len(r.figures)
        rows.append(f"| {label} | {rig_thesis} | {_one(r.baseline[0])} | {_one(r.figures[0])} | "
                    f"{max(f.overshoot_pct for f in r.figures):.1f} % / {_s(_worst(r.figures, 'settling_2pct_s'))} / "
                    f"{max(f.tip_residual_rms for f in r.figures):.2f} | "
                    f"{max(f.overshoot_pct for f in new_t):.1f} % / {_s(_worst(new_t, 'settling_2pct_s'))} / "
                    f"{max(f.tip_residual_rms for f in new_t):.2f} |")
        params = ", ".join(f"{k} = {v:.4g}" for k, v in r.values.items())
        met = r.met()
        held = held_summary(r.figures, r.model_requirements())
        sec = [f"### {label}", "",
               f"Parameters: {params}. Margins on the model (python-control): gain "
               f"{r.margins.gain_margin_db:.1f} dB, phase {r.margins.phase_margin_deg:.1f}° (the thesis's: "
               f"{r.baseline_margins.gain_margin_db:.1f} dB, {r.baseline_margins.phase_margin_deg:.1f}°). "
               f"Requirements met on {sum(met)} of {n} models of the design's set"
               + (f"; hub {s2} {min(ratios):.2f}-{max(ratios):.2f}x the thesis's on the same model"
                  if ratios else "")
               + (f" ({min(unseen_ratios):.2f}-{max(unseen_ratios):.2f}x on the unseen draw)" if unseen_ratios else "")
               + f"; tip residual RMS {min(tips):.2f}-{max(tips):.2f}x the thesis's "
               f"({min(unseen_tips):.2f}-{max(unseen_tips):.2f}x on the unseen draw).", "",
               *([f"Friction: {held['note']}.", ""] if held["note"] else []),
               *[line for w in r.warnings() for line in (f"Warning: {w}.", "")],
               "```toml", r.file.to_toml().rstrip(), "```", "",
               f"| compensator, models | worst overshoot | worst hub {s2} | worst hub {s1} | worst tip {s2} | "
               f"worst tip residual RMS | peak command | hub settled (2 % band) |", "|---|---|---|---|---|---|---|---|",
               _row(f"thesis, design set ({n})", r.baseline), _row(f"tuned, design set ({n})", r.figures),
               _row(f"thesis, unseen ({len(unseen)})", new_b), _row(f"tuned, unseen ({len(unseen)})", new_t),
               _row("thesis, tmm-fit (outside the doubt)", [out_b]),
               _row("tuned, tmm-fit (outside the doubt)", [out_t]), "",
               *[f"![{p}](figures/{p})" for p in pngs], ""]
        sections += sec
        if structure != "p":
            unseen_met = sum(not violations(f, r.requirements._replace(tip_rms=1.0 * max(b.tip_residual_rms, 0.3)))
                             for f, b in zip(new_t, new_b))
            met_lines.append(f"The tuned {structure} meets every requirement (the tip's included) on {sum(met)} of {n} "
                             f"models of its set and on {unseen_met} of {len(new_t)} of the unseen draw.")
        if structure == "p" and samples is None:
            b, f = r.baseline[0], r.figures[0]
            p_summary = [f"The robust P {'meets' if met[0] else 'does NOT meet'} every requirement on the model: "
                         f"{f.overshoot_pct:.1f} % / {_s(f.settling_2pct_s)} against the thesis's P's "
                         f"{b.overshoot_pct:.1f} % / {_s(b.settling_2pct_s)}; over its set it overshoots at most "
                         f"{max(x.overshoot_pct for x in r.figures):.1f} % (the thesis's P "
                         f"{max(x.overshoot_pct for x in r.baseline):.1f} %) and meets every requirement on "
                         f"{sum(met)} of {n} models."]
        if structure == "lead-accel":
            la = r

    # the structures, lead + accelerometer on rig
    structure_rows = []
    for shaper, filt, tip, what in STRUCTURES:
        t = time.perf_counter()
        r = la if (shaper, filt, tip) == (la.space.shaper, la.space.filter, la.tip_rms) else \
            tune("rig", structure="lead-accel", amplitude=200.0, jobs=args.jobs, shaper=shaper, filter=filt,
                 tip_rms=tip)
        sec_t = time.perf_counter() - t if r is not la else times[-1][1]
        print(f"structure {shaper}/{filt}/{tip}: {sec_t:.0f} s", flush=True)
        c = r.tradeoff.points[r.tradeoff.chosen]
        f0, b0 = r.figures[0], r.baseline[0]
        hub_ok = sum(1 for f, b in zip(r.figures, r.baseline)
                     if f.settling_2pct_s is not None and b.settling_2pct_s and f.settling_2pct_s <= 0.6 * b.settling_2pct_s)
        structure_rows.append(
            f"| {what} | {shaper} / {filt} / {'none' if tip is None else f'{tip:g}x'} | "
            f"{f0.overshoot_pct:.1f} % / {f0.settling_2pct_s / b0.settling_2pct_s:.2f}x / "
            f"{f0.tip_residual_rms / max(b0.tip_residual_rms, 0.3):.2f}x | {c.hub_ratio:.2f}x | {c.tip_ratio:.2f}x | "
            f"{c.overshoot_pct:.1f} % | {hub_ok}/{len(r.figures)} | {sum(r.met())}/{len(r.figures)} | "
            f"{sec_t:.0f} s |")

    probe = _notch_probe(rig)
    heldout = _heldout()
    held_rows = _check(heldout, la, folder, args.seeds)
    held_met = sum(r["met"] for r in held_rows)
    print(f"held-out: {held_met} of {len(held_rows)}", flush=True)

    # the rule: the bar on the design model, swept (the default's design and check reused)
    rules = []
    for ratio, wide in RULES:
        label = f"{ratio:g}" + (", the doubt widened" if wide else "")
        if ratio == la.hub_ratio and not wide:
            rules.append((label, la, held_rows))
            continue
        with mock.patch.object(robust_module, "DEFAULT_DOUBT", WIDE_DOUBT if wide else robust_module.DEFAULT_DOUBT):
            r = tune("rig", structure="lead-accel", amplitude=200.0, jobs=args.jobs, hub_ratio=ratio, front=0)
        rules.append((label, r, _check(heldout, r, folder, args.seeds)))
        print(f"rule --hub-ratio {label}: held-out {sum(h['met'] for h in rules[-1][2])}", flush=True)

    def rule_line(label, r, held):
        f, b = r.figures[0], r.baseline[0]
        hub = [h["hub_ratio"] for h in held]
        failed = ", ".join(h["rig"].split(" (")[0] for h in held if not h["met"]) or "none"
        ratios_set = [g.settling_2pct_s / h.settling_2pct_s if g.settling_2pct_s and h.settling_2pct_s else math.inf
                      for g, h in zip(r.figures, r.baseline)]
        tips_set = _tip_ratios(r.figures, r.baseline)
        return (f"| {label}{' (default)' if r is la else ''} | {f.overshoot_pct:.1f} % / "
                f"{f.settling_2pct_s / b.settling_2pct_s:.2f}x / {f.tip_residual_rms / max(b.tip_residual_rms, 0.3):.2f}x "
                f"| {sum(r.met())}/{len(r.figures)} | {_hub_ok(r.figures, r.baseline)}/{len(r.figures)} | "
                f"{_x(max(ratios_set))} / {_x(max(tips_set))} | {sum(h['met'] for h in held)}/{len(held)} "
                f"| {sum(x <= 0.6 for x in hub)}/{len(held)} ({min(hub):.2f}-{sorted(hub)[len(hub) // 2]:.2f}x) "
                f"| {failed} |")

    rule_rows = [rule_line(*rr) for rr in rules]
    save_figure(_limit_figure(rules), folder / "tune-lead-accel-limit.png")
    limit_rows, limit_found = _limit_rows(heldout, args.jobs)

    def held_line(h, i):
        worst = max(h["runs"], key=lambda r: (not r["meets_bar"], r["hub_ratio"], r["tip_ratio"]))
        th, tu = worst["thesis"], worst["tuned"]
        return (f"| {h['rig']}{' (added)' if i >= FIRST_HELD_OUT else ''} | {th['overshoot_pct']:.1f} % / "
                f"{_s(th['settling_2pct_s'])} / {th['tip_residual_rms']:.2f} | {tu['overshoot_pct']:.1f} % / "
                f"{_s(tu['settling_2pct_s'])} / {tu['tip_residual_rms']:.2f} | {h['hub_ratio']:.2f}x | "
                f"{h['tip_ratio']:.2f}x | {'met' if h['met'] else 'NOT met'} |")

    f, b = la.figures[0], la.baseline[0]
    c = la.tradeoff.points[la.tradeoff.chosen]
    hub_ok = _hub_ok(la.figures, la.baseline)
    set_ratios = _ratios(la.figures, la.baseline)
    front = [la.tradeoff.points[i] for i in la.tradeoff.front]
    front_rows = [f"| {'★' if i == la.tradeoff.chosen else ''} | {p.hub_ratio:.2f}x | {p.tip_ratio:.2f}x | "
                  f"{p.overshoot_pct:.1f} % | {'yes' if p.met else 'no'} |"
                  for i, p in zip(la.tradeoff.front, front)]
    if la.tradeoff.chosen not in la.tradeoff.front:
        front_rows.append(f"| ★ (not on the front) | {c.hub_ratio:.2f}x | {c.tip_ratio:.2f}x | {c.overshoot_pct:.1f} % | "
                          f"{'yes' if c.met else 'no'} |")
    doubt = "; ".join(f"{name} {'x' if how == 'ratio' else ''}{lo:g}..{hi:g}" for name, how, lo, hi in DEFAULT_DOUBT)
    text = "\n".join([
        "# Tuned compensators for the rig",
        "",
        "<!-- generated by scripts/tuning_table.py: edit the script, not this file -->",
        "",
        "`station tune` designs a compensator of the rig's own structure (and one step past it) on a",
        "model, judges it on a set of models (the model's doubt), and proves it on the simulated rig",
        "before it writes it (DESIGN.md \"Designing a compensator on a model\"; the command:",
        "[tune.md](tune.md)). It judges the hub and the beam's tip: the **tip position** (hub angle plus",
        "the tip's deflection / L, encoder counts) and its settling, and the tip's **residual",
        "vibration**, the accelerometer's RMS and peak from 0.6 s after the step to the run's end.",
        "Below: the rig's three experiments, designed on the built-in `rig` model",
        f"({', '.join(f'{k} = {v:.4g}' for k, v in rig.effect_dict().items())}) with `station tune`'s",
        "defaults: overshoot ≤ 5 %, gain margin ≥ 6 dB, phase margin ≥ 30°, no limit cycle, the clamp",
        "at ±200 DAC counts, **the tip's residual RMS at most the thesis's compensator's on the same",
        "model** (`--tip-rms 1`; at least the accelerometer's 0.3 counts of noise), a reference shaper of",
        "two impulse pairs (the first beam mode's and the second's, `--shaper opt2`) searched with the",
        f"rest, and the rig's default doubt ({doubt}; effects the simulator does not have are left",
        f"out), its corners and {DEFAULT_SAMPLES} models drawn from it beside the nominal. The doubt is what",
        "the diagnosis of the rig's four thesis logs leaves open (docs/diagnosis.md): friction from",
        "**none** (a rig with less friction than the estimate) to what the open-loop pulses alone ask for,",
        "the drive damping's 95 % interval and least squares' answer, the offsets the pulses and the",
        "2009 session show (either sign: a step the other way), and the beam's EI within 10 %.",
        "\"Unseen\" models are a fresh draw of",
        f"{args.unseen} from the same doubt (another seed): the designs never saw them. The nominal tmm-fit",
        "FEM (no friction, a third of the rig's drive damping) lies outside the doubt; it is shown apart.",
        "",
        f"The rule (`--hub-ratio {la.hub_ratio:g}`, the default): first every requirement on the design model, "
        f"with its hub {s2} at",
        f"most {la.hub_ratio:g}x the thesis's compensator's there; then, over the set, the worst of each model's hub "
        f"{s2}",
        "relative to the thesis's compensator's on that model (a model that fails a requirement adding its",
        "cost). The hidden rigs' bar is 0.6x the thesis's: the margin on the design model is what keeps the",
        "rigs near it, but not in its set, on the right side of that bar ([Where the limit is](#where-the-limit-is)).",
        "",
        f"Settling times are named by their band: **{s2}** is the 2 % band's after the step",
        "(python-control's `step_info` definition with the station's 0.1 s hold), the hub's and the",
        f"tip's alike; **{s1}** is the thesis's (from t = 0 of the run). Overshoot is the thesis's;",
        "every run is the 2 s step of `station step` on the simulated rig (v1, commands rounded to",
        "whole counts, θ and a counted; the design's own runs have no accelerometer noise).",
        "",
        f"| experiment | thesis's experiment on the rig (overshoot / {s1}) | thesis's compensator, rig model "
        f"(overshoot / hub {s2} / tip RMS) | tuned, rig model | tuned, worst over its design set | "
        "tuned, worst over unseen models |",
        "|---|---|---|---|---|---|",
        *rows,
        "",
        "## Lead + accelerometer: the tip as quiet, the hub faster",
        "",
        f"On `rig` the tuned lead + accelerometer settles the hub into the 2 % band in {_s(f.settling_2pct_s)} "
        f"({f.settling_2pct_s / b.settling_2pct_s:.2f}x the thesis's {_s(b.settling_2pct_s)}), overshoots "
        f"{f.overshoot_pct:.1f} % (the thesis's {b.overshoot_pct:.1f} %), and from 0.6 s after the step its "
        f"accelerometer's RMS is {f.tip_residual_rms:.2f} counts against the thesis's {b.tip_residual_rms:.2f} "
        f"(peak {f.tip_residual_peak:.0f} against {b.tip_residual_peak:.0f}); its tip settles into the 2 % band in "
        f"{_s(f.tip_settling_2pct_s)} (the thesis's {_s(b.tip_settling_2pct_s)}). On every model of its set "
        f"({len(la.figures)}) it meets every requirement, the tip's included, on {sum(la.met())}; the hub is at "
        f"most 0.6x the thesis's on {hub_ok} of them (median {sorted(set_ratios)[len(set_ratios) // 2]:.2f}x), and "
        f"at worst {c.hub_ratio:.2f}x (tip {c.tip_ratio:.2f}x). {_fails_words(la)} The limit, and why, below "
        "([Where the limit is](#where-the-limit-is)).",
        "",
        "The former design (the hub alone: 0.266 s on `rig`) left the accelerometer swinging at the",
        "second mode for a second after the hub had stopped; what rings it after 0.6 s is the hub hunting",
        "between encoder counts, each count change kicking the command by the lead's high-frequency gain.",
        "The tuned design trades gain for quiet: a lower DC gain (friction then holds the hub inside the",
        "band instead of hunting), and a second impulse pair in the shaper, half a period of the closed",
        "loop's second mode apart, that leaves the second mode unexcited by the step.",
        "",

        "",
        "### The trade-off",
        "",
        f"Every design the search judged on every model ({len(la.tradeoff.points)}), by its worst hub {s2} and",
        "its worst tip residual RMS over the set, each relative to the thesis's compensator on the same",
        "model; the front holds those no other design beats on both (among those meeting overshoot,",
        "margins and rest everywhere), ★ the chosen one."
        + ("" if la.tradeoff.chosen in la.tradeoff.front else
           f" It is not on the front: the rule puts the hub on `rig` first (at most {la.hub_ratio:g}x the "
           "thesis's there), and the designs that beat it on the set's worst models settle later on `rig` "
           "(the worst models are the doubt's corners no design meets the bar on: "
           "[Where the limit is](#where-the-limit-is))."),
        "",
        f"| | worst hub {s2} / thesis's | worst tip RMS / thesis's | worst overshoot | every requirement met |",
        "|---|---|---|---|---|",
        *front_rows,
        "",
        "![tune-lead-accel-tradeoff.png](figures/tune-lead-accel-tradeoff.png)",
        "",
        "## Where the limit is",
        "",
        "On `rig` the bar is met with room to spare; on rigs unlike it, one compensator of this structure",
        "cannot meet it everywhere:",
        "",
        "- **Rigs near the model** (other friction, an offset, a heavier hub, a weaker actuator, a softer",
        "  drive train): a design whose hub settles at the bar on its model meets 0.6x on some of them and",
        "  not on others, the ratio spreading by a few hundredths around the model's. A margin on the design",
        f"  model (`--hub-ratio {la.hub_ratio:g}`) keeps them inside it; the worst case over the set alone "
        "does not, because",
        "  the set's worst models (below) are out of reach and leave the rest at the bar's edge.",
        "- **Less drive damping, a softer beam, no friction** (tmm-fit, the 2009 rig, EI x0.8, the doubt's",
        "  corners with no friction and the least damping): after the last impulse of the shaper the hub",
        "  arrives, and the beam's first mode, no longer held by friction and less damped by the drive,",
        "  drags it past the 2 % band. A loop soft enough to leave the tip quiet where friction holds the hub",
        "  brings it back late; a loop stiff enough to hold it hunts between encoder counts on the rigs",
        "  with friction and rings the tip. On the held-out rigs the bar is not met on: "
        + "; ".join(f"{h['rig'].split(' (')[0]} overshoot {h['overshoot_pct']:.1f} %, hub {_x(h['hub_ratio'])}, "
                    f"tip {h['tip_ratio']:.2f}x" for h in held_rows if not h["met"]) + ".",
        _limit_words(limit_found),
        "",
        "Is the doubt honest? Drive damping 0.6-1.4x `rig`'s (x1.93-4.51 of tmm-fit) holds the diagnosis's",
        "95 % interval (x2.36-4.47), least squares' answer (x1.98) and the 2009 session's (x1.96), but not",
        "the lower part of least squares' interval (x1.54-1.93), the estimate the diagnosis did not keep",
        "(docs/diagnosis.md); dry friction 0-16 counts holds none, the estimate (5.0, 3.2-8.0) and what the",
        "open-loop pulses alone ask for; the beam's EI within 10 % holds the x0.91 the rig's first mode asks",
        "for. tmm-fit (x1), drive damping x2 of `rig` (x6.4) and a beam 20 % softer lie outside what the",
        "diagnosis allows: they test the design's margin, not its doubt. The last row of the rule table",
        "widens the doubt to least squares' interval and a beam 20 % softer.",
        "",
        f"The rule, swept (lead + accelerometer, step 200, designed on `rig` with {len(la.figures)} models; "
        "the held-out",
        f"rigs as below, {args.seeds} noise seeds each):",
        "",
        f"| --hub-ratio (the bar on rig) | rig: overshoot / hub / tip vs the thesis's | design set: every "
        f"requirement | hub ≤ 0.6x | worst hub / tip | held-out: bar met | hub ≤ 0.6x (least-median) | "
        f"bar NOT met on |",
        "|---|---|---|---|---|---|---|---|",
        *rule_rows,
        "",
        "![tune-lead-accel-limit.png](figures/tune-lead-accel-limit.png)",
        "",
        "Each of the held-out rigs the rule does not meet the bar on, designed for alone and together",
        "with `rig` (the model alone, no doubt drawn; the hidden rigs' bar as the requirement: overshoot",
        "≤ 8 %, the tip ≤ 1.5x the thesis's, the hub ≤ 0.6x on the design model; hub / tip / overshoot,",
        "the ratios to the thesis's compensator on the same rig, without noise):",
        "",
        "| rig X | designed for X alone, on X | designed for rig and X, on rig | on X |",
        "|---|---|---|---|",
        *limit_rows,
        "",
        "## What each structure can and cannot do",
        "",
        "lead + accelerometer, step 200, on `rig` and its doubt, each structure designed by `station tune`",
        f"with the same requirements and budget (worst over the {len(la.figures)} models of the set; \"hub ≤ 0.6x\":",
        "models where the hub settles in at most 0.6x the thesis's time):",
        "",
        "| structure | --shaper / --filter / --tip-rms | rig model: overshoot / hub / tip vs thesis | worst hub "
        "| worst tip | worst overshoot | hub ≤ 0.6x | every requirement | design time |",
        "|---|---|---|---|---|---|---|---|---|",
        *structure_rows,
        "",
        "- **Lead, Ga's gain and frequency, a two-impulse shaper** (the thesis's structure): quiet only with",
        "  a low gain, which the models without friction pay for in hub settling.",
        "- **A second impulse pair for the second mode** (`opt2`, 0.02-0.03 s more delay): the step no",
        "  longer rings the second mode, so the same quiet tip allows a faster hub; the default.",
        "- **A notch or a roll-off in Gth at the second mode** cannot help here, for two reasons the probe",
        "  below shows on the former fast design. The loop's crossover (about 10 Hz) is near the second",
        "  mode, so the notch's phase lag eats the margins; and while the command sits at the ±200 clamp,",
        "  Gth's recursion runs on the clamped command (the rig's anti-windup), which drives the notch's",
        "  lightly damped poles: the step response falls apart. Given a state of its own, the notch keeps",
        "  the step but takes away the damping the loop itself gives the second mode, and the tip rings",
        "  longer. The searched notch and roll-off designs end where the table says.",
        "- **A band-pass at the second mode in Ga** (`damper`, outside the clamp) is active damping of the",
        "  second mode through the accelerometer; the search finds little use for it once the shaper",
        "  keeps the step from exciting that mode.",
        "- **No bound on the tip** (`--tip-rms 0`): the hub alone, as before; the tip pays.",
        "",
        "| notch probe (notch at 18.3 Hz, depth 0.1, width 0.1) | margins | overshoot / hub "
        f"{s2} / tip RMS |",
        "|---|---|---|",
        *probe,
        "",
        "## On rigs the design never saw",
        "",
        "`python scripts/heldout_tune.py` runs the tuned lead + accelerometer and the thesis's as `station",
        "step` runs them (the simulated rig with its accelerometer noise, "
        f"{args.seeds} noise seeds each, the worst counting) on",
        "held-out rigs made as model files and never given to the design; the bar for hidden rigs is",
        f"overshoot ≤ 8 %, hub {s2} ≤ 0.6x the thesis's, tip residual RMS ≤ 1.5x the thesis's. It is met on "
        f"**{held_met} of {len(held_rows)}**",
        f"({sum(h['met'] for h in held_rows[:FIRST_HELD_OUT])} of the first {FIRST_HELD_OUT}, "
        f"{sum(h['met'] for h in held_rows[FIRST_HELD_OUT:])} of the {len(held_rows) - FIRST_HELD_OUT} added "
        "beside them while the rule was chosen, so that it is not tuned to the nine):",
        "",
        f"| held-out rig | thesis's: overshoot / hub {s2} / tip RMS | tuned | hub / thesis's | tip / thesis's "
        "| bar |",
        "|---|---|---|---|---|---|",
        *[held_line(h, i) for i, h in enumerate(held_rows)],
        "",
        "P cannot promise a 2 % band of a 50-count step (1 encoder count) when the motor has dry",
        "friction: at rest the command is kp·e, and a hub that stops with |kp·e| below the friction",
        "stays there, up to friction / kp counts off the target (the rig's structures have no",
        "integral action), so a P loop enters the 1-count band for good only where the hub happens",
        "to stop inside it. `station tune` therefore ranks designs lexicographically: first every",
        "requirement met on the design model (the `rig` model), settling there no later than the",
        "thesis's compensator; then the worst case over the set, where a model on which friction",
        "holds the hub outside the band counts as not met but is judged by the settling time into",
        "the band it holds, charged for the held error (the P section says on how many).",
        *p_summary, *met_lines,
        "",
        *sections,
        "## Running a tuned compensator",
        "",
        "The compensator file records the model it was designed on (`[design]`: `model`, the built-in",
        "name or the model file's path relative to the compensator file, and `model_sha256`, the",
        "sha256 of the model's canonical TOML). `station step --controller C.toml` on the simulated rig",
        "runs that model when no `--model` (or `sim://?model=`) is given, as long as it is still the",
        "same model (the name or file found, the sha256 equal), and says so in one line (`simulated rig:",
        "model rig, from C.toml's design record`); with `--model` naming another model it runs the model",
        "given and says in one line that it is not the design model. A model that changed since, or",
        "cannot be found, is said in one line too, and the default model runs. On a real port nothing",
        "changes.",
        "",
        "## Reproduce",
        "",
        "```sh",
        "python scripts/tuning_table.py            # this page and docs/figures/tune-*.png",
        "station tune --model rig --controller lead-accel --amplitude 200 --out C.toml --report report/",
        "station step --controller C.toml --amplitude 200   # the simulated rig runs C.toml's design model, rig",
        "python scripts/heldout_tune.py --controller C.toml",
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
