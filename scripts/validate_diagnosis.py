#!/usr/bin/env python3
"""Validate the model diagnosis blind: N seeds per hidden effect, a Markdown table.

For every effect of ``tests.blind.cases.MAGNITUDES`` and ``NEW_MAGNITUDES`` (the
vocabulary's named effects and param:drive_c, drive_k, J_base, act_K), for seeds 0..N-1,
the independent generator (tests/blind) writes the four rig-format logs of a case with the
effect hidden at a value drawn in the issue's range; ``station.diagnosis.diagnose`` sees
only those files. Also N clean cases (must give "none" and ``unexplained: false``), N
two-effect cases (``TWO_EFFECTS``), the pairs and triples of ``PAIRS`` and ``TRIPLES``
(every effect named) and the out-of-vocabulary cases of ``OOV_CASES`` (``oov:encoder_cyclic``,
``oov:cogging``, ``oov:position_spring``: must give ``unexplained: true``, whatever they
name). Bar (issues 8 and 17): each in >= 9 of 10 seeds, named values within 25 %.

A case's effects are named when each is among the accepted causes (a single effect: the
first cause); static_friction, which the generator always hides with its coulomb_friction
v_c = 0.3-0.7 v_s, is named when it is a cause and the extended model holds a
coulomb_friction beside it (the diagnosis fits them as one step: breakaway friction); its
judged value is v_s (v_c's error is shown, not judged). A stribeck_speed part sets the
hidden curve only: it is never a cause and not judged. Found values are the extended
model's (the joint values) where it holds the effect, else the value fitted alone.

Usage: ``python scripts/validate_diagnosis.py [--seeds 10] [--seed-list SEED ...]
[--effects NAME ...] [--out docs/diagnosis_validation.md] [--jobs 1]``. ``--effects`` also takes ``clean``,
``two``, the ``oov:`` cases and the pairs and triples by name (e.g. ``coulomb_friction+amp_offset``), and
``new`` for the three new effects with their pairs and triples, ``sensor`` for the sensor and wiring
faults (``SENSOR_CASES``: accel_reversed, accel_offset, accel_drift, encoder_4096, encoder_reversed,
motor_reversed) alone and beside a physical effect (``SENSOR_PAIRS``); a fault is judged as the
effect its case part hides (accel_reversed: accel_gain; encoder_*: encoder_scale; motor_reversed:
motor_polarity); the ``sensor`` family also holds the accelerometer's configuration
(``ACCEL_SETUP_CASES``: a fifth run, the rig's 2014 swept sine, with the accelerometer off the
beam, alone and beside Coulomb friction or drive damping, or on it unplugged), judged by the
audit's decision on that run (off the beam: decided off; unplugged: not decided off), no
beam_damping nor accelerometer mass or inertia among the causes, and the physical effect named
as above (none alone). Progress goes to stderr,
one line per case; the table is printed and written.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # tests.blind is not installed with the package

from tests.blind.cases import (MAGNITUDES, NEW_MAGNITUDES, OOV_CASES, PAIRS, SETTING_MAGNITUDES,  # noqa: E402
                               TOLERANCE, TRIPLES, TWO_EFFECTS, case_effects, value_error)
from tests.blind.cases import SENSOR_CASES, SENSOR_MAGNITUDES, SENSOR_PAIRS  # noqa: E402
from tests.blind.cases import HELD_OFFSET, SLIDING_CASES, SLIDING_MAGNITUDES, case_alignment  # noqa: E402
from tests.blind.cases import ACCEL_SETUP_CASES, ACCEL_SETUPS, DEAD_LEVEL, sweep_setup  # noqa: E402
from station.ranges import number  # noqa: E402

RANGES = {**MAGNITUDES, **NEW_MAGNITUDES, **SETTING_MAGNITUDES}
NEW_CASES = (*NEW_MAGNITUDES, *PAIRS, *TRIPLES)
"""The cases of issue 17's effects (``--effects new``)."""
KNOWN = (*MAGNITUDES, "two", *NEW_CASES, "clean", *OOV_CASES)
"""Every case this script runs (the default), in the table's order."""

RANGES.update(SENSOR_MAGNITUDES)
RANGES.update({part: DEAD_LEVEL for part in ACCEL_SETUPS})  # the dead channel's level, counts
SENSOR = (*SENSOR_CASES, *SENSOR_PAIRS, *ACCEL_SETUP_CASES)
"""The sensor and wiring fault cases, alone and beside a physical effect (``--effects sensor``);
a case part (e.g. "encoder_4096") names the effect it hides (tests/blind/cases.SENSOR_CASES)."""
KNOWN += SENSOR

