#!/usr/bin/env python3
"""Validate the log audit blind: N seeds per class of lying header and lab recursion.

For every class of ``tests.blind.audit.CLASSES`` (alone and beside a hidden Coulomb
friction), for seeds 0..N-1, the independent generator writes one rig-format log of 2000
samples; ``station.logged.LoggedRun`` sees only the file. Judged per case:

- contradiction: a header that lies (``lie:*``, ``session``) is contradicted (the audit's
  controller row "contradicted", ``controller_source`` "inferred (header contradicted)"); a
  header that does not (``int:*`` name none, ``honest:*`` tell the truth) is not; and the
  columns written as unsigned 16-bit words (``words``) are contradicted, each, and no other;
  two columns written in each other's place (``swap``) are said swapped, and no others;
  rows lost or written again (``rows``) are said (n jumps), and in no other class; an a column
  written in another unit (``a_unit``) is said, its count's size to 0.1 %, and in no other class;
  so is a v column written in volts (``v_unit``); a lead's float command printed to 5 or 6
  significant digits (``printed``) is contradicted only under its open-loop header; θ written
  with the other sign (``sign``) is said, and in no other class; the session's lie with one of
  those column faults beside it (``double``) is contradicted and the fault said; so is a
  closed-loop header's lie over two columns swapped (``lie:swap``) or over one column in
  another unit or about another zero (``lie:column``); and two column faults at once under a
  true header or none (``pair``); a lead with Ga over rows lost (``lie:accel_rows``) is
  contradicted under its lying header, its law judged on the rows before the first jump; a
  column fault beside rows lost (``rows:column``) is said, and θ from an earlier run's count
  beside θ negated or u and v swapped (``zero:column``) both, and beside v in volts or about a
  DAC code's midpoint (``zero:command``), and with θ negated or u and v swapped as well under a
  true header (``three:columns``), and with both (``four:columns``), and under an open-loop
  header or none (``three:open_loop``);
- reproduced: the controller used reproduces every logged v to the device's quantization
  (1e-6 counts, the logged integer exactly for an integer recursion, half the last printed
  digit for a v printed to fewer digits) at the hidden alignment;
- design: the law the data gave is the hidden one: the continuous design (num/den in s, to
  1e-9, Tustin) of a lead, the gain of a P law (not judged where the header's law is
  confirmed: the header's own coefficients are used).
  Where the audit says the log pins a first-order design only to a span of zeros and poles
  (``station.analysis.design_doubt.span_phrase``), another design named with the hidden one
  inside the span said counts too (its own column, and listed).

Bar (issue 26): each in >= 9 of 10 seeds per class. The Markdown section replaces the one
between ``<!-- validate_audit -->`` markers in docs/diagnosis_validation.md (appended when
absent) and is printed.

Usage: ``python scripts/validate_audit.py [--seeds 10] [--classes NAME ...] [--out FILE]
[--jobs 1]``. Progress goes to stderr, one line per case.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # tests.blind is not installed with the package

from station.ranges import number  # noqa: E402
from tests.blind.audit import A_UNITS, CLASSES, PHYSICAL, V_UNITS, draw_case  # noqa: E402

KNOWN = tuple(c for base in CLASSES for c in (base, *(f"{base}+{p}" for p in PHYSICAL)))
"""Every case this script runs (the default), in the table's order."""

BEGIN, END = "<!-- validate_audit -->", "<!-- /validate_audit -->"


@dataclass
class Outcome:
    """One audited case."""

    case: str
    seed: int
    hidden: str
    found: str
    source: str | None
    contradiction_ok: bool
    reproduced: bool
    design_ok: bool | None  # None: not judged (the header's law confirmed)
    seconds: float
    error: str = ""
    spanned: bool = False  # the hidden design inside the span said beside another (design_doubt.span_phrase)

    @property
    def ok(self) -> bool:
        return self.contradiction_ok and self.reproduced and (self.design_ok is not False or self.spanned)


def _same(a, b, rel: float = 1e-9) -> bool:
    return len(a) == len(b) and all(abs(x - y) <= rel * max(1.0, abs(y)) for x, y in zip(a, b))