RANGES.update(SLIDING_MAGNITUDES)
SLIDING_PARTS = {"breakaway_sliding": ("static_friction", "coulomb_friction")}
"""A breakaway over a sliding level, both judged (``--effects sliding``: :data:`SLIDING_CASES`); such
a case is also right when the answer's rival, listed in ``alternatives``, holds every hidden effect
within 25 % (the doubt kept until the data settle it, issue 26)."""
KNOWN += SLIDING_CASES
PART_EFFECT = {"held_offset": "amp_offset"}
"""A case part -> the effect it hides, where they differ (an offset the friction holds)."""


def judged(case: str) -> tuple[str, ...]:
    """The effects of a case that must be named and whose values are judged.

    Parameters
    ----------
    case : str
        "clean", "two", an effect, or effects joined by "+" (tests/blind/cases.CASES).
    """
    if case == "clean" or case in OOV_CASES:
        return ()
    if case == "two":
        return TWO_EFFECTS
    case = case_alignment(case)[0]
    out: tuple[str, ...] = ()
    for part in case.split("+"):
        if part not in SETTING_MAGNITUDES and part not in ACCEL_SETUPS:
            out += SLIDING_PARTS.get(part, (SENSOR_CASES.get(part, PART_EFFECT.get(part, part)),))
    return out


def rescued_by_alternative(case: str) -> bool:
    """Whether an alternative holding every hidden effect within 25 % makes the case right
    (the sliding cases)."""
    return any(part in SLIDING_PARTS for part in case_alignment(case)[0].split("+"))


NOT_FOR_A_MISSING_MASS = ("beam_damping", "param:m_accel", "param:J_accel")
"""Causes a configuration case must not name: what a model that keeps the accelerometer's mass
would take for a beam without it."""


@dataclass
class Outcome:
    """One diagnosed case."""

    case: str
    seed: int
    hidden: dict
    causes: list
    values: dict       # effect -> value found (every hidden effect)
    gain_pct: float
    seconds: float

    extended: dict = None  # the extended model's effects
    cost_hidden: float = float("nan")  # in-sample cost J of the hidden effects (the diagnosis's own cost)
    cost_found: float = float("nan")   # ... and of the extended model
    unexplained: bool = False          # the diagnosis's flag
    alternatives: list = None          # the diagnosis's alternatives ({"causes", "values", ...})
    mounting: str = ""                 # the fifth run's audit: "off", "on", "unchecked" ("" without one)

    @property
    def search_miss(self) -> bool:
        """Not ok although the hidden effects fit the runs better than the answer: the
        search missed a better explanation (not a matter of what the runs can tell apart)."""
        return not self.ok and self.cost_hidden < self.cost_found

    @property
    def named(self) -> bool:
        """Every judged effect is a cause (module docstring): "none" for clean, the first
        cause for a single effect, among the causes for two or three."""
        names = judged(self.case)
        if self.case in OOV_CASES:  # out of vocabulary: flagged, whatever it names
            return self.unexplained
        setup = [p for p in self.case.split("+") if p in ACCEL_SETUPS]
        if setup and ((self.mounting == "off") != (setup[0] == "accel_off")
                      or set(NOT_FOR_A_MISSING_MASS) & set(self.causes) or (not names and self.causes)):
            return False
        if not names:
            return not self.causes and not self.unexplained
        if len(names) == 1 and not (self.causes and self.causes[0] == names[0]):
            return False
        return _holds(names, self.causes, self.extended or {})

    def errors(self) -> list[float]:
        """Relative value errors of the judged effects."""
        return [value_error(self.hidden[k], self.values[k]) for k in judged(self.case)]

    @property
    def answered(self) -> bool:
        """Every judged effect named, each within 25 %."""
        return self.named and all(e <= TOLERANCE for e in self.errors())

    @property
    def rival(self) -> dict | None:
        """The alternative holding every judged effect within 25 % (None: none does)."""
        names = judged(self.case)
        for alt in self.alternatives or []:
            values = alt.get("values", {})
            if _holds(names, alt.get("causes", []), values) and all(
                    value_error(self.hidden[k], values[k]) <= TOLERANCE for k in names):
                return alt
        return None

    @property
    def ok(self) -> bool:
        return self.answered or (rescued_by_alternative(self.case) and self.rival is not None)


def _holds(names, causes, values) -> bool:
    """Every judged effect among the causes, a static_friction's sliding level among the values
    (the diagnosis fits a breakaway as one step with its sliding level: not a cause of its own)."""
    held = {"coulomb_friction"} if "static_friction" in names else set()
    return set(names) - held <= set(causes) and held <= set(values)


def run_case(case: str, seed: int) -> Outcome:
    """Generate one case's logs in a temporary folder and diagnose them."""
    from station.diagnosis import diagnose
    from tests.blind.generator import write_case, write_sweep

    hidden = case_effects(case, seed)
    alignment = case_alignment(case)[1]
    setup = sweep_setup(case, seed)
    with tempfile.TemporaryDirectory(prefix=f"blind_{case.replace(':', '_').replace('@', '_')}_{seed}_") as tmp:
        paths = write_case(Path(tmp), hidden, seed, alignment=alignment)
        if setup is not None:  # the fifth run: the swept sine with the accelerometer's configuration
            paths.append(write_sweep(Path(tmp), {**hidden, **setup}, seed))
        t0 = time.perf_counter()
        try:
            result = diagnose([str(p) for p in paths]).to_json()
        except Exception as exc:  # a defect: counted as a miss, the other cases still run
            return Outcome(case, seed, hidden, [f"error: {type(exc).__name__}: {exc}"], {}, 0.0,
                           time.perf_counter() - t0)
        seconds = time.perf_counter() - t0
        extended = dict(result["extended_model"]["effects"])
        cost_hidden, cost_found = (_costs(paths, hidden, extended) if case not in OOV_CASES
                                   else (float("nan"), float("nan")))
    values = {e["name"]: e["value"] for e in result["effects"] if e["name"] in hidden}
    values.update({k: v for k, v in extended.items() if k in hidden})  # the joint values
    return Outcome(case, seed, hidden, list(result["causes"]), values, float(result["gain_pct"]), seconds,
                   extended, cost_hidden, cost_found, bool(result["unexplained"]),
                   list(result.get("alternatives", [])), _mounting(result, paths[-1].name) if setup is not None else "")


def _mounting(result: dict, run: str) -> str:
    """The audit's decision on a run: "off" (the accelerometer's mass off the beam), "on" or
    "unchecked" (the question left open, or not asked)."""
    from station.logged.accelerometer import MOUNTED_CLAIM

    rows = next((r["audit"] for r in result["audit"] if r["run"] == run), [])
    verdict = next((c["verdict"] for c in rows if c["header"] == MOUNTED_CLAIM), "")
    return {"contradicted": "off", "confirmed": "on"}.get(verdict, "unchecked")


def _costs(paths, hidden: dict, found: dict) -> tuple[float, float]:
    """The diagnosis's in-sample cost J (noise-normalised θ and a errors over all runs, 1 at
    the noise floor) of the hidden effects and of the found ones."""
    from station.diagnosis.runs.cases import load_case
    from station.diagnosis.runs.cost import Evaluator, calibrate_noise
    from station.plant.model import load_model

    ev = Evaluator([load_case(p) for p in paths], load_model())
    calibrate_noise(ev)
    runs = range(len(paths))
    return ev.cost(hidden, runs), ev.cost(found, runs)


def _fmt_hidden(d: dict) -> str:
    return ", ".join(f"{k} = {v:.4g}" for k, v in d.items()) or "-"