GA_RTOL = 1e-3
"""Relative agreement of a found Ga's continuous coefficients with the hidden ones."""


def _same_s(found, hidden) -> bool:
    """Whether a found continuous law (num, den) is the hidden one to :data:`GA_RTOL`: each
    coefficient against the largest of its polynomial (a Tustin inverse leaves ~1e-10 of
    higher powers in the numerator)."""
    out = True
    for f, h in zip(found, hidden):
        f, h = np.asarray(f, float), np.asarray(h, float)
        h = np.concatenate((np.zeros(max(0, f.size - h.size)), h))
        f = np.concatenate((np.zeros(max(0, h.size - f.size)), f))
        out = out and bool(np.all(np.abs(f - h) <= GA_RTOL * np.abs(h) + 1e-9 * np.max(np.abs(h))))
    return out


def run_case(case: str, seed: int) -> Outcome:
    """Write one case's log in a temporary folder and audit it."""
    from station.analysis.design_doubt import DesignSpan, span_phrase
    from station.logged import LoggedRun
    from tests.blind.audit import write_audit_case

    hidden = draw_case(case, seed)
    what = (f"{hidden.design_text}, recursion {hidden.recursion}, d {hidden.alignment}, clamp ±{hidden.limit:g}, "
            f"{hidden.reference} {hidden.amplitude:g}, header {hidden.header}"
            + (f" kp {hidden.header_kp:g}" if hidden.header_kp is not None else ""))
    with tempfile.TemporaryDirectory(prefix="blind_audit_") as tmp:
        path, hidden = write_audit_case(Path(tmp), case, seed)
        t0 = time.perf_counter()
        try:
            run = LoggedRun.from_path(path)
            audit = run.audit
        except Exception as exc:  # a defect: counted as a miss, the other cases still run
            return Outcome(case, seed, what, f"error: {type(exc).__name__}: {exc}", None, False, False, False,
                           time.perf_counter() - t0, str(exc))
        seconds = time.perf_counter() - t0
    contradicted = any(c.claim == "controller" and c.verdict == "contradicted" for c in audit.claims)
    lied = hidden.lies
    contradiction_ok = (contradicted and run.source == "inferred (header contradicted)") if lied else not contradicted
    # the columns the lab's client read as unsigned 16-bit words: contradicted, each, and no other
    shown = {"u": "u", "v": "v", "theta": "θ", "a": "a", "theta_d_hat": "θ̂d"}
    words = {c.header for c in audit.claims if c.claim == "columns" and c.verdict == "contradicted"
             and "16-bit" in c.data}
    contradiction_ok = contradiction_ok and words == {f"{shown[c]} in signed counts" for c in hidden.wrapped}
    # two columns written in each other's place: said, and no swap where there is none
    swaps = {c.data for c in audit.claims if c.claim == "columns" and c.data.endswith(" swapped")}
    contradiction_ok = contradiction_ok and swaps == ({f"{shown[hidden.swap[0]]} and {shown[hidden.swap[1]]} swapped"}
                                                      if hidden.swap else set())
    # θ written with the other sign than the loop fed back: said, and never where it is not
    signs = {c.data for c in audit.claims if c.claim == "columns" and c.data.endswith("written with the other sign")}
    contradiction_ok = contradiction_ok and signs == ({"θ written with the other sign"} if hidden.negate else set())
    # a written in another unit: its count's size found (to 0.1 %), and never where a is in counts
    units = [c.data for c in audit.claims if c.claim == "columns" and c.data.startswith("a in steps of")]
    step = A_UNITS.get(hidden.a_unit) if hidden.a_unit else None
    contradiction_ok = contradiction_ok and (
        not units if step is None else len(units) == 1 and abs(float(units[0].split()[-1]) / step - 1) < 1e-3)
    # v written in another unit: its count's size found (to 0.1 %), and never where v is in counts
    units = [c.data for c in audit.claims if c.claim == "columns" and c.header == "v in DAC counts"]
    step = V_UNITS.get(hidden.v_unit) if hidden.v_unit else None
    contradiction_ok = contradiction_ok and (
        not units if step is None else len(units) == 1 and abs(float(units[0].split()[-1]) / step - 1) < 1e-3)
    # v written about another zero: found (the zero exactly), and never where v is about 0
    zeros = [c.data for c in audit.claims if c.claim == "columns" and c.header == "v in DAC counts about 0"]
    contradiction_ok = contradiction_ok and zeros == ([f"v about {hidden.v_zero:g} counts"] if hidden.v_zero else [])
    # u written in degrees or radians: said, its unit named, and never where u is in counts
    refs = [c.data for c in audit.claims if c.claim == "columns" and c.header == "u in encoder counts"]
    contradiction_ok = contradiction_ok and refs == ([f"u in {hidden.u_unit}"] if hidden.u_unit else [])
    # θ written from the encoder's count at the start where the loop took it off: found (θ0 exactly), and only there
    starts = [c.data for c in audit.claims if c.claim == "columns" and c.header == "θ as the loop's error used it"]
    contradiction_ok = contradiction_ok and starts == (
        [f"θ logged before its zero was taken off (θ0 = {hidden.theta_zero:g} counts)"] if hidden.theta_zero else [])
    # a written as the accelerometer read it where the loop took its zero off: found (a0 to 0.01), and only there
    accels = [c.data for c in audit.claims if c.claim == "columns"
              and c.header == "a as the loop's accelerometer feedback used it"]
    contradiction_ok = contradiction_ok and len(accels) == bool(hidden.a_zero) and (
        not accels or abs(float(accels[0].split("a0 = ")[1].split()[0]) - hidden.a_zero) < 0.01)
    # rows lost or written again: said (n jumps), and never where every tick is there once
    jumps = any(c.claim == "sample_time" and c.data.startswith("n jumps") for c in audit.claims)
    contradiction_ok = contradiction_ok and jumps == bool(hidden.rows)
    reproduced = run.reproduced and (run.alignment == hidden.alignment or hidden.alignment in run.identified.alignments)
    spec = getattr(run.controller, "spec", {}) or {}
    design = spec.get("design")
    if run.source == "header":
        design_ok = None
    elif hidden.law == "p":
        design_ok = spec.get("kind") == "p" and spec.get("kp") == hidden.kp
    else:
        design_ok = (isinstance(design, dict) and design.get("method") == "Tustin"
                     and _same(design["num_s"], hidden.num_s) and _same(design["den_s"], hidden.den_s))
    if hidden.ga_s is not None and design_ok is not None:  # and the accelerometer feedback, as the generator discretized it
        from tests.blind.rig import DT

        # Ga's numbers are not round (DESIGN.md's): named when its continuous form (Tustin's
        # inverse) is the hidden one to GA_RTOL, as far as the data pin its slowest pole
        from station.analysis.continuous_design import to_continuous

        ga = getattr(run.controller, "ga", None)
        back = None if ga is None else to_continuous(ga.num, ga.den, DT, "Tustin")
        design_ok = design_ok and back is not None and _same_s(back, hidden.ga_s)
    found = (f"{getattr(run.controller, 'name', None)}, recursion {getattr(run.controller, 'recursion', 'none')}, "
             f"d {run.alignment}, max|dv| {run.max_abs_dv if run.max_abs_dv is None else f'{run.max_abs_dv:.2g}'}")
    alts = design.get("alternatives", []) if isinstance(design, dict) else []
    if alts:  # the designs the log does not tell apart from it, said beside it
        law = getattr(run.controller, "recursion", "none")
        among = hidden.num_s is not None and any(_same(d["num_s"], hidden.num_s) and _same(d["den_s"], hidden.den_s)
                                                 and d.get("recursion", law) == hidden.recursion for d in alts)
        more = design.get("more_alternatives", 0)
        texts = [d["text"] + (f" (recursion {d['recursion']})" if d.get("recursion") else "") for d in alts]
        found += (f"; beside it {' or '.join(texts)}" + (f" and {more} more" if more else "")
                  + (" (the hidden among them)" if among else ""))
    spanned = False
    if design_ok is False and hidden.num_s is not None and len(hidden.num_s) == 2 and isinstance(design, dict) \
            and design.get("method") == "Tustin" and span_phrase(design):
        # the log admits a family: the span said holds the hidden zero and pole (the gain follows them)
        span = DesignSpan.from_json(design["span"])
        spanned = span.holds(hidden.num_s[1] / hidden.num_s[0], hidden.den_s[1])
        found += f"; {'the hidden inside' if spanned else 'the hidden outside'} the span said{span_phrase(design)[1:]}"
    return Outcome(case, seed, what, found, run.source, contradiction_ok, reproduced, design_ok, seconds,
                   spanned=spanned)