def table(outcomes: list[Outcome], seeds: str, elapsed: float) -> str:
    """The Markdown report: summary per effect, then every case."""
    by_case: dict[str, list[Outcome]] = {}
    for o in outcomes:
        by_case.setdefault(o.case, []).append(o)
    lines = [
        "# Blind validation of the model diagnosis",
        "",
        f"Written by `scripts/validate_diagnosis.py {seeds}`: {len(outcomes)} cases in "
        f"{elapsed / 60:.1f} min. Each case is four 2 s rig-format logs (P kp = 2 step 50, lead step 100, "
        "lead + accelerometer step 200, open-loop ±100 pulses) written by the independent generator "
        "`tests/blind` (its own FEM, stick-slip friction with breakaway and Stribeck curve, backlash on a "
        "100-sub-step grid with micro-steps where the Stribeck curve is steep, accelerometer noise 0.3 counts, "
        "the rig's truncation and rounding) with one, two or three effects hidden at values drawn in issue 8's "
        "and issue 17's ranges; `station.diagnosis.diagnose` sees only the files (leave-one-run-out over the "
        "four).",
        "",
        f"Bar (issues 8 and 17): the cause named in at least 9 of 10 seeds with its value within {TOLERANCE:.0%}; "
        "clean cases give \"none\" in at least 9 of 10; two- and three-effect cases name every effect, each "
        "within 25 %. A single effect must be the first cause; static_friction (hidden with coulomb_friction "
        "v_c = 0.3–0.7 v_s) is named when it is a cause with a coulomb_friction beside it in the extended "
        "model, and judged on v_s; a stribeck_speed part only shapes the hidden friction (never a cause, "
        "not judged). Found values are the extended model's.",
        "",
        "| effect | hidden range | seeds | named | named and within 25 % | median \\|value error\\| % | max \\|value error\\| % |",
        "|---|---|---|---|---|---|---|",
    ]
    for case, group in by_case.items():
        if case == "clean" or case in OOV_CASES or rescued_by_alternative(case):
            continue
        parts = TWO_EFFECTS if case == "two" else case.split("+")
        rng = " + ".join(f"{n} {RANGES[n][0]:g}–{RANGES[n][1]:g}" for n in parts) if len(parts) > 1 \
            else f"{RANGES[case][0]:g}–{RANGES[case][1]:g}"
        errs = [e for o in group if o.named for e in o.errors()]
        med = f"{100 * statistics.median(errs):.1f}" if errs else "-"
        mx = f"{100 * max(errs):.1f}" if errs else "-"
        name = f"two: {' + '.join(TWO_EFFECTS)}" if case == "two" else case
        lines.append(f"| {name} | {rng} | {len(group)} | {sum(o.named for o in group)} | "
                     f"{sum(o.ok for o in group)} | {med} | {mx} |")
    lines += sliding_table(by_case)
    clean = by_case.get("clean", [])
    if clean:
        lines += ["", f"Clean cases: \"none\" with `unexplained: false` in {sum(o.named for o in clean)} of "
                      f"{len(clean)} ({100 * sum(o.named for o in clean) / len(clean):.0f} %); \"none\" in "
                      f"{sum(not o.causes for o in clean)}, `unexplained: false` in {sum(not o.unexplained for o in clean)}."]
    for case in OOV_CASES:
        group = by_case.get(case, [])
        if group:
            lines += ["", f"Out-of-vocabulary {case} ({', '.join(OOV_CASES[case])} hidden): `unexplained: true` in "
                          f"{sum(o.ok for o in group)} of {len(group)}; named as a cause anyway: "
                          f"{', '.join(sorted({c for o in group for c in o.causes})) or 'nothing'}."]
    misses = [o for o in outcomes if not o.ok]
    if misses:
        search = sum(o.search_miss for o in misses)
        lines += ["", f"Misses: {len(misses)} of {len(outcomes)} cases. In {search} of them the hidden effects fit "
                      "the four runs better than the answer (in-sample cost J, the diagnosis's own: noise-normalised "
                      "θ and a errors, 1 at the noise floor; columns J hidden / J found below): the search did not "
                      "reach the better explanation (a friction-like proxy such as deadzone often comes first; the "
                      "lookahead, last look and swap of station.diagnosis.search.stepwise undo it only where another "
                      "first effect with one partner, or one swap, reaches the better one), rather than the "
                      "runs failing to tell the explanations apart."]
    lines += ["", "## Every case", "",
              "| case | seed | hidden | causes found | values found | θ gain % | J hidden | J found | unexplained | s |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for o in outcomes:
        mark = "" if o.ok else " ✗"
        hidden = _fmt_hidden(o.hidden) + (f"; fifth run: {_fmt_hidden(sweep_setup(o.case, o.seed))}, decided "
                                          f"{o.mounting}" if o.mounting else "")
        lines.append(f"| {o.case}{mark} | {o.seed} | {hidden} | {', '.join(o.causes) or 'none'} | "
                     f"{_fmt_hidden(o.values)} | {o.gain_pct:.1f} | {o.cost_hidden:.3g} | {o.cost_found:.3g} | "
                     f"{'yes' if o.unexplained else 'no'} | {o.seconds:.0f} |")
    return "\n".join(lines) + "\n"


def sliding_table(by_case: dict[str, list[Outcome]]) -> list[str]:
    """The breakaway-over-a-sliding-level cases: both levels judged, or the rival in ``alternatives``."""
    groups = {case: group for case, group in by_case.items() if rescued_by_alternative(case)}
    if not groups:
        return []
    lines = ["", "Breakaway over a sliding level (issue 26; `--effects sliding`): static_friction v_s and its "
                 "sliding level coulomb_friction v_c both judged. Bar: both named within 25 % (v_s a cause, v_c "
                 "in the extended model), or the answer's rival listed in `alternatives` holding every hidden "
                 "effect within 25 %, in at least 9 of 10 seeds. `@d0`: the closed loops at alignment 0 (the "
                 "rig's 2009 logs).", "",
             "| case | hidden range | seeds | named, both within 25 % | else the rival in alternatives | right | "
             r"median \|v_s error\| % | median \|v_c error\| % |",
             "|---|---|---|---|---|---|---|---|"]
    for case, group in groups.items():
        parts = case_alignment(case)[0].split("+")
        rng = " + ".join(f"amp_offset ±({HELD_OFFSET[0]:g}–{HELD_OFFSET[1]:g}) v_c" if n == "held_offset"
                         else f"{n} {RANGES[n][0]:g}–{RANGES[n][1]:g}" for n in parts)
        named = [o for o in group if o.named]
        med = {k: (f"{100 * statistics.median(value_error(o.hidden[k], o.values[k]) for o in named):.1f}"
                   if named else "-") for k in ("static_friction", "coulomb_friction")}
        lines.append(f"| {case} | {rng} (v_c 0.3–0.7 v_s) | {len(group)} | {sum(o.answered for o in group)} | "
                     f"{sum(not o.answered and o.rival is not None for o in group)} | {sum(o.ok for o in group)} | "
                     f"{med['static_friction']} | {med['coulomb_friction']} |")
    lines += ["", "| case | seed | hidden | causes found | values found | the rival in alternatives |",
              "|---|---|---|---|---|---|"]
    for case, group in groups.items():
        for o in group:
            alt = o.rival
            rival = "-" if alt is None or o.answered else \
                f"{' + '.join(alt['causes'])} ({_fmt_hidden(alt['values'])}, cost ratio {alt['cost_ratio']:.3g})"
            lines.append(f"| {case}{'' if o.ok else ' ✗'} | {o.seed} | {_fmt_hidden(o.hidden)} | "
                         f"{', '.join(o.causes) or 'none'} | {_fmt_hidden(o.extended or {})} | {rival} |")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=number(1, 1000, integer=True), default=10, help="seeds per effect (default 10)")
    parser.add_argument("--effects", nargs="+", default=list(KNOWN),
                        help="cases to hide (effects of tests/blind/cases.MAGNITUDES and NEW_MAGNITUDES, its PAIRS "
                             "and TRIPLES, 'two', 'clean', 'new' for issue 17's, 'sensor' for the sensor and "
                             "wiring faults; default all)")
    parser.add_argument("--seed-list", type=number(0, 2**32 - 1, integer=True), nargs="+", metavar="SEED",
                        help="run only these seeds (instead of 0..N-1 of --seeds; e.g. a case's misses)")
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "diagnosis_validation.md",
                        help="Markdown table to write (default docs/diagnosis_validation.md)")
    parser.add_argument("--jobs", type=number(1, 64, integer=True), default=1, help="cases diagnosed in parallel (default 1)")
    args = parser.parse_args(argv)
    groups = {"new": NEW_CASES, "sensor": SENSOR, "sliding": SLIDING_CASES}
    effects = [c for name in args.effects for c in groups.get(name, (name,))]
    for name in effects:
        if name not in KNOWN:
            parser.error(f"--effects: unknown '{name}' (known: {', '.join(KNOWN)}, new, sensor, sliding)")
    if args.seeds < 1:
        parser.error("--seeds: expected a positive integer")
    if args.seed_list and min(args.seed_list) < 0:
        parser.error("--seed-list: expected non-negative integers")
    seeds = args.seed_list or list(range(args.seeds))
    jobs = [(case, seed) for case in effects for seed in seeds]
    t0 = time.perf_counter()
    outcomes: list[Outcome] = []

    def report(o: Outcome) -> None:
        outcomes.append(o)
        verdict = "ok" if o.ok else "MISS"
        print(f"[{len(outcomes)}/{len(jobs)}] {o.case} seed {o.seed}: hidden {_fmt_hidden(o.hidden)}; found "
              f"{', '.join(o.causes) or 'none'} ({_fmt_hidden(o.values)})"
              f"{f'; fifth run decided {o.mounting}' if o.mounting else ''} {verdict} {o.seconds:.0f} s",
              file=sys.stderr, flush=True)

    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as pool:
            for o in pool.map(run_case, *zip(*jobs)):
                report(o)
    else:
        for case, seed in jobs:
            report(run_case(case, seed))
    label = (f"--seed-list {' '.join(map(str, seeds))}" if args.seed_list else f"--seeds {args.seeds}")
    text = table(outcomes, label, time.perf_counter() - t0)
    print(text)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(f"written {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