def table(outcomes: list[Outcome], seeds: str, elapsed: float) -> str:
    """The Markdown section: one row per case, then every miss."""
    by_case: dict[str, list[Outcome]] = {}
    for o in outcomes:
        by_case.setdefault(o.case, []).append(o)
    lines = [
        BEGIN,
        "## Log audit: lying headers and lab recursions",
        "",
        f"Written by `scripts/validate_audit.py {seeds}`: {len(outcomes)} logs in {elapsed / 60:.1f} min. Each is "
        "one rig-format log of 2000 samples written by the independent generator `tests/blind/audit.py` (its own "
        "FEM, amplifier and sensors; a P law or a lead K(s+z)/(s+p) with round numbers, Tustin at 0.002 s, its "
        "recursion on the float or on the stored integer (truncated or rounded), alignment 0 or 1, clamp ±200 or "
        "±150, a step, 5 Hz sine or the lab's ‘0–10 Hz’ sweep (its instantaneous frequency to 20 Hz) reference); `station.logged.LoggedRun` sees only the file. "
        "`lie:open_loop`: an open-loop header on closed-loop data; `lie:p_kp`: `#kp=2.0` over another gain; "
        "`lie:lead_pole`: the thesis's lead printed, another pole run; `lie:accel_fb`: a lead with "
        "accelerometer feedback θ̂_d = u − Ga(a) (DESIGN.md's Ga, its gain ×0.5–1.5 and frequencies ×0.7–1.4; "
        "the float recursion) under a header without Ga (open loop, or the lead alone); `lie:accel_rows`: the "
        "same, or no header, over a log that lost one to three spans of 1–30 rows, the first from row 150 on "
        "(Ga's state is in no column: the law is judged on the rows before the first jump); `rows:column`: a "
        "true header (P, a lead on the stored integer, or the thesis's lead + Ga on the float, both named) over "
        "a log that lost rows (as `rows`) with one column fault beside it — θ negated, u and v or θ and a "
        "swapped, or v in volts — the fault said as in its own class; `zero:column`: `theta_zero`'s headers and "
        "θ from an earlier run's count, beside θ negated or u and v swapped — both said as in their own classes, "
        "and the law confirmed or inferred on the columns read back; `zero:command`: the same headers and θ0 "
        "beside v in volts (as `v_unit`'s; a P law's under its own header) or about a DAC code's midpoint (as "
        "`v_zero`'s): a script that wrote the device's raw words — both said as in their own classes; "
        "`three:columns`: `zero:command`'s two faults under a true header (P, or a lead on the stored integer) "
        "beside θ negated or u and v swapped — three column faults at once, each said, the header confirmed; "
        "`four:columns`: the same beside θ negated and u and v swapped both — four at once; "
        "`three:open_loop`: `three:columns`'s three under the lab's session's open-loop header or none — the law "
        "inferred (a P with v about a DAC code's midpoint, a lead on the stored integer so or in volts), each said; "
        "`int:*`: integer "
        "recursions with no "
        "header (the 2014 layout); `session`: the lab's third session (open-loop header, a lead on the "
        "truncated integer at alignment 0); `lie:sent`: an open-loop header on a lead whose recursion runs on the "
        "float while the whole count it sends is logged; `lie:accel_int`: an open-loop header on a lead with "
        "DESIGN.md's Ga as it stands, the command stored or sent as a whole count; `words`: a true header (P, or a lead on the stored integer) over columns the lab's client read from the legacy protocol's 16-bit two's-complement words as unsigned (a negative x written as 65536 + x; each such column must be contradicted, and no column of any other class); `swap`: a true header (P, or a lead on the stored integer) or none (the 2014 layout) over columns u and v, or θ and a, written in each other's place (the swap must be said, and none in any other class); `rows`: a true header (P, or a lead on the stored integer) or none (the 2014 layout, where t jumps) over a log that lost one to three spans of 1–30 rows while the hub moves, or holds a block of rows written again (n jumps must be said, and in no other class, and the law reproduce every row it can judge: replayed again from each jump with its memory as logged); `a_unit`: a true header (P, or a lead on the stored integer) or none over a log whose a a script scaled into m/s², g or mV and printed to 7 digits (a's unit must be said, its count's size to 0.1 %, and in no other class); `v_unit`: a true header (P, or a lead on the stored integer or the float) over a log whose v a script wrote in volts of a ±5 V 12-bit or ±10 V 16-bit converter, 7 digits (said as a's, and the law then confirmed; a float command's unit read by the header's law replayed on its own commands; a command in mV within the DAC's range is another gain as much as another unit and is not drawn); `printed`: a lead on the float command under its true header or an open-loop one, every number printed to 5 significant digits (MATLAB's csvwrite) or 6 (C's %g): the law judged to that printing, confirmed or inferred, and no column contradicted; `sign`: θ written with the other sign than the loop fed back, under a true header (P, or a lead on the stored integer), none, or an open-loop one (said, and in no other class); `double`: the lab's session (an open-loop header on a lead on the truncated integer) with one column fault beside it — v in volts, θ negated, u and v swapped, or (on the float) every number printed to 5 or 6 digits — the lie contradicted, the law inferred and the fault said; `lie:swap`: a closed-loop header that lies (`#kp=2.0` over another gain, or the thesis's lead printed over another pole) with u and v, or θ and a, written in each other's place: the lie contradicted, the law inferred on the swap and the swap said; `pair`: two column faults at once under a true header (P, or a lead on the stored integer) or none — u and v, or θ and a, swapped beside θ negated, or (under a true header) beside v in volts: each fault said, and the law confirmed (where friction held the hub at 0 the whole run, θ negated is θ itself: no sign fault is hidden there, and the alignment is left to both); `v_zero`: a true header (P, or a lead on the stored integer), none (the 2014 layout), or the lab's session's open-loop one (a lead on the truncated integer) over a log whose v a script wrote as an unsigned DAC code about its midpoint, 128, 2048 or 32768 (said, with its zero, and in no other class, and the law confirmed or inferred on v less it); `u_unit`: the same headers over a log whose u (the reference) a script wrote in degrees or radians of the hub, θ in counts (the unit said, in no other class, and the law confirmed or inferred on u in counts); `theta_zero`: the same headers over a log whose θ a script wrote as the encoder read it, from a count of ±5–400 an earlier run left, where the loop took that count off (θ0 said exactly, in no other class, and the law confirmed or inferred on θ − θ0); `a_zero`: the thesis's lead + accelerometer feedback under its true header, on the float command (a third) or the whole count stored or sent (truncated or rounded), over a log whose a a script wrote as the accelerometer read it where the loop fed Ga the reading less a calibrated zero of ±0.5–80 counts (a0 said to 0.01 counts, in no other class, and the law confirmed on a − a0); `lie:a_zero`: the same under an open-loop header or none, a lead and a scaled Ga (as `lie:accel_fb`'s) of their own on the float command (a0 said to 0.01 counts, the law and Ga inferred on a − a0); `lie:column`: a closed-loop header that lies (as `lie:swap`'s) over one column fault — v in volts (on a lead's stored integer: a P's v in another unit is another kp as much), v about a DAC code's midpoint, θ from an earlier run's count, or u in degrees or radians — the lie contradicted, the law inferred on the column read back, and the fault said as in its own class; `honest:*`: true headers (P, or a lead on the stored integer, or "
        "`honest:lead_sent` a lead on the float logging the whole count it sends) the audit must confirm. `+coulomb_friction`: beside a hidden Coulomb friction of 3–30 DAC counts.",
        "",
        "Bar (issue 26): in at least 9 of 10 seeds, a lying header contradicted (and a true or absent one not), "
        "the controller reproducing every logged v to the device's quantization (1e-6 counts; the logged "
        "integer exactly) at the hidden alignment, and the hidden law named: the continuous design (num/den in s "
        "to 1e-9, Tustin) or the P gain (— where the header's law is confirmed and used as printed), and "
        "for `lie:accel_fb` and `lie:accel_rows` Ga too (its Tustin inverse's coefficients to 1e-3: DESIGN.md's "
        "are not round "
        "numbers, and a run pins Ga's slowest pole only so far). Where the log pins a first-order design only to a "
        "family and says so (the span of its zero and pole, `analysis.design_doubt`), the hidden design inside "
        "that span counts as named: no audit can name one design of a family that every member reproduces.",
        "",
        "| class | seeds | contradiction right | reproduced | design / gain named | or in the span said | all "
        "| median s |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for case, group in by_case.items():
        judged = [o for o in group if o.design_ok is not None]
        design = f"{sum(o.design_ok for o in judged)} of {len(judged)}" if judged else "—"
        spanned = f"{sum(o.design_ok or o.spanned for o in judged)} of {len(judged)}" if judged else "—"
        secs = sorted(o.seconds for o in group)[len(group) // 2]
        lines.append(f"| {case} | {len(group)} | {sum(o.contradiction_ok for o in group)} | "
                     f"{sum(o.reproduced for o in group)} | {design} | {spanned} | {sum(o.ok for o in group)} | "
                     f"{secs:.1f} |")
    misses = [o for o in outcomes if not o.ok]
    spans = [o for o in outcomes if o.spanned]
    lines += ["", f"Misses: {len(misses)} of {len(outcomes)}."
              + (f" The hidden design inside the span said beside another named: {len(spans)}." if spans else "")]
    if misses:
        lines += ["", "| case | seed | hidden | found | controller_source |", "|---|---|---|---|---|"]
        lines += [f"| {o.case} | {o.seed} | {o.hidden} | {o.found} | {o.source} |" for o in misses]
    if spans:  # counted in "all": another design named, and the family said holds the hidden one
        lines += ["", "Named another design, the hidden inside the span said beside it:", "",
                  "| case | seed | hidden | found |", "|---|---|---|---|"]
        lines += [f"| {o.case} | {o.seed} | {o.hidden} | {o.found} |" for o in spans]
    lines.append(END)
    return "\n".join(lines) + "\n"


def write_section(path: Path, section: str) -> None:
    """Replace the section between the markers in ``path`` (append it when absent)."""
    text = path.read_text() if path.exists() else ""
    if BEGIN in text and END in text:
        head, rest = text.split(BEGIN, 1)
        tail = rest.split(END, 1)[1].lstrip("\n")
        text = head + section + ("\n" + tail if tail else "")
    else:
        text = text.rstrip("\n") + ("\n\n" if text else "") + section
    path.write_text(text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=number(1, 1000, integer=True), default=10, help="seeds per class (default 10)")
    parser.add_argument("--classes", nargs="+", default=list(KNOWN), metavar="NAME",
                        help=f"cases to run (default all: {', '.join(KNOWN)})")
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "diagnosis_validation.md",
                        help="Markdown file whose audit section is replaced (default docs/diagnosis_validation.md)")
    parser.add_argument("--jobs", type=number(1, 64, integer=True), default=1, help="cases in parallel (default 1)")
    args = parser.parse_args(argv)
    for name in args.classes:
        if name not in KNOWN:
            parser.error(f"--classes: unknown '{name}' (known: {', '.join(KNOWN)})")
    jobs = [(case, seed) for case in args.classes for seed in range(args.seeds)]
    t0 = time.perf_counter()
    outcomes: list[Outcome] = []

    def report(o: Outcome) -> None:
        outcomes.append(o)
        print(f"[{len(outcomes)}/{len(jobs)}] {o.case} seed {o.seed}: hidden {o.hidden}; found {o.found} "
              f"({o.source}) {'ok' if o.ok else 'MISS'} {o.seconds:.1f} s", file=sys.stderr, flush=True)

    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as pool:
            for o in pool.map(run_case, *zip(*jobs)):
                report(o)
    else:
        for case, seed in jobs:
            report(run_case(case, seed))
    text = table(outcomes, f"--seeds {args.seeds}", time.perf_counter() - t0)
    print(text)
    write_section(args.out, text)
    print(f"written {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
